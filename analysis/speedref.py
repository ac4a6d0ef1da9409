"""Speed reference for a record channel: shaft speed (rpm) at each of the channel's samples.

Order analysis needs the shaft speed at every sample of the analysed channel. A Record carries it
as a ``rotational_speed`` channel (rad/s, possibly on another clock) or as a tacho/encoder pulse
train (edge times with ``pulses_per_rev`` and ``missing_teeth``). The speed is interpolated
linearly onto the channel's time samples; pulse trains are first turned into speed by
:func:`measure.tacho.speed_from_pulses` (exact for constant angular acceleration; averaged over
``window_revs`` revolutions, which removes tooth-spacing errors and integer orders of the shaft's
own torsional vibration from the reference).

Error: linear interpolation of the speed adds ``(Δt)² |d²n/dt²| / 8`` rpm between speed samples;
samples of the channel beyond the speed trace take its end value (logged when more than
one revolution away).

References
----------
交通大学《内燃机动力学》(1958) 第二篇第五章 §1 (time and angle marks on torsiograph records).
"""

from __future__ import annotations

import logging

import numpy as np
import xarray as xr

from crankbench.predict._validate import check_positive, suggest
from crankbench.predict.errors import AnalysisError, RecordError

__all__ = ["speed_reference", "find_speed_channel"]

log = logging.getLogger("crankbench")

_TWO_PI = 2.0 * np.pi


def _is_pulses(var) -> bool:
    return var.attrs.get("quantity") == "pulse_times" or (
        len(var.dims) == 1 and str(var.dims[0]).split("_")[0] == "pulse")


def _times(record, name: str) -> np.ndarray:
    var = record[name]
    if _is_pulses(var):
        return np.asarray(var.values, dtype=float)
    dim = var.dims[0]
    if dim in record.coords:
        return np.asarray(record[dim].values, dtype=float)
    rate = var.attrs.get("sample_rate")
    if rate is None:
        raise RecordError(f"channel {name!r}: dim {dim!r} has no time coordinate and no "
                          "sample_rate attr")
    return np.arange(var.shape[0]) / float(rate)


def find_speed_channel(record, channel: str | None = None) -> str:
    """Name of the record's speed source: a ``rotational_speed`` channel, else a pulse train.

    A speed channel on the same clock as ``channel`` is preferred.

    Examples
    --------
    >>> import xarray as xr
    >>> rec = xr.Dataset({"n": ("time", np.full(4, 100.0), {"quantity": "rotational_speed",
    ...                                                      "units": "rad/s"})})
    >>> find_speed_channel(rec)
    'n'
    """
    names = [str(n) for n in record.data_vars]
    speeds = [n for n in names if record[n].attrs.get("quantity") == "rotational_speed"]
    pulses = [n for n in names if _is_pulses(record[n])]
    for group in (speeds, pulses):
        if group:
            if channel is not None and channel in record.data_vars:
                same = [n for n in group if record[n].dims == record[channel].dims]
                if same:
                    return same[0]
            if len(group) > 1:
                log.info("several speed sources (%s); using %r", ", ".join(group), group[0])
            return group[0]
    raise AnalysisError(f"record has no speed reference: no channel with quantity "
                        f"'rotational_speed' and no pulse train; channels: {', '.join(names)}")


def _pulse_speed(var, name):
    if var.attrs.get("pulses_per_rev") is None:
        raise RecordError(f"pulse channel {name!r} has no 'pulses_per_rev' attr")
    from crankbench.measure.tacho import pulse_channel_speed  # reads the layout attrs

    t, omega = pulse_channel_speed(var)
    return np.asarray(t, float), np.asarray(omega, float)


def speed_reference(record, channel: str, *,
                    speed_channel: str | None = None) -> xr.DataArray:
    """Shaft speed in rpm at each time sample of ``channel``.

    Parameters
    ----------
    record : xarray.Dataset
        A Record (docs/DESIGN.md data model).
    channel : str
        The channel to be analysed (its time samples are where the speed is wanted).
    speed_channel : str, optional
        The speed source: a ``rotational_speed`` channel (rad/s) or a pulse train (edge times,
        attrs ``pulses_per_rev``, ``missing_teeth``). Default: found by
        :func:`find_speed_channel`.

    Returns
    -------
    xarray.DataArray
        Speed, rpm (``attrs["units"]``), one value per sample of ``channel``, on that channel's
        time coordinate (s); ``attrs["source"]`` names where it came from. Pass it as
        ``speed_rpm=`` to the order trackers.

    Examples
    --------
    >>> import xarray as xr
    >>> t = np.arange(5) / 10.0
    >>> rec = xr.Dataset(
    ...     {"acc": ("time", np.zeros(5), {"units": "m/s^2", "sample_rate": 10.0}),
    ...      "n": ("time_tacho", np.full(3, 2 * np.pi * 25.0), {"quantity": "rotational_speed",
    ...                                                         "units": "rad/s"})},
    ...     coords={"time": t, "time_tacho": [0.0, 0.2, 0.4]})
    >>> n = speed_reference(rec, "acc")
    >>> n.values, n.attrs["units"], n.attrs["source"]
    (array([1500., 1500., 1500., 1500., 1500.]), 'rpm', "speed channel 'n'")
    """
    if channel not in record.data_vars:
        raise RecordError(f"record has no channel {channel!r}"
                          f"{suggest(channel, map(str, record.data_vars))}; channels: "
                          f"{', '.join(map(str, record.data_vars))}")
    name = speed_channel or find_speed_channel(record, channel)
    if name not in record.data_vars:
        raise RecordError(f"record has no speed channel {name!r}"
                          f"{suggest(name, map(str, record.data_vars))}")
    var = record[name]
    t_out = _times(record, channel)
    if _is_pulses(var):
        t_in, omega = _pulse_speed(var, name)
        source = f"pulse train {name!r}"
    else:
        units = var.attrs.get("units", "rad/s")
        if units not in ("rad/s",):
            raise RecordError(f"speed channel {name!r} has units {units!r}; expected 'rad/s' "
                              "(convert at ingest)")
        t_in = _times(record, name)
        omega = np.asarray(var.values, dtype=float)
        source = f"speed channel {name!r}"
    good = np.isfinite(omega)
    if not good.all():
        log.warning("%s: %d non-finite speed values skipped", source, int((~good).sum()))
        t_in, omega = t_in[good], omega[good]
    if t_in.shape[0] == 0:
        raise AnalysisError(f"{source} holds no usable speed values")
    rpm = np.interp(t_out, t_in, omega) * (60.0 / _TWO_PI)
    if rpm.min() <= 0:
        i = int(np.argmin(rpm))
        raise AnalysisError(f"{source}: speed {rpm[i]:.6g} rpm at t = {t_out[i]:.6g} s; order "
                            "analysis needs the shaft turning (> 0 rpm) throughout; select a "
                            "time range where it turns")
    rev_time = 60.0 / float(np.median(rpm))
    outside = max(t_in[0] - t_out[0], t_out[-1] - t_in[-1])
    # speed from pulses starts a window (1-2 revolutions) after the first edge: holding it over
    # that stretch is expected; beyond 3 revolutions the user should know
    if outside > 3.0 * rev_time:
        log.warning("%s covers %.6g–%.6g s but channel %r spans %.6g–%.6g s; the speed is held "
                    "constant beyond its ends", source, t_in[0], t_in[-1], channel, t_out[0],
                    t_out[-1])
    check_positive(rev_time, "revolution time", error=AnalysisError)
    dim = record[channel].dims[0]
    return xr.DataArray(rpm, dims=(dim,), coords={dim: (dim, t_out, {"units": "s"})},
                        name="speed_rpm", attrs={"units": "rpm", "long_name": "shaft speed",
                                                 "source": source, "channel": channel})
