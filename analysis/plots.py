"""Figures of order-analysis results: order map, Campbell diagram, order tracks, mode shapes.

Each function takes a result of :mod:`analysis.orders` and an optional matplotlib ``ax``, draws
on it, and returns the figure; none calls ``show()``.
"""

from __future__ import annotations

import numpy as np

from crankbench.predict.errors import AnalysisError

__all__ = ["plot_order_map", "plot_campbell", "plot_order_tracks", "plot_mode_shapes"]


def _axes(ax, figsize=(7.0, 4.5)):
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=figsize, layout="constrained")
    return ax.figure, ax


def _db(values, floor_db=-80.0):
    values = np.asarray(values, dtype=float)
    top = np.nanmax(values) if np.isfinite(values).any() and np.nanmax(values) > 0 else 1.0
    with np.errstate(divide="ignore"):
        return np.maximum(20 * np.log10(np.maximum(values, 0) / top), floor_db)


def _speed_axis(da):
    if "rpm" in da.dims:
        return da["rpm"].values
    return da["rpm"].values


def plot_order_map(order_map, ax=None, *, db: bool = True, floor_db: float = -80.0):
    """Colour map of an order map: speed (rpm) against order.

    Parameters
    ----------
    order_map : xarray.DataArray
        From :func:`analysis.order_map` (dims (time|rpm, order), ``rpm`` coordinate).
    ax : matplotlib Axes, optional
    db : bool
        Colour in dB re the map's maximum (else linear, in the map's units).
    floor_db : float
        Lowest level shown, dB.

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> m = xr.DataArray(np.ones((3, 4)), dims=("time", "order"),
    ...                  coords={"rpm": ("time", [1000., 1100., 1200.]), "order": np.arange(4.)},
    ...                  attrs={"units": "m/s^2", "amplitude_convention": "peak"})
    >>> fig = plot_order_map(m)
    >>> fig.axes[0].get_xlabel()
    'order'
    """
    if "order" not in order_map.dims or "rpm" not in order_map.coords:
        raise AnalysisError("plot_order_map needs an order map with dim 'order' and an 'rpm' "
                            "coordinate (analysis.order_map)")
    fig, ax = _axes(ax)
    values = order_map.transpose(..., "order").values
    if order_map.attrs.get("scaling") == "power":
        values = np.sqrt(np.maximum(values, 0))
    speed = _speed_axis(order_map)
    shown = _db(values, floor_db) if db else values
    mesh = ax.pcolormesh(order_map["order"].values, speed, shown, shading="nearest",
                         cmap="viridis", rasterized=True)
    units = order_map.attrs.get("units", "")
    label = (f"dB re max" if db else f"{order_map.attrs.get('amplitude_convention', '')} "
             f"[{units}]")
    fig.colorbar(mesh, ax=ax, label=label)
    ax.set_xlabel("order")
    ax.set_ylabel("speed [rpm]")
    ax.set_title(str(order_map.name or "order map"))
    return fig


def plot_campbell(campbell=None, ax=None, *, orders=None, db: bool = True,
                  floor_db: float = -80.0, critical_frequencies_hz=(), speed_range_rpm=None,
                  frequency_max_hz=None, crossings=None):
    """Torsional Campbell diagram in the usual axes: speed (rpm) on x, frequency (Hz) on y.

    Order rays ``f = q · n / 60`` run from the origin, each labelled inside the axes at its
    end; the natural frequencies are horizontal lines, labelled inside the axes; measured
    crossings are markers. A measured short-time spectrum (:func:`analysis.campbell_map`) may
    lie underneath as a colour map.

    Parameters
    ----------
    campbell : xarray.DataArray, optional
        From :func:`analysis.campbell_map` (dims (time|rpm, frequency), ``rpm`` coordinate).
    ax : matplotlib Axes, optional
    orders : sequence of float, optional
        Order rays (default ``campbell.attrs['order_lines']``).
    db, floor_db
        As in :func:`plot_order_map`.
    critical_frequencies_hz : sequence of float or dict
        Natural frequencies, Hz (a dict ``{label: frequency}`` names them).
    speed_range_rpm : (float, float), optional
        x range (default: the map's speeds).
    frequency_max_hz : float, optional
        Top of the y axis (default: the map's highest frequency).
    crossings : pandas.DataFrame, optional
        Measured crossings with ``speed_rpm`` and ``frequency_hz`` columns.

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> c = xr.DataArray(np.ones((3, 5)), dims=("time", "frequency"),
    ...                  coords={"rpm": ("time", [1000., 1500., 2000.]),
    ...                          "frequency": np.arange(5.) * 25},
    ...                  attrs={"units": "m", "order_lines": [1, 2]})
    >>> ax = plot_campbell(c).axes[0]
    >>> len(ax.lines), ax.get_xlabel(), ax.get_ylabel()
    (2, 'engine speed (rpm)', 'frequency (Hz)')
    """
    if campbell is not None and ("frequency" not in campbell.dims or
                                 "rpm" not in campbell.coords):
        raise AnalysisError("plot_campbell needs a map with dim 'frequency' and an 'rpm' "
                            "coordinate (analysis.campbell_map)")
    fig, ax = _axes(ax, figsize=(7.5, 5.0))
    if campbell is not None:
        speed = _speed_axis(campbell)
        values = campbell.transpose(..., "frequency").values
        mesh = ax.pcolormesh(speed, campbell["frequency"].values,
                             (_db(values, floor_db) if db else values).T, shading="nearest",
                             cmap="Greys", rasterized=True,
                             alpha=0.55)
        fig.colorbar(mesh, ax=ax, label="measured spectrum, dB re max" if db else
                     f"[{campbell.attrs.get('units', '')}]", shrink=0.8)
        lo_default = (float(np.nanmin(speed)), float(np.nanmax(speed)))
        f_default = float(campbell["frequency"].values[-1])
        lines = campbell.attrs.get("order_lines", []) if orders is None else orders
    else:
        lo_default, f_default, lines = (0.0, 1.0), None, orders or ()
    x0, x1 = speed_range_rpm if speed_range_rpm is not None else lo_default
    nat = (dict(critical_frequencies_hz) if isinstance(critical_frequencies_hz, dict) else
           {f"{f:.1f} Hz": f for f in critical_frequencies_hz})
    f_top = frequency_max_hz or f_default or 1.2 * max(
        [max(nat.values(), default=1.0)] + [q * x1 / 60 for q in lines])
    xs = np.array([0.0, x1])
    for q in lines:
        ax.plot(xs, q * xs / 60.0, color="tab:blue", lw=0.8)
        # label inside the axes: at the ray's end, or where it leaves the top
        x_end = min(x1, 60.0 * f_top / q) if q > 0 else x1
        y_end = q * x_end / 60.0
        ax.text(x_end - 0.01 * (x1 - x0), y_end - 0.015 * f_top, f"{q:g}", color="tab:blue",
                fontsize=7, ha="right", va="top", clip_on=True)
    for label, f in nat.items():
        if f <= f_top:
            ax.axhline(f, color="tab:red", lw=0.9, ls="--")
            ax.text(x0 + 0.01 * (x1 - x0), f + 0.01 * f_top, label, color="tab:red",
                    fontsize=7, ha="left", va="bottom", clip_on=True)
    if crossings is not None and len(crossings):
        ax.plot(crossings["speed_rpm"], crossings["frequency_hz"], "o", mfc="none", mec="k",
                ms=6, mew=1.2, label="measured crossings", zorder=5)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, 0.93))
    ax.set_xlim(x0, x1)
    ax.set_ylim(0.0, f_top)
    ax.set_xlabel("engine speed (rpm)")
    ax.set_ylabel("frequency (Hz)")
    ax.set_title(str(getattr(campbell, "name", None) or "Campbell diagram"), fontsize=9)
    return fig


def plot_mode_shapes(system, ax=None, *, modes=(1, 2, 3, 4)):
    """Relative mode shapes along the shaft line, nodes in model order.

    Nodes outside the undamped eigen-problem (a viscous damper's seismic ring, which has no
    spring) hold no mode-shape value and are left out; every other node is drawn at its place
    in the model's node list (free end first, as the model is written).

    Parameters
    ----------
    system : TorsionalSystem
    ax : matplotlib Axes, optional
    modes : sequence of int
        Elastic mode numbers to draw.

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> from crankbench.predict.torsion import chain
    >>> fig = plot_mode_shapes(chain([1.0, 2.0, 1.0], [1e4, 1e4], names=["a", "b", "c"]))
    >>> [t.get_text() for t in fig.axes[0].get_xticklabels()]
    ['a', 'b', 'c']
    """
    m = system.mode_shapes()
    keep = np.flatnonzero(np.asarray(getattr(system, "eigen_nodes",
                                             np.ones(len(m.node_names), bool)), bool))
    rel = m.relative()[keep]
    names = [m.node_names[i] for i in keep]
    fig, ax = _axes(ax, figsize=(7.5, 4.2))
    for i, k in enumerate(m.mode_numbers):
        if k in modes:
            ax.plot(range(len(names)), rel[:, i], marker="o", ms=4,
                    label=f"mode {k}: {m.frequencies_hz[i]:.4g} Hz")
    ax.set_xticks(range(len(names)), names, rotation=55, ha="right", fontsize=7)
    ax.axhline(0, color="0.6", lw=0.8)
    ax.set_ylabel("relative amplitude")
    ax.set_xlabel("shaft line, nodes in model order")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    return fig


def plot_order_tracks(tracks, ax=None, *, against: str = "rpm", phase: bool = False):
    """Amplitude (and optionally phase) of each tracked order against speed or time.

    Parameters
    ----------
    tracks : xarray.Dataset
        From :func:`analysis.order_track`.
    ax : matplotlib Axes, optional
        Amplitude axes (a phase axes is added below when ``phase`` and ``ax`` is None).
    against : {'rpm', 'time'}
    phase : bool
        Also draw the phase (degrees).

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> ds = xr.Dataset({"amplitude": (("order", "time"), np.ones((2, 3)), {"units": "m"}),
    ...                  "phase": (("order", "time"), np.zeros((2, 3)))},
    ...                 coords={"order": [1., 2.], "time": [0., 1., 2.],
    ...                         "rpm": ("time", [1000., 1100., 1200.])},
    ...                 attrs={"amplitude_convention": "peak", "method": "cot"})
    >>> len(plot_order_tracks(ds).axes[0].lines)
    2
    """
    import matplotlib.pyplot as plt

    if against not in ("rpm", "time"):
        raise AnalysisError(f"against={against!r} is not one of 'rpm', 'time'")
    if ax is None:
        if phase:
            fig, (ax, ax_p) = plt.subplots(2, 1, sharex=True, figsize=(7.0, 6.0),
                                           layout="constrained")
        else:
            fig, ax = plt.subplots(figsize=(7.0, 4.0), layout="constrained")
            ax_p = None
    else:
        fig, ax_p = ax.figure, None
    xs = tracks[against].values
    for o in tracks["order"].values:
        ax.plot(xs, tracks["amplitude"].sel(order=o).values, label=f"order {o:g}")
        if ax_p is not None:
            ax_p.plot(xs, np.degrees(np.unwrap(tracks["phase"].sel(order=o).values)))
    units = tracks["amplitude"].attrs.get("units", "")
    conv = tracks.attrs.get("amplitude_convention", "")
    ax.set_ylabel(f"{conv} amplitude [{units}]")
    ax.legend(fontsize=8)
    ax.set_title(f"order tracks ({tracks.attrs.get('method', '')})", fontsize=9)
    last = ax_p if ax_p is not None else ax
    last.set_xlabel("speed [rpm]" if against == "rpm" else "time [s]")
    if ax_p is not None:
        ax_p.set_ylabel("phase [deg]")
    return fig
