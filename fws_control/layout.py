"""Fixed figure layouts: margins and gaps in inches for a grid of axes.

The library's figures have fixed sizes and known content, so their layout
can be given once in inches instead of being computed on every save.
Matplotlib's constrained layout measures every tick label, title and legend
before each draw (and ``savefig`` draws once more without rendering to run
it): in ``fws-control reproduce`` that was about a third of the CPU time.
:func:`grid_margins` turns margins and gaps in inches into the fractions
that :class:`matplotlib.gridspec.GridSpec` takes, so that ``plt.subplots(...,
gridspec_kw=grid_margins(...))`` lays a figure out without a layout engine.
``tests/test_figures.py`` draws every figure of ``reproduce`` and checks
that no label, tick label, title or legend overlaps another panel or leaves
the canvas.

This module imports nothing from matplotlib: it is arithmetic only.
"""

from __future__ import annotations

from .validation import check_scalar

__all__ = ["grid_margins"]


def grid_margins(
    figsize: tuple[float, float],
    *,
    nrows: int = 1,
    ncols: int = 1,
    left: float = 0.7,
    right: float = 0.15,
    bottom: float = 0.5,
    top: float = 0.7,
    wgap: float = 0.75,
    hgap: float = 0.75,
) -> dict[str, float]:
    """GridSpec fractions for margins and gaps given in inches.

    Parameters
    ----------
    figsize : (float, float)
        Figure width and height [in].
    nrows, ncols : int, optional
        Rows and columns of the grid.
    left, right, bottom, top : float, optional
        Space between the figure's edge and the outer axes [in]: room for
        tick labels and axis labels (left, bottom), titles and a suptitle
        (top).
    wgap, hgap : float, optional
        Space between neighbouring axes [in], horizontally and vertically.

    Returns
    -------
    dict
        ``left``, ``right``, ``bottom``, ``top`` (figure fractions) and
        ``wspace``, ``hspace`` (fractions of the mean axes width and height),
        as :class:`matplotlib.gridspec.GridSpec` takes them.

    Raises
    ------
    ValueError
        If a size is negative or not finite, or the margins and gaps leave
        no room for the axes.

    Examples
    --------
    >>> from fws_control.layout import grid_margins
    >>> kw = grid_margins((10.0, 5.0), ncols=2, left=1.0, right=0.5, wgap=0.5)
    >>> [round(kw[k], 4) for k in ("left", "right", "wspace")]  # axes 4 in wide
    [0.1, 0.95, 0.125]
    """
    try:
        width, height = (float(v) for v in figsize)
    except (TypeError, ValueError):
        raise ValueError(
            f"figsize must be (width, height) in inches, got {figsize!r}"
        ) from None
    for name, v in (("figsize[0]", width), ("figsize[1]", height)):
        check_scalar(name, v)
        if v <= 0.0:
            raise ValueError(f"{name} must be > 0 in, got {v!r}")
    for name, v in (("nrows", nrows), ("ncols", ncols)):
        if isinstance(v, bool) or not isinstance(v, int) or v < 1:
            raise ValueError(f"{name} must be an int >= 1, got {v!r}")
    sizes = {
        "left": left,
        "right": right,
        "bottom": bottom,
        "top": top,
        "wgap": wgap,
        "hgap": hgap,
    }
    for name, v in sizes.items():
        check_scalar(name, v)
        if v < 0.0:
            raise ValueError(f"{name} must be >= 0 in, got {v!r}")
    axes_w = (width - left - right - (ncols - 1) * wgap) / ncols
    axes_h = (height - bottom - top - (nrows - 1) * hgap) / nrows
    if axes_w <= 0.0 or axes_h <= 0.0:
        raise ValueError(
            f"margins and gaps leave no room for the axes in a {width:g} x "
            f"{height:g} in figure (axes {axes_w:.3g} x {axes_h:.3g} in): "
            "they must sum to less than the figure size"
        )
    return {
        "left": left / width,
        "right": 1.0 - right / width,
        "bottom": bottom / height,
        "top": 1.0 - top / height,
        "wspace": wgap / axes_w,
        "hspace": hgap / axes_h,
    }
