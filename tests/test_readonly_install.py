"""The compiled engine where numba cannot write its cache.

An account without a writable home (a service, a container, ``nobody``)
leaves the engine no cache folder: no ``~/.cache/fws_control`` and no
``NUMBA_CACHE_DIR`` (the package's own folder is never used, see
:mod:`fws_control.simulation.compilation`). numba's cache then raises
``RuntimeError: cannot cache function ...: no locator available``; the
engine must compile uncached instead, with one warning.

References: numba's own ``cache=False`` compile of the same function, and
Python's ``%`` for one of the engine's kernels compiled by an account that
cannot write the package nor its home (numba's real cache locators on a
read-only file system, not a patched list). The whole engine compiled that
way costs 30-60 s of CPU and runs the same code path; ``fws-control
reproduce`` itself is checked with a cache in ``tests/test_cli.py``.
"""

from __future__ import annotations

import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fws_control.simulation import compilation

ROOT = Path(__file__).resolve().parents[1]


def test_no_cache_folder_compiles_uncached_with_one_warning(monkeypatch):
    numba = pytest.importorskip("numba", reason="the extra 'fast' (numba)")

    # no writable cache folder: no locator of the engine's cache fits
    monkeypatch.setattr(compilation._KernelCacheImpl, "_locator_classes", [])
    monkeypatch.setattr(compilation, "_CACHING", True)

    def hypot3(x, y, z):
        return (x * x + y * y + z * z) ** 0.5

    with pytest.raises(RuntimeError, match="no locator available"):
        compilation._KernelCache(hypot3)
    with pytest.warns(RuntimeWarning, match="no writable cache folder") as seen:
        first = compilation.jit(hypot3)
        second = compilation.jit(lambda x: 2.0 * x)
    assert len(seen) == 1  # one warning, not one per kernel
    assert compilation.cache_dir() is None
    assert first(2.0, 3.0, 6.0) == 7.0 and second(1.5) == 3.0
    reference = numba.njit(cache=False)(hypot3)
    rng = np.random.default_rng(1)
    for x, y, z in rng.normal(size=(5, 3)):
        assert first(x, y, z) == reference(x, y, z) == np.sqrt(x * x + y * y + z * z)


def _unprivileged_command() -> tuple[list[str], str | None]:
    """A prefix that runs a command without the right to write others' files.

    As root: ``setpriv`` drops every capability (no CAP_DAC_OVERRIDE: the
    mode bits bind root as any account), so a folder without write bits is
    read-only. As another account the mode bits bind already.
    """
    if os.geteuid() != 0:
        return [], None
    setpriv = shutil.which("setpriv")
    if setpriv is None:
        return [], "setpriv (util-linux) is not installed: cannot drop root's rights"
    return [setpriv, "--inh-caps=-all", "--bounding-set=-all"], None


def _read_only(path: Path) -> None:
    for p in [path, *path.rglob("*")]:
        mode = p.stat().st_mode
        p.chmod(mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))


# Two of the engine's own kernels, compiled where no cache folder is
# writable: their values (against Python's %), the cache folder (none) and
# the signatures numba compiled printed.
_KERNELS = """
from fws_control.simulation import compilation, compiled_loop
wrap = compiled_loop.wrap_lap
print(wrap(7.5, 10.0) == 7.5 % 10.0, wrap(-2.5, 2.0) == -2.5 % 2.0)
print(compilation.cache_dir() or "none", len(compiled_loop.wrap_lap.signatures))
"""


def test_compiled_kernels_from_a_read_only_install_without_a_home(tmp_path):
    pytest.importorskip("numba", reason="the extra 'fast' (numba)")
    prefix, why = _unprivileged_command()
    if why:
        print(why)
        pytest.skip(why)
    site = tmp_path / "site"
    shutil.copytree(
        ROOT / "fws_control",
        site / "fws_control",
        ignore=shutil.ignore_patterns("__pycache__", "*.pyc"),
    )
    home = tmp_path / "home"
    home.mkdir()
    out = tmp_path / "figures"
    out.mkdir()
    _read_only(site)
    _read_only(home)
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("NUMBA_CACHE_DIR", "XDG_CACHE_HOME", "MPLCONFIGDIR", "PYTHONPATH")
    }
    env.update(HOME=str(home), PYTHONPATH=str(site), PYTHONDONTWRITEBYTECODE="1")
    # the folder really is read-only for the command's account
    probe = subprocess.run(
        [*prefix, sys.executable, "-c", f"open({str(site / 'probe')!r}, 'w')"],
        env=env, capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert probe.returncode != 0 and "Permission denied" in probe.stderr
    try:
        run = subprocess.run(
            [*prefix, sys.executable, "-c", _KERNELS],
            env=env, cwd=tmp_path, capture_output=True, text=True, timeout=600,
            check=False,
        )  # fmt: skip
    finally:
        for p in [site, *site.rglob("*"), home]:
            p.chmod(p.stat().st_mode | stat.S_IWUSR)  # so that tmp_path is removed
    assert run.returncode == 0, run.stderr[-2000:]
    # the kernel ran, compiled once, with no cache folder
    assert run.stdout.split() == ["True", "True", "none", "1"], run.stdout
    assert not list(site.rglob("*.nb[ic]")) and not list(home.rglob("*.nb[ic]"))
    assert run.stderr.count("no writable cache folder") == 1, run.stderr[-2000:]
