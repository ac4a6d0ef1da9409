"""Indicator analysis of a crank-angle-domain export (pressure per cycle against crank angle).

An indicating system (AVL IndiCom, Kistler KiBox, Dewesoft CA mode) has already cut the
pressure into cycles on its own crank-angle axis; :func:`measure.readers.angle_table.\
read_angle_table` reads such a file into a Dataset with dims ``(cycle, crank_angle)``.
:func:`indicator_analysis_cycles` runs on it the same back half as the time-domain analysis
(:func:`analysis.pressure.indicator_analysis`): pegging, the thermodynamic TDC check and
correction, peaks, IMEP/PMEP/COV and the single-zone heat release. What differs is the front:

* the **zero** of the file's axis is taken as a TDC of the channel's cylinder (indicating
  systems reference the axis to TDC); which TDC fires — file angle 0 or 360, or, on an axis
  referenced to cylinder 1, that plus the cylinder's firing angle — is the one with the
  highest mean pressure within ±30° (stated; a warning when the two TDCs of a cycle differ by
  less than a factor 1.25), unless ``firing_tdc_deg`` (or the map's ``[source]
  firing_tdc_deg``) says where it is;
* the **TDC correction** is an angle shift of the cut: consecutive cycles (cycle numbers
  stepping by 1) are joined into one continuous angle record, so a shifted cycle takes its
  edge from its neighbour (the ends of a run are extended periodically by 90° at most, and a
  lone cycle — an averaged one — is periodic); the grid is the file's own (no resampling when
  no shift is applied);
* **speed is optional**: only the speed and time columns of the result need it (``speed`` per
  cycle in the file, or ``speed_rpm=``); without it they are NaN and the summary says "speed
  not given". Pegging, TDC, IMEP, PMEP, COV and heat release are per degree and need no
  time; the peg's drift correction within a cycle is then linear in crank angle (the same at
  steady speed).

A 0..720 axis with the firing TDC at 0 puts each combustion's compression in the previous
file cycle: N consecutive cycles then give N − 1 whole firing cycles (−360..360 around the
firing TDC), the first and last half cycles being incomplete.

Accuracy: the cut picks the file's samples exactly (4-point Lagrange at integer positions),
so on the same cycles the results equal the time-domain analysis's to the precision the file
prints (tests/analysis/test_pressure_cycles.py: IMEP, peak pressure, peak angle, COV and heat
release within 1e-4 relative and 0.01° on the synthetic bench's I4 exported with 4 decimals of
bar); against the bench's truth the time-domain accuracy table of :mod:`analysis.pressure`
holds.
"""

from __future__ import annotations

import dataclasses
import logging

import numpy as np

from crankbench.predict._threads import single_threaded_blas
from crankbench.predict._validate import check_option
from crankbench.predict.errors import AnalysisError

from . import indicator as thermo
from .pressure import BAR, DEG, _analyse_cycles, _checked_cylinder, _load_engine
from .pressure_angle import _cut

__all__ = ["indicator_analysis_cycles", "angle_pressure_channels"]

log = logging.getLogger("crankbench")

TWO_PI = 2.0 * np.pi
#: periodic extension at the ends of a run of consecutive cycles, rad (covers any TDC shift)
_PAD = 90.0 * DEG


def angle_pressure_channels(data) -> list:
    """Pressure channels of an angle-domain Dataset (dims ``(cycle, crank_angle)``).

    Examples
    --------
    >>> import xarray as xr
    >>> ds = xr.Dataset({"P1": (("cycle", "crank_angle"), np.ones((1, 4)), {"quantity":
    ...                  "pressure"})}, coords={"cycle": [1], "crank_angle": np.arange(4.0)})
    >>> angle_pressure_channels(ds)
    ['P1']
    """
    return [str(n) for n, v in data.data_vars.items() if v.attrs.get("quantity") == "pressure"
            and v.dims == ("cycle", "crank_angle")]


def _runs(numbers):
    """Index ranges of runs of consecutive cycle numbers."""
    cut = np.flatnonzero(np.diff(numbers) != 1) + 1
    edges = np.concatenate([[0], cut, [numbers.size]])
    return [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:])]


def _continuous(p, axis, omega, lone):
    """One run of consecutive cycles as a continuous angle record (θ, p, t), extended at both
    ends periodically (by a whole cycle for a lone cycle, else by ``_PAD``); ``omega`` per
    cycle gives the clock t (any unit when only linear in time matters)."""
    n = axis.size
    step = axis[1] - axis[0]
    period = n * step
    k = p.shape[0]
    m = n if lone else min(n, int(np.ceil(_PAD / step)) + 4)
    theta = np.concatenate([axis[-m:] - period,
                            (np.arange(k)[:, None] * period + axis[None, :]).ravel(),
                            axis[:m] + k * period])
    values = np.concatenate([p[0, -m:], p.ravel(), p[-1, :m]])
    w = np.concatenate([np.full(m, omega[0]), np.repeat(omega, n), np.full(m, omega[-1])])
    t = np.concatenate([[0.0], np.cumsum(np.diff(theta) / w[1:])])
    return theta, values, t - np.interp(axis[0], theta, t)


def _firing_tdc(data, channel, p, axis, fire, period, given, warnings):
    """File angle (rad) of the channel's firing TDC, and how it was chosen."""
    if given is not None:
        return float(np.deg2rad(given)), f"firing TDC at {given:g} deg of the file's axis (given)"
    mean = p.mean(axis=0)
    cands = sorted({round(float(np.mod(c, period)), 9) for c in
                    ([0.0, fire] + ([TWO_PI, fire + TWO_PI] if period > TWO_PI + 1e-9 else []))})

    def level(c):
        d = np.abs(np.angle(np.exp(1j * (axis - c) * TWO_PI / period))) * period / TWO_PI
        return float(mean[d <= 30 * DEG].mean())

    levels = [level(c) for c in cands]
    best = int(np.argmax(levels))
    base = cands[best]
    own = abs(np.mod(base, TWO_PI)) < 1e-6 or abs(np.mod(base, TWO_PI) - TWO_PI) < 1e-6
    text = (f"firing TDC at {np.rad2deg(base):g} deg of the file's axis (the highest mean "
            f"pressure within ±30 deg of the cylinder's TDCs: {levels[best] / BAR:.3g} bar"
            + ("" if own else "; the axis is referenced to cylinder 1") + ")")
    if period > TWO_PI + 1e-9:
        other = level(np.mod(base + TWO_PI, period))
        if levels[best] < 1.25 * other:
            warnings.append(f"channel {channel!r}: the pressure does not tell the firing TDC "
                            f"from the gas-exchange TDC (mean {levels[best] / BAR:.3g} against "
                            f"{other / BAR:.3g} bar within ±30 deg): the phase is a guess; give "
                            "firing_tdc_deg= (CLI --firing-tdc-deg, map [source] firing_tdc_deg)")
            text += "; inconclusive (see the warnings)"
    return base, text


@single_threaded_blas
def indicator_analysis_cycles(data, engine, *, channel=None, cylinder=None, firing_tdc_deg=None,
                              speed_rpm=None, peg="auto", peg_pressure=None,
                              peg_window_deg=(-100.0, -35.0), polytropic_exponent=None,
                              tdc_correction=False, tdc_window_deg=(-90.0, -25.0),
                              loss_angle_deg=0.5, gamma=1.32, max_cycles=None, cycle=None):
    """Indicator analysis of one pressure channel of an angle-domain export.

    Parameters
    ----------
    data : xarray.Dataset or path-like
        From :func:`measure.readers.angle_table.read_angle_table` (a path is read with it).
    engine : predict.engine.Engine, path-like or None
        Engine model (cylinder geometry); without it only peaks and the BDC peg are given.
    channel : str, optional
        Pressure channel (default: the first).
    cylinder : int, optional
        Its cylinder (default: its ``cylinder`` attr, else 1).
    firing_tdc_deg : float, optional
        Angle of the file's axis at which this channel's cylinder fires, deg (default: the
        data's ``firing_tdc_deg`` attr, else found from the pressure among the cylinder's
        TDCs).
    speed_rpm : float, optional
        Engine speed, rpm, when the file has no speed column (only the speed and time
        columns of the result use it).
    peg, peg_pressure, peg_window_deg, polytropic_exponent, tdc_correction, tdc_window_deg, \
loss_angle_deg, gamma, max_cycles
        As :func:`analysis.pressure.indicator_analysis`.
    cycle : {2, 4}, optional
        Strokes without an engine model (default: the file's cycle span).

    Returns
    -------
    analysis.pressure.IndicatorResult
        With ``cycle_number`` (the file's cycle numbers of the cycles analysed).

    Raises
    ------
    AnalysisError
        Not an angle-domain Dataset, the file's cycle span (720° or 360°) not the engine's
        cycle, no whole cycle, an invalid option.

    Examples
    --------
    >>> import xarray as xr
    >>> from crankbench.predict.engine import Engine
    >>> eng = Engine(crank_angles_deg=[0], crank_radius=0.045, rod_length=0.15,
    ...              reciprocating_mass=0.5, bore=0.085, compression_ratio=10.0)
    >>> from crankbench.analysis.indicator import chamber_volume
    >>> ca = np.deg2rad(np.arange(-360.0, 360.0, 0.5))
    >>> V = chamber_volume(eng, ca)
    >>> p = np.where(np.abs(ca) <= np.pi, 0.95e5 * (V.max() / V) ** 1.33,   # 0.95 * 10^1.33
    ...              np.where(ca > 0, 1.05e5, 0.95e5))                       # exhaust, intake
    >>> ds = xr.Dataset({"p": (("cycle", "crank_angle"), p[None, :], {"quantity": "pressure",
    ...                  "units": "Pa"})}, coords={"cycle": [1], "crank_angle": ca},
    ...                 attrs={"domain": "crank_angle", "cycle_deg": 720.0})
    >>> r = indicator_analysis_cycles(ds, eng, peg="none")
    >>> angle = np.round(np.rad2deg(r.mean["peak_angle"]), 3) + 0.0
    >>> gross = np.round(r.imep_gross[0] / 1e5, 3) + 0.0
    >>> print(f"{r.mean['peak_pressure'] / 1e5:.2f} bar at {angle:.1f} deg, PMEP "
    ...       f"{r.pmep[0] / 1e5:.3f} bar, gross IMEP {gross:.3f} bar")
    20.31 bar at 0.0 deg, PMEP 0.100 bar, gross IMEP 0.000 bar
    """
    if not hasattr(data, "data_vars"):
        from crankbench.measure.readers.angle_table import read_angle_table

        data = read_angle_table(data)
    if data.attrs.get("domain") != "crank_angle" or "crank_angle" not in data.dims:
        raise AnalysisError("not a crank-angle-domain dataset (dims (cycle, crank_angle), attr "
                            "domain = 'crank_angle'); read the export with "
                            "measure.readers.angle_table.read_angle_table")
    engine = None if engine is None else _load_engine(engine)
    if engine is not None:
        thermo._check_engine(engine)
    peg = check_option(peg, "peg", ("auto", "bdc", "polytropic", "none"), error=AnalysisError)
    chans = angle_pressure_channels(data)
    if channel is None:
        if not chans:
            raise AnalysisError("the export has no cylinder-pressure channel; variables: "
                                + ", ".join(map(str, data.data_vars)))
        channel = chans[0]
    elif channel not in chans:
        raise AnalysisError(f"channel={channel!r} is not a pressure channel of the export; "
                            f"pressure channels: {', '.join(chans) or 'none'}")
    span = float(data.attrs.get("cycle_deg", 720.0))
    strokes = engine.cycle if engine is not None else int(cycle or round(span / 180.0))
    if strokes not in (2, 4):
        raise AnalysisError(f"cycle={cycle!r} must be 2 or 4")
    if abs(span - 180.0 * strokes) > 1e-6:
        raise AnalysisError(f"the export's cycles span {span:g} deg, but the "
                            f"{'engine is' if engine is not None else 'analysis is for'} a "
                            f"{strokes}-stroke ({180 * strokes} deg per cycle); expected a "
                            f"{180 * strokes}-deg axis (a 360-deg export of a 4-stroke holds "
                            "only one revolution)")
    warnings = []
    var = data[channel]
    cyl = _checked_cylinder(engine, channel, cylinder if cylinder is not None
                            else var.attrs.get("cylinder"), warnings)
    axis = np.asarray(data["crank_angle"].values, float)
    p = np.asarray(var.values, float)
    if not np.all(np.isfinite(p)):
        raise AnalysisError(f"channel {channel!r} holds non-finite pressures")
    numbers = np.asarray(data["cycle"].values, np.int64)
    order = np.argsort(numbers, kind="stable")
    numbers, p = numbers[order], p[order]
    period = np.pi * strokes
    step = float(axis[1] - axis[0])
    n = axis.size
    psi = -period / 2 + np.arange(n) * step
    omega = None
    if "speed" in data.data_vars:
        omega = np.asarray(data["speed"].values, float)[order]
    elif speed_rpm is not None:
        if not speed_rpm > 0:
            raise AnalysisError(f"speed_rpm={speed_rpm!r} must be > 0")
        omega = np.full(numbers.size, float(speed_rpm) * TWO_PI / 60.0)
    timed = omega is not None and np.all(np.isfinite(omega)) and np.all(omega > 0)
    clock = omega if timed else np.ones(numbers.size)      # without speed: angle as the clock
    fire = float(np.deg2rad(engine.firing_angles_deg()[cyl - 1])) if engine is not None else 0.0
    given = firing_tdc_deg if firing_tdc_deg is not None else data.attrs.get("firing_tdc_deg")
    base0, phase_text = _firing_tdc(data, channel, p, axis, fire, period, given, warnings)
    reference = (f"crank-angle axis of the export ({data.attrs.get('raw_source', 'data')}, "
                 f"{data.attrs.get('layout', '')} layout, {np.rad2deg(step):g} deg step; its 0 "
                 "taken as a TDC)")
    runs = []
    starts = {}
    for a, b in _runs(numbers):
        theta, values, t = _continuous(p[a:b], axis, clock[a:b], lone=b - a == 1)
        t0 = float(np.sum(period / clock[:a])) if a else 0.0
        if timed and a:        # across a gap in the numbering: the missing cycles at the mean
            t0 = float((numbers[a] - numbers[0]) * period / np.mean(omega))
        runs.append((theta, values, t + t0, (axis[0], axis[0] + (b - a) * period),
                     numbers[a:b]))
    kept_numbers = []

    def cut(shift):
        parts = []
        kept_numbers.clear()
        for theta, values, t, (lo, hi), nums in runs:
            got = _cut(theta, values, t, base0 + shift, psi, period)
            if got[0].shape[0] == 0:
                continue
            centres = np.interp(got[1], t, theta)
            keep = (centres >= lo - 1e-9) & (centres < hi - 1e-9)
            parts.append(tuple(g[keep] for g in got))
            kept_numbers.extend(nums[np.clip(np.floor((centres[keep] - lo) / period)
                                             .astype(int), 0, nums.size - 1)])
        if not parts:
            raise AnalysisError(f"channel {channel!r} holds no whole {np.rad2deg(period):g}-deg "
                                "cycle around its firing TDC")
        return tuple(np.concatenate([q[i] for q in parts]) for i in range(4))

    result = _analyse_cycles(
        cut, engine=engine, psi=psi, strokes=strokes, channel=channel, cyl=cyl, has_tdc=True,
        search=None, reference=reference, phase_text=phase_text, warnings=warnings,
        tdc_correction=tdc_correction, max_cycles=max_cycles, peg=peg,
        peg_pressure=peg_pressure, peg_window_deg=peg_window_deg,
        polytropic_exponent=polytropic_exponent, tdc_window_deg=tdc_window_deg,
        loss_angle_deg=loss_angle_deg, gamma=gamma)
    count = result.n_cycles
    nan = np.full(count, np.nan)
    return dataclasses.replace(
        result, cycle_number=np.asarray(kept_numbers[:count], np.int64),
        cycle_time=result.cycle_time if timed else nan,
        speed_rpm=result.speed_rpm if timed else nan)
