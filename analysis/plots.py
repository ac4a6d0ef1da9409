"""Figures of order-analysis results: order map, Campbell (rpm–frequency) map, order tracks.

Each function takes a result of :mod:`analysis.orders` and an optional matplotlib ``ax``, draws
on it, and returns the figure; none calls ``show()``.
"""

from __future__ import annotations

import numpy as np

from crankbench.predict.errors import AnalysisError

__all__ = ["plot_order_map", "plot_campbell", "plot_order_tracks"]


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
                         cmap="viridis")
    units = order_map.attrs.get("units", "")
    label = (f"dB re max" if db else f"{order_map.attrs.get('amplitude_convention', '')} "
             f"[{units}]")
    fig.colorbar(mesh, ax=ax, label=label)
    ax.set_xlabel("order")
    ax.set_ylabel("speed [rpm]")
    ax.set_title(str(order_map.name or "order map"))
    return fig


def plot_campbell(campbell, ax=None, *, orders=None, db: bool = True, floor_db: float = -80.0,
                  critical_frequencies_hz=()):
    """Campbell diagram: speed (rpm) against frequency (Hz), with order rays.

    Parameters
    ----------
    campbell : xarray.DataArray
        From :func:`analysis.campbell_map`.
    ax : matplotlib Axes, optional
    orders : sequence of float, optional
        Order rays ``f = o · rpm / 60`` to draw (default ``attrs['order_lines']``).
    db, floor_db
        As in :func:`plot_order_map`.
    critical_frequencies_hz : sequence of float
        Natural frequencies drawn as vertical lines (e.g. predicted torsional modes).

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
    >>> len(plot_campbell(c).axes[0].lines)
    2
    """
    if "frequency" not in campbell.dims or "rpm" not in campbell.coords:
        raise AnalysisError("plot_campbell needs a map with dim 'frequency' and an 'rpm' "
                            "coordinate (analysis.campbell_map)")
    fig, ax = _axes(ax)
    speed = _speed_axis(campbell)
    values = campbell.transpose(..., "frequency").values
    mesh = ax.pcolormesh(campbell["frequency"].values, speed,
                         _db(values, floor_db) if db else values, shading="nearest",
                         cmap="magma")
    fig.colorbar(mesh, ax=ax, label="dB re max" if db else f"[{campbell.attrs.get('units', '')}]")
    lines = campbell.attrs.get("order_lines", []) if orders is None else orders
    rpm_line = np.array([np.nanmin(speed), np.nanmax(speed)])
    f_top = float(campbell["frequency"].values[-1])
    for o in lines:
        ax.plot(o * rpm_line / 60.0, rpm_line, color="w", lw=0.8, ls="--")
        f_end = o * rpm_line[-1] / 60.0
        if f_end <= f_top:
            ax.annotate(f"{o:g}", (f_end, rpm_line[-1]), color="w", fontsize=8)
    for fc in critical_frequencies_hz:
        ax.axvline(fc, color="c", lw=0.8)
    ax.set_xlim(campbell["frequency"].values[0], f_top)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("speed [rpm]")
    ax.set_title(str(campbell.name or "Campbell diagram"))
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
