"""The Record: a measurement as an :class:`xarray.Dataset`, its validator and builders.

Schema (docs/DESIGN.md "Data model")
-------------------------------
Each channel is a 1-D data variable with attrs

* ``units`` — canonical SI spelling (:data:`measure.units.SI_UNITS`),
* ``quantity`` — one of :data:`measure.units.QUANTITIES`; ``units`` must match it,
* ``sample_rate`` — Hz (float, > 0; absent for ``pulse_times``),
* optional ``location``, ``direction``, ``sensitivity`` with ``sensitivity_units``.

Channels on one clock share the dim ``time`` (coordinate in s from record start, float64);
channels on another clock get ``time_<group>`` with its own coordinate. Pulse trains are stored as
edge times on dim ``pulse`` (``pulse_<name>`` when several) with units ``s``, quantity
``pulse_times`` and attrs ``pulses_per_rev`` (int) and ``missing_teeth`` (int, default 0);
optional ``speed_ratio`` (turns of the pulse source per crankshaft turn, > 0, default 1: 0.5 for
a mark once per four-stroke cycle) and ``role`` ("wheel" or "tdc", set when decoded from a raw
signal by a channel map, with ``runt_teeth``/``lost_teeth`` and how it was decoded).
Dataset attrs: ``start_time`` (ISO 8601), ``source`` (file name), ``source_stat`` (the source
file's identity at read time; its SHA-256 is :func:`measure.provenance.source_sha256`, computed
on demand), optional ``engine_id`` and ``test_id``; a record read through a channel map also keeps
``raw_source``, ``raw_sha256`` (the raw export it came from), ``channel_map`` (the map's text)
and ``channel_map_sha256``. Mixed sample rates are never resampled.
"""

from __future__ import annotations

import datetime as _dt
import math
from collections.abc import Mapping

import numpy as np
import pandas as pd
import xarray as xr

from crankbench.predict.errors import RecordError

from .scan import (  # noqa: F401 - re-exported: the Record's sample checks
    _SCAN_BLOCK, CLIP_QUANTITIES, _block_extremes, clipped_spans, nonfinite_spans,
    note_block_extremes, shared_scans)
from .units import QUANTITIES, QUANTITY_UNITS, SI_UNITS, sensitivity_to_si, to_si

__all__ = [
    "RecordError",
    "RecordWarning",
    "validate",
    "make_record",
    "channel_time",
    "list_channels",
    "is_pulse_dim",
    "nonfinite_spans",
    "clipped_spans",
    "time_coordinate",
]

#: Relative tolerance between ``sample_rate`` and the mean step of the time coordinate.
RATE_RTOL = 1e-4
#: Largest deviation of a single time step from 1/sample_rate, as a fraction of 1/sample_rate.
STEP_JITTER = 0.5


class RecordWarning(UserWarning):
    """Data usable in part (non-finite spans masked, fallbacks taken)."""


def is_pulse_dim(dim: str) -> bool:
    """True for ``pulse`` and ``pulse_<name>`` dims (edge-time channels).

    Examples
    --------
    >>> is_pulse_dim("pulse_cam"), is_pulse_dim("time_rpm")
    (True, False)
    """
    return dim == "pulse" or dim.startswith("pulse_")


def time_coordinate(n: int, sample_rate: float, start: float = 0.0) -> np.ndarray:
    """Regular time coordinate ``start + i / sample_rate`` for ``i = 0 .. n-1`` (s, float64).

    Examples
    --------
    >>> time_coordinate(4, 1000.0)
    array([0.   , 0.001, 0.002, 0.003])
    """
    t = np.arange(int(n), dtype=np.float64)
    t /= float(sample_rate)
    if start:
        t += start
    return t


def _describe_spans(spans, t) -> str:
    parts = []
    for a, b in spans[:3]:
        if t is not None:
            parts.append(f"samples {a}..{b - 1} (t = {t[a]:.6g}..{t[b - 1]:.6g} s)")
        else:
            parts.append(f"samples {a}..{b - 1}")
    more = f" and {len(spans) - 3} more span(s)" if len(spans) > 3 else ""
    return "; ".join(parts) + more


def _is_lazy(var) -> bool:
    """True for a chunked (dask-backed) Variable or DataArray (a numpy-backed one is answered
    without xarray's protocol check of ``.chunks``, which costs more than the rest of a small
    record's validation)."""
    return not isinstance(var.data, np.ndarray) and var.chunks is not None


def _check_time_axis(name: str, t: np.ndarray, fs: float | None, dim: str) -> None:
    t = np.asarray(t, dtype=np.float64)
    if t.size < 2:
        if t.size and not np.isfinite(t[0]):
            raise RecordError(f"channel {name!r}: time coordinate {dim!r} has NaN/inf at index "
                              "0; expected finite times in s")
        return
    with np.errstate(invalid="ignore"):  # inf - inf in a corrupt time axis is reported below
        dt = np.diff(t)
    # min/max reductions first (no temporaries); locate the fault only when there is one.
    # NaN propagates through min/max and an inf makes the sum inf - inf = NaN.
    dt_min, dt_max = float(dt.min()), float(dt.max())
    if not math.isfinite(dt_min + dt_max + float(t[0])):
        i = int(np.flatnonzero(~np.isfinite(t))[0])
        raise RecordError(f"channel {name!r}: time coordinate {dim!r} has NaN/inf at index {i}; "
                          "expected finite times in s")
    if dt_min <= 0:
        i = int(np.flatnonzero(dt <= 0)[0])
        kind = "duplicated" if dt[i] == 0 else "non-monotonic"
        raise RecordError(
            f"channel {name!r}: {kind} time stamp in {dim!r} at index {i + 1} "
            f"(t[{i}] = {t[i]:.9g} s, t[{i + 1}] = {t[i + 1]:.9g} s); expected strictly "
            "increasing time")
    if fs is None:
        return
    step = 1.0 / fs
    mean_step = (t[-1] - t[0]) / (t.size - 1)
    if max(dt_max - mean_step, mean_step - dt_min) > STEP_JITTER * min(step, mean_step):
        worst = int(np.argmax(np.abs(dt - mean_step)))
        raise RecordError(
            f"channel {name!r}: time step {dt[worst]:.9g} s at index {worst + 1} of {dim!r} "
            f"deviates from 1/sample_rate = {step:.9g} s by more than {STEP_JITTER:.0%} "
            "(gap or jitter in the logger clock)")
    if abs(mean_step - step) > RATE_RTOL * step:
        raise RecordError(
            f"channel {name!r}: sample_rate={fs:g} Hz is inconsistent with its time coordinate "
            f"{dim!r} (mean step {mean_step:.9g} s = {1 / mean_step:.6g} Hz); expected steps of "
            f"{step:.9g} s")


def validate(record: xr.Dataset, *, allow_nonfinite: bool = False,
             _regular_dims: frozenset = frozenset()) -> xr.Dataset:
    """Check ``record`` against the Record schema and return it unchanged.

    Parameters
    ----------
    record : xarray.Dataset
        The record to check.
    allow_nonfinite : bool
        Accept NaN/inf samples (masked dropouts). By default any NaN/inf is an error naming the
        channel and the spans.
    _regular_dims : frozenset
        Internal (readers): time dims built as ``start + i / sample_rate``, whose step-by-step
        scan is skipped.

    Returns
    -------
    xarray.Dataset
        ``record`` itself.

    Raises
    ------
    RecordError
        Naming the channel and what is wrong: missing or non-SI ``units``, unknown ``quantity``,
        units not matching the quantity, ``sample_rate`` missing, <= 0 or inconsistent with the
        time coordinate, non-monotonic or duplicated time, NaN/inf runs, bad pulse attrs.

    Notes
    -----
    For lazily loaded (dask-backed) channels the attribute and coordinate checks run, but the
    NaN/inf scan of the samples is left to the consumer (it would read the whole file).

    Examples
    --------
    >>> rec = make_record({"acc": dict(data=np.zeros(100), sample_rate=1000.0,
    ...                                 units="m/s^2", quantity="acceleration")})
    >>> validate(rec)["acc"].attrs["sample_rate"]
    1000.0
    """
    if not isinstance(record, xr.Dataset):
        raise RecordError(f"a Record must be an xarray.Dataset, got {type(record).__name__}")
    if not record.data_vars:
        raise RecordError("record has no channels; expected at least one data variable")
    start = record.attrs.get("start_time")
    if start is not None:
        try:
            _dt.datetime.fromisoformat(str(start))
        except ValueError:
            raise RecordError(f"record attr start_time={start!r} is not ISO 8601 "
                              "(expected e.g. '2026-01-31T12:00:00+00:00')") from None
    checked_dims: set[str] = set()
    variables = record.variables  # Variables, not DataArrays: record[name] costs O(channels)
    coords = record.coords  # membership only: no set of names built
    ends: dict[str, tuple] = {}
    for name in record.data_vars:
        var = variables[name]
        name = str(name)
        if var.ndim != 1:
            raise RecordError(f"channel {name!r} has dims {var.dims}; expected one dim "
                              "('time', 'time_<group>' or 'pulse...')")
        dim = str(var.dims[0])
        units = var.attrs.get("units")
        quantity = var.attrs.get("quantity")
        if units is None:
            raise RecordError(f"channel {name!r} has no 'units' attr; expected one of "
                              f"{', '.join(SI_UNITS)}")
        if units not in SI_UNITS:
            raise RecordError(f"channel {name!r} has non-SI units {units!r}; expected one of "
                              f"{', '.join(SI_UNITS)} (convert with measure.units.to_si)")
        if quantity is None:
            raise RecordError(f"channel {name!r} has no 'quantity' attr; expected one of "
                              f"{', '.join(QUANTITIES)}")
        if quantity not in QUANTITY_UNITS:
            raise RecordError(f"channel {name!r} has unknown quantity {quantity!r}; expected one "
                              f"of {', '.join(QUANTITIES)}")
        expected = QUANTITY_UNITS[quantity]
        if expected is not None and units != expected:
            raise RecordError(f"channel {name!r}: quantity {quantity!r} needs units {expected!r}, "
                              f"got {units!r}")
        if var.dtype.kind not in "fiu":
            raise RecordError(f"channel {name!r} has dtype {var.dtype}; expected real numbers")
        if "sensitivity" in var.attrs and "sensitivity_units" not in var.attrs:
            raise RecordError(f"channel {name!r} has 'sensitivity' without "
                              "'sensitivity_units'")
        pulse = quantity == "pulse_times"
        if pulse:
            _validate_pulses(name, var, dim)
            continue
        if is_pulse_dim(dim):
            raise RecordError(f"channel {name!r} is on pulse dim {dim!r} but has quantity "
                              f"{quantity!r}; expected 'pulse_times'")
        if dim != "time" and not dim.startswith("time_"):
            raise RecordError(f"channel {name!r} is on dim {dim!r}; expected 'time' or "
                              "'time_<group>'")
        fs = var.attrs.get("sample_rate")
        if fs is None:
            raise RecordError(f"channel {name!r} has no 'sample_rate' attr; expected Hz > 0")
        fs = _rate(name, fs)
        if dim not in coords:
            raise RecordError(f"channel {name!r}: dim {dim!r} has no time coordinate; expected "
                              "s from record start")
        if dim not in checked_dims:
            coord = variables[dim]
            units_t = coord.attrs.get("units", "s")
            if units_t != "s":
                raise RecordError(f"time coordinate {dim!r} has units {units_t!r}; expected 's'")
            index = record.xindexes.get(dim)
            ends[dim] = _ends(coord, index)
            if dim in _regular_dims or _lazy_index(index):
                # built as start + i / sample_rate by a reader: strictly increasing and
                # evenly spaced by construction; only the rate needs checking
                _check_time_axis_rate_only(name, ends[dim], fs, dim)
            else:
                _check_time_axis(name, coord.values, fs, dim)
            checked_dims.add(dim)
        else:
            _check_time_axis_rate_only(name, ends[dim], fs, dim)
        if not _is_lazy(var) and not allow_nonfinite and var.dtype.kind == "f":
            spans = nonfinite_spans(var.values)
            if spans:
                n_bad = sum(b - a for a, b in spans)
                raise RecordError(
                    f"channel {name!r} has {n_bad} NaN/inf sample(s) in {len(spans)} run(s): "
                    f"{_describe_spans(spans, variables[dim].values)}; expected finite values "
                    "(read with allow_nonfinite=True, or `crankbench import|analyse --allow-nonfinite`, "
                    "to mask them)")
    return record


def _lazy_index(index) -> bool:
    from .timeindex import is_implicit_time  # implicit regular clocks (issue 21)

    return is_implicit_time(index)


def _ends(coord, index=None) -> tuple[int, float, float]:
    n = coord.size
    if n < 2:
        return n, 0.0, 0.0
    if hasattr(index, "sample_rate") and hasattr(index, "start"):  # implicit: its numbers
        return n, index.start, index.start + (n - 1) / index.sample_rate
    values = coord.values  # numpy's indexing: xarray's would wrap each number in a Variable
    return n, float(values[0]), float(values[-1])


def _check_time_axis_rate_only(name, ends, fs, dim) -> None:
    n, t0, t1 = ends
    if n < 2:
        return
    mean_step = (t1 - t0) / (n - 1)
    if abs(mean_step * fs - 1.0) > RATE_RTOL:
        raise RecordError(
            f"channel {name!r}: sample_rate={fs:g} Hz is inconsistent with its time coordinate "
            f"{dim!r} (mean step {mean_step:.9g} s); channels sharing a time dim need the same "
            "sample rate")


def _validate_pulses(name: str, var: xr.DataArray, dim: str) -> None:
    if not is_pulse_dim(dim):
        raise RecordError(f"pulse-time channel {name!r} is on dim {dim!r}; expected 'pulse' or "
                          "'pulse_<name>'")
    if var.attrs.get("units") != "s":
        raise RecordError(f"pulse-time channel {name!r} must have units 's'")
    ppr = var.attrs.get("pulses_per_rev")
    if ppr is None:
        raise RecordError(f"pulse-time channel {name!r} has no 'pulses_per_rev' attr; expected "
                          "an integer >= 1")
    if not _is_int(ppr) or int(ppr) < 1:
        raise RecordError(f"pulse-time channel {name!r}: pulses_per_rev={ppr!r}; expected an "
                          "integer >= 1")
    missing = var.attrs.get("missing_teeth", 0)
    if not _is_int(missing) or not 0 <= int(missing) < int(ppr):
        raise RecordError(f"pulse-time channel {name!r}: missing_teeth={missing!r}; expected an "
                          f"integer in [0, {int(ppr) - 1}]")
    ratio = var.attrs.get("speed_ratio", 1.0)
    try:
        ratio_ok = float(ratio) > 0 and math.isfinite(float(ratio))
    except (TypeError, ValueError):
        ratio_ok = False
    if not ratio_ok:
        raise RecordError(f"pulse-time channel {name!r}: speed_ratio={ratio!r}; expected a "
                          "number > 0 (turns of the pulse source per crankshaft turn)")
    if _is_lazy(var):
        return
    t = np.asarray(var.values, dtype=np.float64)
    if t.size and not np.all(np.isfinite(t)):
        i = int(np.flatnonzero(~np.isfinite(t))[0])
        raise RecordError(f"pulse-time channel {name!r} has NaN/inf edge time at index {i}; "
                          "expected finite times in s")
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.flatnonzero(dt <= 0)[0])
        kind = "duplicated" if dt[i] == 0 else "non-monotonic"
        raise RecordError(f"pulse-time channel {name!r}: {kind} edge time at index {i + 1} "
                          f"({t[i]:.9g} s then {t[i + 1]:.9g} s); expected strictly increasing")


def _is_int(value) -> bool:
    if isinstance(value, (bool, np.bool_)):
        return False
    if isinstance(value, (int, np.integer)):
        return True
    if isinstance(value, (float, np.floating)) and float(value).is_integer():
        return True
    return False


_SPEC_KEYS = {"data", "sample_rate", "units", "quantity", "time", "t0", "dim", "location",
              "direction", "sensitivity", "sensitivity_units", "pulses_per_rev",
              "missing_teeth", "attrs"}


def plain_variable(dim: str, values: np.ndarray, attrs: dict) -> xr.Variable:
    """``xarray.Variable((dim,), values, attrs)`` of a channel read into a plain numpy array
    (``values``: float or integer samples in SI units), without xarray's checks for other array
    types: among them, whether it is a dask array holding a masked one, which imports dask
    (about 0.3 s with what it pulls in) at the first record a process reads. Anything but a
    plain 1-D numeric ndarray takes xarray's full path."""
    if type(values) is np.ndarray and values.ndim == 1 and values.dtype.kind in "fiu":
        return xr.Variable((dim,), values, attrs, fastpath=True)
    return xr.Variable((dim,), values, attrs)


def make_record(
    channels: Mapping[str, Mapping],
    *,
    start_time: str | _dt.datetime | None = None,
    attrs: Mapping | None = None,
    allow_nonfinite: bool = False,
) -> xr.Dataset:
    """Build a validated Record from arrays and sample rates.

    Parameters
    ----------
    channels : mapping of name -> dict
        Each dict holds ``data`` (1-D array), ``units`` (any spelling :func:`measure.units.to_si`
        knows; converted to SI here), ``quantity`` (optional when the unit implies it), and
        either ``sample_rate`` (Hz) with optional ``t0`` (s, start offset, default 0) or an
        explicit ``time`` array (s; ``sample_rate`` then defaults to its mean rate). Optional:
        ``dim`` (force a dim name), ``location``, ``direction``, ``sensitivity`` with
        ``sensitivity_units`` (converted to SI), ``attrs`` (extra attrs). Pulse trains:
        ``quantity="pulse_times"``, ``data`` = edge times (s), ``pulses_per_rev``,
        ``missing_teeth`` (default 0), no sample rate.
    start_time : str or datetime, optional
        Absolute start (ISO 8601). Default: not set.
    attrs : mapping, optional
        Dataset attrs (``engine_id``, ``test_id``, ...).
    allow_nonfinite : bool
        Passed to :func:`validate`.

    Returns
    -------
    xarray.Dataset
        The Record. Clocks are grouped by (sample rate, length, start offset): the fastest clock
        (first on ties) gets dim ``time``, each other clock ``time_<first channel on it>``.
        Pulse channels get ``pulse`` (one train) or ``pulse_<name>`` (several).

    Examples
    --------
    >>> fs = 1000.0
    >>> rec = make_record({
    ...     "acc": dict(data=np.ones(2000), sample_rate=fs, units="g"),
    ...     "rpm": dict(data=np.full(20, 3000.0), sample_rate=10.0, units="rpm"),
    ...     "tacho": dict(data=np.arange(5) * 0.02, quantity="pulse_times", units="s",
    ...                   pulses_per_rev=1)})
    >>> print(rec["acc"].dims, rec["acc"].attrs["units"], float(rec["acc"][0]))
    ('time',) m/s^2 9.80665
    >>> print(rec["rpm"].dims, rec["rpm"].attrs["quantity"], round(float(rec["rpm"][0]), 3))
    ('time_rpm',) rotational_speed 314.159
    """
    if not isinstance(channels, Mapping) or not channels:
        raise RecordError("make_record needs a non-empty mapping of channel name -> spec dict")
    built: dict[str, dict] = {}
    for name, spec in channels.items():
        if not isinstance(spec, Mapping):
            raise RecordError(f"channel {name!r}: spec must be a dict with data, units, ...")
        unknown = set(spec) - _SPEC_KEYS
        if unknown:
            raise RecordError(f"channel {name!r}: unknown spec key(s) {sorted(unknown)}; "
                              f"expected some of {sorted(_SPEC_KEYS)}")
        built[str(name)] = _build_channel(str(name), spec)

    # group sampled channels by clock
    clocks: list[dict] = []
    for name, ch in built.items():
        if ch["pulse"]:
            continue
        key = ch["clock"]
        for clock in clocks:
            if ch.get("dim") is not None and clock["dim"] is not None:
                if clock["dim"] == ch["dim"]:
                    if clock["key"] != key:
                        raise RecordError(f"channel {name!r} is on dim {ch['dim']!r} but its "
                                          "clock (sample rate, length, t0) differs from "
                                          f"{clock['names'][0]!r}")
                    clock["names"].append(name)
                    break
                continue
            if clock["key"] == key and (ch.get("dim") is None or clock["dim"] is None):
                clock["names"].append(name)
                if ch.get("dim") is not None:
                    clock["dim"] = ch["dim"]
                break
        else:
            clocks.append({"key": key, "names": [name], "dim": ch.get("dim"), "time": ch["time"],
                           "fs": ch["sample_rate"]})
    auto = [c for c in clocks if c["dim"] is None]
    if auto and not any(c["dim"] == "time" for c in clocks):
        main = max(auto, key=lambda c: c["fs"])
        main["dim"] = "time"
    for clock in clocks:
        if clock["dim"] is None:
            clock["dim"] = f"time_{clock['names'][0]}"
    coords = {}
    data_vars = {}
    for clock in clocks:
        coords[clock["dim"]] = (clock["dim"], pd.Index(clock["time"], copy=False), {"units": "s",
                                                             "long_name": "time from record start"})
        for name in clock["names"]:
            ch = built[name]
            data_vars[name] = plain_variable(clock["dim"], ch["data"], ch["attrs"])
    pulses = [n for n, ch in built.items() if ch["pulse"]]
    for name in pulses:
        ch = built[name]
        dim = ch.get("dim") or ("pulse" if len(pulses) == 1 else f"pulse_{name}")
        data_vars[name] = plain_variable(dim, ch["data"], ch["attrs"])
    ds = xr.Dataset(data_vars, coords=coords)
    ds = ds[list(built)]  # keep the caller's channel order
    ds_attrs = dict(attrs or {})
    if start_time is not None:
        ds_attrs["start_time"] = (start_time.isoformat() if isinstance(start_time, _dt.datetime)
                                  else str(start_time))
    ds.attrs = ds_attrs
    return validate(ds, allow_nonfinite=allow_nonfinite)


def _build_channel(name: str, spec: Mapping) -> dict:
    if "data" not in spec:
        raise RecordError(f"channel {name!r}: spec has no 'data'")
    try:
        data = np.asarray(spec["data"])
    except (TypeError, ValueError):
        raise RecordError(f"channel {name!r}: data is not an array") from None
    if data.dtype.kind not in "fiu" or data.ndim != 1:
        raise RecordError(f"channel {name!r}: data must be a 1-D real array, got dtype "
                          f"{data.dtype} shape {data.shape}")
    if data.dtype.kind in "iu":
        data = data.astype(np.float64)
    if "units" not in spec:
        raise RecordError(f"channel {name!r}: spec has no 'units'")
    values, units, hint = to_si(data, spec["units"], channel=name)
    quantity = spec.get("quantity", hint)
    if quantity is None or quantity == "sensitivity":
        raise RecordError(f"channel {name!r}: units {spec['units']!r} do not imply a quantity; "
                          f"pass quantity= one of {', '.join(QUANTITIES)}")
    attrs = {"units": units, "quantity": quantity}
    extra = dict(spec.get("attrs") or {})
    for key in ("location", "direction"):
        if spec.get(key) is not None:
            attrs[key] = str(spec[key])
    if spec.get("sensitivity") is not None:
        if spec.get("sensitivity_units") is None:
            raise RecordError(f"channel {name!r}: sensitivity given without sensitivity_units")
        value, su = sensitivity_to_si(spec["sensitivity"], spec["sensitivity_units"], channel=name)
        attrs["sensitivity"] = value
        attrs["sensitivity_units"] = su
    pulse = quantity == "pulse_times"
    out = {"pulse": pulse, "dim": spec.get("dim"), "data": values}
    if pulse:
        if "pulses_per_rev" not in spec:
            raise RecordError(f"pulse-time channel {name!r}: spec needs 'pulses_per_rev'")
        attrs["pulses_per_rev"] = spec["pulses_per_rev"]
        attrs["missing_teeth"] = spec.get("missing_teeth", 0)
        for key in ("pulses_per_rev", "missing_teeth"):
            if not _is_int(attrs[key]):
                raise RecordError(f"pulse-time channel {name!r}: {key}={attrs[key]!r}; "
                                  "expected an integer")
            attrs[key] = int(attrs[key])
        out["data"] = np.asarray(values, dtype=np.float64)
        attrs.update(extra)
        out["attrs"] = attrs
        return out
    if spec.get("time") is not None:
        time = np.asarray(spec["time"], dtype=np.float64)
        if time.shape != data.shape:
            raise RecordError(f"channel {name!r}: time has shape {time.shape}, data "
                              f"{data.shape}; expected equal lengths")
        if spec.get("sample_rate") is not None:
            fs = _rate(name, spec["sample_rate"])
        elif time.size >= 2 and np.all(np.isfinite(time)) and time[-1] > time[0]:
            fs = (time.size - 1) / (time[-1] - time[0])
        else:
            raise RecordError(f"channel {name!r}: cannot infer sample_rate from its time array; "
                              "pass sample_rate (Hz)")
        key = ("explicit", fs, time.size, float(time[0]) if time.size else 0.0, time.tobytes())
    else:
        if spec.get("sample_rate") is None:
            raise RecordError(f"channel {name!r}: spec needs 'sample_rate' (Hz) or 'time' (s)")
        fs = _rate(name, spec["sample_rate"])
        t0 = float(spec.get("t0", 0.0))
        time = time_coordinate(data.size, fs, t0)
        key = ("regular", fs, data.size, t0)
    attrs["sample_rate"] = float(fs)
    attrs.update(extra)
    out.update(attrs=attrs, time=time, sample_rate=float(fs), clock=key)
    return out


def _rate(name: str, value) -> float:
    try:
        fs = float(value)
    except (TypeError, ValueError):
        raise RecordError(f"channel {name!r}: sample_rate={value!r} is not a number "
                          "(expected Hz > 0)") from None
    if not np.isfinite(fs) or fs <= 0:
        raise RecordError(f"channel {name!r}: sample_rate={value!r} Hz; expected a finite "
                          "value > 0")
    return fs


def channel_time(record: xr.Dataset, name: str) -> np.ndarray:
    """Times of channel ``name`` in s from record start (float64).

    For sampled channels the channel's time coordinate; for pulse-time channels the edge times
    themselves.

    Examples
    --------
    >>> rec = make_record({"x": dict(data=np.zeros(3), sample_rate=2.0, units="V")})
    >>> channel_time(rec, "x")
    array([0. , 0.5, 1. ])
    """
    if name not in record.data_vars:
        from crankbench.predict._validate import suggest
        raise RecordError(f"record has no channel {name!r}{suggest(name, map(str, record.data_vars))}; "
                          f"channels: {', '.join(map(str, record.data_vars))}")
    var = record[name]
    if var.attrs.get("quantity") == "pulse_times":
        return np.asarray(var.values, dtype=np.float64)
    dim = var.dims[0]
    if dim not in record.coords:
        raise RecordError(f"channel {name!r}: dim {dim!r} has no time coordinate")
    return np.asarray(record[dim].values, dtype=np.float64)


def list_channels(record: xr.Dataset) -> pd.DataFrame:
    """One row per channel: name, quantity, units, sample_rate (Hz), n, duration_s, dim.

    ``duration_s`` is ``n / sample_rate`` for sampled channels and the span between the first
    and last edge for pulse trains (``sample_rate`` NaN).

    Examples
    --------
    >>> rec = make_record({"x": dict(data=np.zeros(500), sample_rate=100.0, units="mm/s")})
    >>> list_channels(rec)[["name", "units", "n", "duration_s"]].to_dict("records")
    [{'name': 'x', 'units': 'm/s', 'n': 500, 'duration_s': 5.0}]
    """
    rows = []
    for name, var in record.data_vars.items():
        n = int(var.size)
        fs = var.attrs.get("sample_rate")
        if var.attrs.get("quantity") == "pulse_times":
            vals = var.values if n else np.array([])
            duration = float(vals[-1] - vals[0]) if n >= 2 else 0.0
            fs = float("nan")
        else:
            fs = float(fs) if fs is not None else float("nan")
            duration = n / fs if fs and np.isfinite(fs) and fs > 0 else float("nan")
        rows.append({"name": str(name), "quantity": var.attrs.get("quantity"),
                     "units": var.attrs.get("units"), "sample_rate": fs, "n": n,
                     "duration_s": duration, "dim": str(var.dims[0]) if var.dims else ""})
    return pd.DataFrame(rows, columns=["name", "quantity", "units", "sample_rate", "n",
                                       "duration_s", "dim"])
