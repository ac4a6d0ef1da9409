"""Cheaper report figures that show the same thing: long traces decimated to the pixel grid.

A report figure is read at the resolution it is printed at. A time or speed trace of 10⁵
samples drawn into an axes about 1000 pixels wide costs the renderer (and an inline SVG's
size) per sample, yet the reader sees per pixel column only the vertical span the trace
covers there. :func:`envelope_indices` keeps, per pixel column, the first and last sample and
the samples holding the column's minimum and maximum (and the first gap, NaN, so breaks in a
trace stay breaks) — the *M4* rule of Jugel et al. (2014), "M4: a visualization-oriented time
series data aggregation", Proc. VLDB Endowment 7(10), §3. In every column the drawn vertices
therefore span exactly the data's minimum and maximum (every peak survives, at its own sample,
so within a pixel of where it was), and the segment joining two columns joins two neighbouring
samples, so it is the original segment. What changes is inside a column: the drawn segments
there may lean into the neighbouring pixel column (the columns are not aligned with the final
pixels), so every column's inked span matches the full trace's within one pixel column
(tests/analysis/test_report_figures.py renders both and compares).

:func:`decimate_figure` applies this to every eligible line of a matplotlib figure in place
(:meth:`analysis.report.Report.add_figure` does so before rendering): a plain line (no markers,
default draw style) in data coordinates, long enough to gain. A line whose x is monotonic (a
time or speed axis) gets the min/max envelope; any other line (a p-V loop, amplitude against a
noisy measured speed) keeps the first and last sample of each run of samples inside one pixel
cell (:func:`pixel_run_indices`), which stays within a pixel of the data. Lines with markers
and step lines are drawn as they are.
"""

from __future__ import annotations

import logging

import numpy as np

from crankbench.predict._validate import check_int
from crankbench.predict.errors import ConfigError

__all__ = ["envelope_indices", "pixel_run_indices", "decimate_figure"]

log = logging.getLogger("crankbench")


def _samples(x, y, caller: str):
    """x and y as float arrays, checked to be 1-D of one length."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.ndim != 1 or x.shape != y.shape:
        raise ConfigError(f"{caller}: x and y must be 1-D of one length, got shapes "
                          f"{x.shape} and {y.shape}")
    return x, y


def _first_per_segment(candidates: np.ndarray, segment: np.ndarray) -> np.ndarray:
    """Index of the first True of ``candidates`` in each segment that has one."""
    idx = np.flatnonzero(candidates)
    if not idx.size:
        return idx
    _, first = np.unique(segment[idx], return_index=True)
    return idx[first]


def envelope_indices(x, y, *, n_columns: int, x_range=None) -> np.ndarray:
    """Indices of the samples that draw a trace exactly at a pixel grid (min/max envelope).

    The x range is cut into ``n_columns`` equal columns (plus one column each side for samples
    outside it); per column the first and last sample, the samples of the minimum and the
    maximum of ``y`` and the first NaN are kept (M4 rule, module docstring).

    Parameters
    ----------
    x : array_like, shape (n,)
        Monotonic (non-decreasing or non-increasing) finite abscissae, in the axis' scaled
        coordinates (e.g. log10 of x on a log axis).
    y : array_like, shape (n,)
        Ordinates; NaN marks a gap.
    n_columns : int
        Pixel columns across ``x_range`` (>= 1).
    x_range : (float, float), optional
        The x span the columns cover (default: the data's).

    Returns
    -------
    numpy.ndarray of int
        Sorted unique indices into ``x``/``y``: at most 5 per column.

    Examples
    --------
    A 0.1-s-wide spike in a 10 000-sample trace drawn at 100 columns survives at its own
    sample and value; 10 000 samples become at most 5 per column:

    >>> import numpy as np
    >>> t = np.linspace(0.0, 10.0, 10_001)
    >>> y = np.sin(t)
    >>> y[4321] = 7.5
    >>> keep = envelope_indices(t, y, n_columns=100)
    >>> print(keep.size <= 500, 4321 in keep, float(y[keep].max()))
    True True 7.5
    """
    x, y = _samples(x, y, "envelope_indices")
    n_columns = check_int(n_columns, "n_columns", minimum=1, error=ConfigError)
    n = x.size
    if n <= 2:
        return np.arange(n)
    if not np.isfinite(x).all():
        raise ConfigError("envelope_indices: x must be finite (NaN marks gaps in y, not x)")
    step = np.diff(x)
    if not ((step >= 0).all() or (step <= 0).all()):
        raise ConfigError("envelope_indices: x must be monotonic (a time or speed axis)")
    lo, hi = (min(x[0], x[-1]), max(x[0], x[-1])) if x_range is None else sorted(
        map(float, x_range))
    if not hi > lo:
        return np.array([0, n - 1]) if n > 1 else np.arange(n)
    # column -1 and n_columns gather the samples left and right of the range
    column = np.clip(np.floor((x - lo) * (n_columns / (hi - lo))), -1, n_columns).astype(np.int64)
    starts = np.flatnonzero(np.diff(column)) + 1
    starts = np.concatenate(([0], starts))
    ends = np.concatenate((starts[1:] - 1, [n - 1]))
    segment = np.repeat(np.arange(starts.size), np.diff(np.concatenate((starts, [n]))))
    gap = np.isnan(y)
    low = np.minimum.reduceat(np.where(gap, np.inf, y), starts)
    high = np.maximum.reduceat(np.where(gap, -np.inf, y), starts)
    keep = np.concatenate((starts, ends,
                           _first_per_segment(y == low[segment], segment),
                           _first_per_segment(y == high[segment], segment),
                           _first_per_segment(gap, segment)))
    return np.unique(keep)


def pixel_run_indices(x, y, *, n_columns: int, n_rows: int, x_range, y_range) -> np.ndarray:
    """Indices that draw a curve of any shape (a loop, a noisy speed axis) within a pixel.

    The plane is cut into ``n_columns`` × ``n_rows`` cells; of every run of consecutive
    samples in one cell only the first and the last are kept (and NaN gaps stay gaps). A
    dropped sample lies in the cell of the kept samples around it, so the drawn curve stays
    within one cell of the data, and an extreme sample is kept because the curve enters or
    leaves a cell there.

    Parameters
    ----------
    x, y : array_like, shape (n,)
        Samples in the axes' scaled coordinates; NaN marks a gap.
    n_columns, n_rows : int
        Cells across ``x_range`` and ``y_range`` (>= 1).
    x_range, y_range : (float, float)
        The spans the cells cover (samples outside fall in one cell row/column beyond).

    Returns
    -------
    numpy.ndarray of int
        Sorted indices into ``x``/``y``.

    Examples
    --------
    A circle of 100 000 samples in a 200 × 200 cell grid keeps about 2 samples per cell it
    crosses:

    >>> import numpy as np
    >>> phi = np.linspace(0.0, 2 * np.pi, 100_000)
    >>> keep = pixel_run_indices(np.cos(phi), np.sin(phi), n_columns=200, n_rows=200,
    ...                          x_range=(-1.1, 1.1), y_range=(-1.1, 1.1))
    >>> print(keep.size < 2000, keep[0], keep[-1])
    True 0 99999
    """
    x, y = _samples(x, y, "pixel_run_indices")
    n_columns = check_int(n_columns, "n_columns", minimum=1, error=ConfigError)
    n_rows = check_int(n_rows, "n_rows", minimum=1, error=ConfigError)
    n = x.size
    if n <= 2:
        return np.arange(n)

    def cells(v, span, count):
        lo, hi = sorted(map(float, span))
        if not hi > lo:
            return np.zeros(v.size, np.int64)
        c = np.floor((np.nan_to_num(v, nan=lo) - lo) * (count / (hi - lo)))
        return np.clip(c, -1, count).astype(np.int64) + 1

    cell = cells(x, x_range, n_columns) * (n_rows + 2) + cells(y, y_range, n_rows)
    cell[np.isnan(x) | np.isnan(y)] = -1  # a gap is a cell of its own
    change = np.flatnonzero(np.diff(cell)) + 1
    return np.unique(np.concatenate(([0, n - 1], change, change - 1)))


def _plain(value) -> bool:
    return value is None or (isinstance(value, str) and value in ("None", "none", "", " "))


def _width_bound(ax) -> float:
    """Largest fraction of its figure's width ``ax`` can take whatever the layout does: its
    grid cells' share (a colorbar or free axes: the whole figure)."""
    get_spec = getattr(ax, "get_subplotspec", None)
    spec = get_spec() if get_spec is not None else None
    if spec is None:
        return 1.0
    grid = spec.get_gridspec()
    ratios = np.asarray(grid.get_width_ratios() or np.ones(grid.ncols), float)
    return float(ratios[list(spec.colspan)].sum() / ratios.sum())


def decimate_figure(fig, *, dpi: float, min_points: int = 2000) -> tuple[int, int]:
    """Decimate every eligible line of ``fig`` in place to the pixel grid of its output.

    A line is eligible when it has at least ``min_points`` samples, no markers, the default
    draw style and data coordinates. With finite monotonic x (in its axis' scale) it is
    replaced by the samples of :func:`envelope_indices`, otherwise by those of
    :func:`pixel_run_indices`, at one column per output pixel of the width the axes' grid
    cells span in the figure (one row per pixel of the figure's height): an axes never grows
    beyond its cells, so a cell is never wider than a pixel whatever the layout does later. Call it when the axes limits are final (just before
    saving). A line that would keep more than 80 % of its samples is left as it is.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    dpi : float
        Output resolution, dots per inch (for SVG: the resolution the page is read at).
    min_points : int
        Shorter lines are left alone.

    Returns
    -------
    (int, int)
        Points of the eligible lines before and after.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import matplotlib.pyplot as plt
    >>> import numpy as np
    >>> fig, ax = plt.subplots(figsize=(5.0, 3.0))
    >>> t = np.linspace(0.0, 40.0, 400_001)
    >>> _ = ax.plot(t, np.sin(2 * np.pi * 3 * t))
    >>> before, after = decimate_figure(fig, dpi=100)
    >>> print(before, after <= 4 * 500 + 10)
    400001 True
    >>> plt.close(fig)
    """
    if dpi <= 0:
        raise ConfigError(f"decimate_figure: dpi={dpi!r} must be positive")
    width_px = fig.get_figwidth() * float(dpi)
    n_rows = max(1, int(np.ceil(fig.get_figheight() * float(dpi))))
    before = after = 0
    for ax in fig.axes:
        n_columns = max(1, int(np.ceil(width_px * _width_bound(ax))))
        lines = [ln for ln in ax.get_lines() if len(ln.get_xdata(orig=False)) >= min_points]
        if not lines:
            continue
        scale = ax.xaxis.get_transform()
        limits = scale.transform(np.asarray(ax.get_xlim(), float))  # autoscale now, then fix
        if not np.isfinite(limits).all():
            continue
        for line in lines:
            if not (_plain(line.get_marker()) and line.get_drawstyle() in (None, "default")
                    and line.get_transform() == ax.transData and line.get_markevery() is None):
                continue
            try:
                xs = np.asarray(line.get_xdata(orig=False), dtype=float)
                ys = np.asarray(line.get_ydata(orig=False), dtype=float)
            except (TypeError, ValueError):
                continue
            if xs.shape != ys.shape or xs.ndim != 1:
                continue
            sx = scale.transform(xs)
            step = np.diff(sx)
            if np.isfinite(sx).all() and ((step >= 0).all() or (step <= 0).all()):
                keep = envelope_indices(sx, ys, n_columns=n_columns, x_range=limits)
            else:
                y_scale = ax.yaxis.get_transform()
                keep = pixel_run_indices(
                    sx, y_scale.transform(ys), n_columns=n_columns, n_rows=n_rows,
                    x_range=limits, y_range=y_scale.transform(np.asarray(ax.get_ylim(), float)))
            if keep.size < 0.8 * xs.size:
                line.set_data(xs[keep], ys[keep])
                before += xs.size
                after += keep.size
    if before:
        log.debug("figure lines decimated to the pixel grid: %d -> %d points", before, after)
    return before, after
