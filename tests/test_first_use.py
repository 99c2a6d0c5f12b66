"""First use of the compiled engine: the notice, the cache folder, uninstall.

References: numba's own cache counters (``dispatcher.stats``: a cache miss
is a compilation, a hit a load) for when the notice must and must not be
printed; numba's documented rule for the folder under ``NUMBA_CACHE_DIR``
(``<parent folder>_<sha1 of the source folder>``) and the XDG rule for the
user cache, written out here; the files on disk; and ``pip`` itself, which
installs the built wheel into a fresh environment and uninstalls it, after
which ``import fws_control`` must fail.
"""

from __future__ import annotations

import base64
import contextlib
import hashlib
import json
import os
import site
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

import pytest

from fws_control.simulation import compilation, compiled

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "fws_control"

numba = pytest.importorskip("numba", reason="the extra 'fast' (numba)")


def _env(**updates: str) -> dict:
    """This checkout first on the path, none of the cache settings inherited."""
    drop = ("NUMBA_CACHE_DIR", "XDG_CACHE_HOME", compilation.QUIET_VARIABLE)
    env = {k: v for k, v in os.environ.items() if k not in drop}
    env["PYTHONPATH"] = str(ROOT)
    env.update(updates)
    return env


def _python(code: str, env: dict, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        env=env, cwd=cwd, capture_output=True, text=True, timeout=900, check=False,
    )  # fmt: skip


def _subfolder(source_dir: Path) -> str:
    # numba's get_suitable_cache_subpath, written out from its definition
    digest = hashlib.sha1(str(source_dir).encode()).hexdigest()
    return f"{source_dir.name}_{digest}"


# A kernel of the package compiled inside a first_use block (the notice is
# only for fws_control's kernels: a user's own numba function compiled first
# must not trigger it), and numba's cache counters printed.
_SMALL = """
import math, numba
numba.njit(lambda x: x + 1.0)(1.0)            # a user's function: no notice
from fws_control.simulation import compiled_loop
from fws_control.simulation.compilation import first_use
with first_use(lambda: 3.0):
    assert compiled_loop.wrap_lap(7.5, 2.0) == 7.5 % 2.0
stats = compiled_loop.wrap_lap.stats
print(sum(stats.cache_hits.values()), sum(stats.cache_misses.values()))
from fws_control.simulation.compilation import cache_dir
print(cache_dir())
"""


def _package_cache_files() -> set[Path]:
    # (a working tree may hold cache files numba wrote there by default)
    return {p for p in PACKAGE.rglob("*") if p.suffix in (".nbi", ".nbc")}


def test_notice_on_a_compilation_only_and_once(tmp_path):
    # The runs here also check two of the cache folder's rules (numba's under
    # NUMBA_CACHE_DIR, XDG's under XDG_CACHE_HOME), as
    # test_cache_folder_outside_the_package does for HOME: each run compiles
    # in a new interpreter, and its start costs about 3 s of CPU.
    before = _package_cache_files()
    cache = tmp_path / "cache"
    folder = cache / _subfolder(PACKAGE / "simulation")
    cold = _python(_SMALL, _env(NUMBA_CACHE_DIR=str(cache)), tmp_path)
    assert cold.returncode == 0, cold.stderr[-2000:]
    counts, printed_dir = cold.stdout.splitlines()[-2:]
    assert counts.split() == ["0", "1"]  # numba: one compilation, no load
    assert printed_dir == str(folder)  # numba's rule
    lines = cold.stderr.splitlines()
    assert len(lines) == 2, cold.stderr
    assert lines[0].startswith("fws_control: compiling the simulation engine")
    assert "about 3 s of CPU" in lines[0]
    assert f"cached in {folder}" in lines[0]
    assert "FWS_CONTROL_QUIET=1" in lines[0]
    seconds = float(lines[1].split("compiled in ")[1].split(" s of CPU")[0])
    assert 0.0 < seconds < 60.0
    assert list(folder.glob("compiled_loop.wrap_lap-*.nbi"))

    # a second process loads the kernel: numba counts a hit, nothing printed
    warm = _python(_SMALL, _env(NUMBA_CACHE_DIR=str(cache)), tmp_path)
    assert warm.returncode == 0, warm.stderr[-2000:]
    assert warm.stdout.splitlines()[-2].split() == ["1", "0"]
    assert warm.stderr == ""

    # quiet: compiled (a miss) and cached, nothing printed; in the user
    # cache under XDG_CACHE_HOME (XDG's rule; the XDG folders are Linux's,
    # elsewhere under NUMBA_CACHE_DIR)
    home = tmp_path / "home"
    home.mkdir()
    if sys.platform == "linux":
        where = {"HOME": str(home), "XDG_CACHE_HOME": str(tmp_path / "xdg")}
        other = tmp_path / "xdg" / "fws_control" / folder.name
    else:
        where = {"HOME": str(home), "NUMBA_CACHE_DIR": str(tmp_path / "quiet")}
        other = tmp_path / "quiet" / folder.name
    quiet = _python(_SMALL, _env(FWS_CONTROL_QUIET="1", **where), tmp_path)
    assert quiet.returncode == 0, quiet.stderr[-2000:]
    counts, printed_dir = quiet.stdout.splitlines()[-2:]
    assert counts.split() == ["0", "1"]
    assert printed_dir == str(other)
    assert quiet.stderr == ""
    assert list(other.glob("compiled_loop.wrap_lap-*.nbi"))
    # numba wrote nothing into the package (its default: __pycache__ there)
    assert not _package_cache_files() - before


def test_cache_folder_outside_the_package(tmp_path):
    # (the NUMBA_CACHE_DIR and XDG_CACHE_HOME rules: the runs of
    # test_notice_on_a_compilation_only_and_once)
    if sys.platform != "linux":
        print("the XDG folders are Linux's: NUMBA_CACHE_DIR checked above only")
        return
    home = tmp_path / "home"
    home.mkdir()
    code = """
    from fws_control.simulation import compiled_loop
    from fws_control.simulation.compilation import cache_dir
    compiled_loop.wrap_lap(0.5, 2.0)
    print(cache_dir())
    """
    # XDG's rule without XDG_CACHE_HOME: ~/.cache
    expected = home / ".cache" / "fws_control" / _subfolder(PACKAGE / "simulation")
    before = _package_cache_files()
    run = _python(code, _env(HOME=str(home)), tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.strip() == str(expected)
    assert list(expected.glob("compiled_loop.wrap_lap-*.nbi")), expected
    # numba wrote nothing into the package (its default: __pycache__ there)
    assert not _package_cache_files() - before


def test_compile_seconds_counts_what_is_still_to_compile(tmp_path, monkeypatch):
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))

    def cube(x):
        return x * x * x

    first = compilation.jit(cube)
    assert compilation.compile_seconds(first, 5.0) == 5.0
    assert not list(tmp_path.rglob("*.nbi"))
    assert first(2.0) == 8.0
    assert compilation.compile_seconds(first, 5.0) == 0.0  # compiled here
    assert len(list(tmp_path.rglob("*.nbi"))) == 1
    again = compilation.jit(cube)  # as in a new process: on disk only
    assert not again.overloads
    assert compilation.compile_seconds(again, 5.0) == 0.0
    assert compilation.is_compiled(again) and not compilation.is_compiled(cube)
    # an index of another source (an edit of any kernel source changes the
    # stamp): numba would compile, and so it counts
    stamp = compilation._kernel_sources_stamp()
    monkeypatch.setattr(compilation, "_kernel_sources_stamp", lambda: (*stamp, "x"))
    edited = compilation.jit(cube)
    assert compilation.compile_seconds(edited, 5.0) == 5.0
    assert not compilation.is_compiled(edited)
    assert edited(2.0) == 8.0  # compiled again, into the same index
    assert compilation.is_compiled(compilation.jit(cube))


def test_the_estimate_is_of_the_kernels_the_call_uses(monkeypatch):
    # a call with a feature (here announced before any kernel is chosen, as
    # _run_compiled does: a compilation may start before that) is estimated
    # with the kernels of every feature, which take longer to compile
    plans = []
    monkeypatch.setattr(compiled, "first_use", lambda est: plans.append(est) or
                        contextlib.nullcontext())  # fmt: skip
    # as if nothing were cached: each stage costs its full estimate
    monkeypatch.setattr(compiled, "compile_seconds", lambda kernel, sec: sec)
    stages = ("DOP853", "signals", "peaks")
    with compiled.compiling(*stages, features=True):
        full = plans[-1]()
    with compiled.compiling(*stages, features=False):
        paper = plans[-1]()
    assert full > paper > 0.0
    with compiled.compiling(*stages):  # default: as the thread's last call
        assert plans[-1]() == paper


def test_compiling_names_its_stages():
    with pytest.raises(ValueError, match=r"stages must be in .*'BDF'"):
        compiled.compiling("DOP853", "BDF")
    with pytest.raises(ValueError, match="inline must be 'never' or 'always'"):
        compilation.jit(lambda x: x, inline="sometimes")


# --------------------------------------------------------------------------
# pip install, one compiled simulate, pip uninstall

# A DOP853 integration alone first, then one default simulate: the first
# must touch neither Radau's driver nor the signals or the peaks. numba's
# counters per kernel (a cache hit is a load, a miss a compilation) name
# what each call needed, whether the cache was cold or warm.
_STAGES = """
import json
import numpy as np
import fws_control as fws
from fws_control.simulation import compiled, compiled_drivers, compiled_variants

# the two methods' drivers (a kernel they call is compiled with them, or
# loaded inside them from the cache), the signals and the peaks: those of
# a call without a delay, the dynamic model, a controller's law or a
# varying speed, and those of a call with all of them
plain = compiled_variants.kernels([])
full = compiled_variants.kernels(compiled_variants.FEATURES)
KERNELS = {}
for name in ("solve_batch", "solve_batch_radau", "signals_batch", "peaks_batch"):
    KERNELS[name] = getattr(plain, name)
    KERNELS["full " + name] = getattr(full, name)
KERNELS["run_impl"] = plain.solve_batch.py_func.__globals__["_run_impl"]
KERNELS["full run_impl"] = compiled_drivers._run_impl

def touched():
    names = [n for n, k in KERNELS.items()
             if sum(k.stats.cache_hits.values())
             + sum(k.stats.cache_misses.values())
             + len(k.signatures)]
    return names

veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
g = fws.double_root_gains(veh, speed=5.0, curvature=0.1, ratio=-1.0, pole=-1.0)
compiled.integrate_compiled(
    veh, fws.Arc(curvature=0.1), g, speed=np.array([5.0]), feedforward=True,
    path_state=np.array([[0.0, -5.0, 0.0]]), t_eval=np.linspace(0.0, 1.0, 3),
    time_constant=None)
alone = touched()
res = fws.simulate(fws.LateralPlant(veh, speed=5.0), fws.Arc(curvature=0.1), g,
                   initial_state=(0.0, -5.0, 0.0), duration=15.0)
print(json.dumps({"status": str(res.status), "alone": alone, "all": touched()}))
"""

# In the fresh environment: one of the engine's kernels in a first-use
# block, and where its cache went.
_INSTALLED = """
import json
import fws_control as fws
from fws_control.simulation import compiled_loop
from fws_control.simulation.compilation import cache_dir, first_use
with first_use(lambda: 1.0):
    assert compiled_loop.wrap_lap(7.5, 2.0) == 7.5 % 2.0
print(json.dumps({"file": fws.__file__, "cache": cache_dir()}))
"""


def test_a_dop853_integration_needs_none_of_the_other_stages(tmp_path):
    # this checkout's own cache (warm after the first compiled test): loads
    # and compilations are counted alike
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    run = _python(_STAGES, env, tmp_path)
    assert run.returncode == 0, run.stderr[-3000:]
    out = json.loads(run.stdout.strip().splitlines()[-1])
    assert out["status"] == "ok"
    # the paper's loop: its specialised kernels only, never the full ones
    assert out["alone"] == ["solve_batch"]
    assert out["all"] == ["solve_batch", "signals_batch", "peaks_batch"]


def _wheel(folder: Path) -> Path:
    """A wheel of this checkout's package, as setuptools builds it (offline).

    The package's files (``*.py`` and ``py.typed``, no ``__pycache__``) and
    the dist-info pip needs: METADATA, WHEEL and RECORD (each file's SHA-256
    and size, as the wheel format specifies). Built here rather than with
    ``pip wheel``: that needs the build backend of pyproject.toml
    (setuptools >= 77) in the environment or from the network.
    """
    version = "0.0.0.dev0"
    info = f"fws_control-{version}.dist-info"
    files = {
        p.relative_to(ROOT).as_posix(): p.read_bytes()
        for p in sorted(PACKAGE.rglob("*"))
        if p.is_file()
        and "__pycache__" not in p.parts
        and (p.suffix == ".py" or p.name == "py.typed")
    }
    files[f"{info}/METADATA"] = (
        f"Metadata-Version: 2.1\nName: fws-control\nVersion: {version}\n"
    ).encode()
    files[f"{info}/WHEEL"] = (
        b"Wheel-Version: 1.0\nGenerator: tests\nRoot-Is-Purelib: true\n"
        b"Tag: py3-none-any\n"
    )
    record = []
    for name, data in files.items():
        digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest())
        record.append(f"{name},sha256={digest.rstrip(b'=').decode()},{len(data)}")
    record.append(f"{info}/RECORD,,")
    files[f"{info}/RECORD"] = ("\n".join(record) + "\n").encode()
    path = folder / f"fws_control-{version}-py3-none-any.whl"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as whl:
        for name, data in files.items():
            whl.writestr(name, data)
    return path


def test_pip_uninstall_leaves_no_package_that_imports(tmp_path):
    """Install the wheel into a fresh environment, compile, uninstall."""
    wheel = _wheel(tmp_path)
    venv = tmp_path / "venv"
    subprocess.run(
        [sys.executable, "-m", "venv", "--without-pip", str(venv)],
        check=True, timeout=300,
    )  # fmt: skip
    python = venv / "bin" / "python"
    purelib = "import sysconfig; print(sysconfig.get_paths()['purelib'])"
    sp = Path(
        subprocess.run(
            [str(python), "-c", purelib], capture_output=True, text=True,
            check=True, timeout=60,
        ).stdout.strip()
    )  # fmt: skip
    # the dependencies (and pip) from this interpreter's site-packages, as
    # plain path entries: the .pth files there (this checkout's editable
    # install among them) are not run in the new environment
    (sp / "_dependencies.pth").write_text("\n".join(site.getsitepackages()) + "\n")
    home = tmp_path / "home"
    home.mkdir()
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("PYTHONPATH", "NUMBA_CACHE_DIR", "XDG_CACHE_HOME")
    }
    env.update(HOME=str(home), PYTHONNOUSERSITE="1")

    def run(*args):
        return subprocess.run(
            [str(python), *args], env=env, cwd=tmp_path, capture_output=True,
            text=True, timeout=900, check=False,
        )  # fmt: skip

    before = run("-c", "import fws_control")
    assert before.returncode != 0, "fws_control imports before the install"
    # --ignore-installed: this checkout's own install, seen through the
    # dependencies' folder, is neither counted nor touched
    install = run("-m", "pip", "install", "--no-deps", "--no-index",
                  "--ignore-installed", "-q", str(wheel))  # fmt: skip
    assert install.returncode == 0, install.stderr[-2000:]
    simulated = run("-c", _INSTALLED)
    assert simulated.returncode == 0, simulated.stderr[-3000:]
    out = json.loads(simulated.stdout.strip().splitlines()[-1])
    assert Path(out["file"]).is_relative_to(sp)
    # the notice, once
    assert simulated.stderr.count("compiling the simulation engine") == 1
    # the kernel went to the user cache, none into the installed package
    cache = Path(out["cache"])
    assert cache.is_relative_to(home / ".cache" / "fws_control")
    assert list(cache.glob("*.nbi")) and list(cache.glob("*.nbc"))
    assert not [p for p in (sp / "fws_control").rglob("*.nb[ic]")]

    uninstall = run("-m", "pip", "uninstall", "-y", "-q", "fws-control")
    assert uninstall.returncode == 0, uninstall.stderr[-2000:]
    assert not (sp / "fws_control").exists(), sorted(
        str(p) for p in (sp / "fws_control").rglob("*")
    )
    after = run("-c", "import fws_control")
    assert after.returncode != 0
    assert "ModuleNotFoundError: No module named 'fws_control'" in after.stderr


def test_a_kernel_is_stamped_with_the_equations_it_inlines():
    # numba keys a cache entry to its own file's stamp; the kernels inline
    # fws_control.equations, so its stamp must be part of theirs
    if compilation.numba is None:
        print("numba is not installed: no cache")
        return
    locator = compilation._KernelLocator(compilation.jit, compilation.__file__)
    stamp = dict(
        (name, (mtime, size)) for name, mtime, size in locator.get_source_stamp()
    )
    kernels = sorted((PACKAGE / "simulation").glob("compiled*.py"))
    assert len(kernels) >= 10  # the engine's modules, the variants too
    for path in (PACKAGE / "equations.py", *kernels):
        st = path.stat()
        assert stamp[path.name] == (st.st_mtime, st.st_size)
