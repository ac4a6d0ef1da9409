"""Crank angle of a record for the indicator analysis: pulses, TDC marks, phase, cycles.

Helpers of :mod:`analysis.pressure`: which channel is the wheel/encoder and which the TDC mark
(:func:`find_channels`), crank angle against time with its zero on the TDC marks (the circular
mean of every mark, so the half-sample timing error of a narrow mark averages out), the
4-stroke phase (from a cam/phase mark or the pressure), and the cut of the pressure record
into cycles on an even crank-angle grid (4-point Lagrange interpolation between samples,
error O((Δθ)⁴ p⁗) for sample spacing Δθ).
"""

from __future__ import annotations

import logging
import re

import numpy as np

from crankbench.predict.errors import AnalysisError, RecordError

__all__ = ["find_channels"]

log = logging.getLogger("crankbench")

TWO_PI = 2.0 * np.pi
DEG = np.pi / 180.0
BAR = 1.0e5
_TDC_NAMES = re.compile(r"(^|[^a-z])(tdc|ot|trigger|index|ref|zero|mark)([^a-z]|$)", re.I)
_PHASE_NAMES = re.compile(r"(cam|phase|sync|cmp|nw)", re.I)


def find_channels(record) -> dict:
    """Crank-angle and TDC-mark candidates of a record, best first.

    Examples
    --------
    >>> from crankbench.measure.record import make_record
    >>> rec = make_record({"crank": dict(data=np.arange(10) / 600.0, quantity="pulse_times",
    ...                                  units="s", pulses_per_rev=60),
    ...                    "tdc": dict(data=np.arange(3) / 10.0, quantity="pulse_times",
    ...                                units="s", pulses_per_rev=1)})
    >>> find_channels(rec)
    {'angle': ['crank'], 'tdc': ['tdc']}
    """
    names = [str(n) for n in record.data_vars]
    return {"angle": _find(record, names, "angle"), "tdc": _find(record, names, "tdc")}


def _pulse_info(var):
    ppr = var.attrs.get("pulses_per_rev")
    return None if ppr is None else (int(ppr), int(var.attrs.get("missing_teeth", 0)))


def _edges(record, name):
    """Edge times (s) of a pulse channel, or detected from its voltage."""
    from crankbench.measure.record import channel_time

    var = record[name]
    if var.attrs.get("quantity") == "pulse_times":
        return np.asarray(var.values, float)
    from crankbench.measure.tacho import detect_edges

    t = channel_time(record, name)
    fs = float(var.attrs.get("sample_rate", 1.0 / np.median(np.diff(t[:1000]))))
    return t[0] + detect_edges(np.asarray(var.values, float), fs=fs)


def _mark_times(record, name):
    """Times of once-per-revolution (or once-per-cycle) marks: edges, or narrow pulses."""
    from crankbench.measure.record import channel_time

    var = record[name]
    if var.attrs.get("quantity") == "pulse_times":
        return np.asarray(var.values, float)
    x = np.asarray(var.values, float)
    t = channel_time(record, name)
    lo, hi, med = np.min(x), np.max(x), np.median(x)
    if not hi > lo:
        raise RecordError(f"mark channel {name!r} is constant; no marks in it")
    mid = 0.5 * (lo + hi)
    y = x - mid if med < mid else mid - x          # pulses away from the resting level
    i = np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0)) + 1
    if i.size == 0:
        raise RecordError(f"mark channel {name!r}: no pulse crosses the mid level")
    frac = -y[i - 1] / (y[i] - y[i - 1])
    times = t[i - 1] + frac * (t[i] - t[i - 1])
    if times.size > 2:                             # one mark per pulse: drop bounces
        gap = np.median(np.diff(times))
        keep = np.concatenate([[True], np.diff(times) > 0.5 * gap])
        times = times[keep]
    return times


def _find(record, names, want):
    """Channels for a role among ``names``, best first.

    ``angle``: pulse trains (then pick-up/encoder voltages) with pulses_per_rev > 1, most
    pulses first. ``tdc``: a channel with ``role = "tdc"`` (a decoded channel-map mark), then
    once-per-revolution pulse trains not named like a cam/phase signal, then voltage/other
    channels named like a TDC mark (tdc, ot, trigger, index, ref, zero, mark).
    """
    out = []
    for n in names:
        var = record[n]
        info = _pulse_info(var)
        q = var.attrs.get("quantity")
        role = var.attrs.get("role")
        pulses = q == "pulse_times"
        if want == "angle":
            if info and info[0] > 1 and q in ("pulse_times", "voltage") and role != "tdc":
                out.append(((-info[0], 0 if pulses else 1), n))
        elif role == "tdc":
            out.append(((0, 0), n))
        elif info and info[0] == 1 and not _PHASE_NAMES.search(n):
            out.append(((1, 0 if pulses else 1), n))
        elif info is None and q in ("pulse_times", "voltage", "other") and _TDC_NAMES.search(n):
            out.append(((2, 0), n))
    return [n for _, n in sorted(out)]


def _angle(record, *, angle_channel, tdc_channel, tdc_offset_deg, marks_out=None):
    """AngleTrace, a description of its zero, and whether that zero is a TDC.

    ``marks_out`` (a dict), when given, receives ``name`` and ``times`` (s) of the TDC-mark
    channel used, if any.
    """
    from crankbench.measure.tacho import angle_from_pulses

    names = [str(n) for n in record.data_vars]
    if angle_channel is None:
        cands = _find(record, names, "angle") or _crank_angle_channels(record, names)
        if not cands:
            raise AnalysisError("no crank-angle source: the record has no pulse train or "
                                "pick-up/encoder voltage with pulses_per_rev > 1 and no "
                                "crank-angle channel; channels: "
                                f"{', '.join(names)} (set pulses_per_rev with the import "
                                "channel map, or pass angle_channel=)")
        angle_channel = cands[0]
    elif angle_channel not in record.data_vars:
        raise AnalysisError(f"angle_channel={angle_channel!r} is not a channel of the record; "
                            f"channels: {', '.join(names)}")
    if _pulse_info(record[angle_channel]) is None and \
            record[angle_channel].attrs.get("quantity") == "angle":
        return _crank_angle_trace(record, angle_channel)
    info = _pulse_info(record[angle_channel])
    if info is None:
        raise AnalysisError(f"angle channel {angle_channel!r} has no pulses_per_rev attr")
    ppr, missing = info
    edges = _edges(record, angle_channel)
    if tdc_channel is None:
        cands = [n for n in _find(record, names, "tdc") if n != angle_channel]
        tdc_channel = cands[0] if cands else None
    given = tdc_offset_deg
    if tdc_channel is not None:
        marks = _mark_times(record, tdc_channel)
        if marks_out is not None:
            marks_out.update(name=tdc_channel, times=marks)
        off = 0.0 if given is None else float(given)
        trace = _referenced(angle_from_pulses(edges, pulses_per_rev=ppr, missing_teeth=missing),
                            marks, off, tdc_channel)
        return trace, (f"TDC mark channel {tdc_channel!r}" + (f" + {off:g} deg" if off else "")
                       + f"; angle from {angle_channel!r} ({ppr}-{missing} pulses/rev)"), True
    gap = _gap_reference(record, names, angle_channel, given)
    if gap is not None:
        g, g_off, marks = gap
        trace = _referenced(angle_from_pulses(edges, pulses_per_rev=ppr, missing_teeth=missing),
                            marks, 0.0, g)
        return trace, (f"TDC {g_off:g} deg after the gap of {g!r}; angle from "
                       f"{angle_channel!r} ({ppr}-{missing} pulses/rev)"), True
    attr = record[angle_channel].attrs.get("tdc_offset_deg")
    off = given if given is not None else attr
    if off is not None and (missing or given is not None):
        trace = angle_from_pulses(edges, pulses_per_rev=ppr, missing_teeth=missing,
                                  tdc_offset_deg=float(off))
        where = "the wheel gap" if missing else "the first edge"
        return trace, (f"{where} of {angle_channel!r} ({ppr}-{missing}), TDC {float(off):g} "
                       "deg after it"), True
    trace = angle_from_pulses(edges, pulses_per_rev=ppr, missing_teeth=missing)
    return trace, f"no TDC reference; angle from {angle_channel!r} ({ppr}-{missing})", False


def _crank_angle_channels(record, names):
    """Sampled crank-angle channels (an indicating system's export): quantity 'angle' spanning
    more than 300° (a torsiograph's vibration angle spans far less)."""
    out = []
    for n in names:
        var = record[n]
        if var.attrs.get("quantity") != "angle" or _pulse_info(var) is not None:
            continue
        x = np.asarray(var.values, float)
        if x.size > 16 and np.nanmax(x) - np.nanmin(x) > 300 * DEG:
            out.append(n)
    return out


def _crank_angle_trace(record, name):
    """AngleTrace of a sampled crank-angle channel, 0 at TDC as exported, unwrapped."""
    from crankbench.measure.record import channel_time
    from crankbench.measure.tacho import AngleTrace

    x = np.asarray(record[name].values, float)
    t = channel_time(record, name)
    ok = np.isfinite(x)
    x, t = x[ok], t[ok]
    span = float(x.max() - x.min())
    period = 4 * np.pi if span > 1.1 * TWO_PI else TWO_PI       # 720° or 360° sawtooth
    d = np.diff(x)
    wraps = d < -0.5 * span
    angle = x + period * np.concatenate([[0], np.cumsum(wraps)])
    step = np.diff(angle)
    if np.mean(step > 0) < 0.99 or np.any(step < -2 * DEG):
        raise AnalysisError(f"crank-angle channel {name!r} does not increase steadily (wraps at "
                            f"{np.rad2deg(period):g} deg taken out); expected a sawtooth or a "
                            "cumulative angle")
    keep = np.concatenate([[True], step > 0])               # repeated values carry no time
    trace = AngleTrace(time=t[keep], angle=angle[keep], pulses_per_rev=0,
                       reference="crank-angle channel", tdc_offset=0.0)
    return trace, (f"crank-angle channel {name!r} (its 0 taken as TDC of cylinder 1, wrapping "
                   f"every {np.rad2deg(period):g} deg)"), True


def _gap_reference(record, names, angle_channel, given):
    """TDC times from another channel's wheel gap, when the angle channel has no gap.

    A finer encoder without a reference gives the angle; a missing-tooth wheel with a known TDC
    offset (``given`` or its ``tdc_offset_deg`` attr) gives the zero: its TDC instants become
    the marks. None when the angle channel has its own gap or no such wheel exists.
    """
    from crankbench.measure.tacho import angle_from_pulses

    if (_pulse_info(record[angle_channel]) or (0, 0))[1]:
        return None
    for g in _find(record, names, "angle"):
        info = _pulse_info(record[g])
        off = given if given is not None else record[g].attrs.get("tdc_offset_deg")
        if g == angle_channel or not info[1] or off is None:
            continue
        tr = angle_from_pulses(_edges(record, g), pulses_per_rev=info[0], missing_teeth=info[1],
                               tdc_offset_deg=float(off))
        k = np.arange(np.ceil(tr.angle[0] / TWO_PI), np.floor(tr.angle[-1] / TWO_PI) + 1)
        if k.size:
            return g, float(off), np.interp(k * TWO_PI, tr.angle, tr.time)
    return None


def _referenced(trace, marks, offset_deg, name):
    """Move the zero of ``trace`` to the TDC marks: their circular mean angle (mod 2π).

    Averaging over every mark in the record removes the timing error of a single mark (a
    mark two samples wide is located to about half a sample); the spread of the marks is
    checked (a warning above 1°: a slipping or noisy mark).
    """
    from crankbench.measure.tacho import AngleTrace

    inside = marks[(marks >= trace.time[0]) & (marks <= trace.time[-1])]
    if inside.size == 0:
        raise AnalysisError(f"TDC channel {name!r}: no mark falls within the pulse train "
                            f"[{trace.time[0]:g}, {trace.time[-1]:g}] s")
    z = np.exp(1j * trace.at(inside))
    ref = float(np.angle(np.mean(z)))
    spread = np.angle(z * np.exp(-1j * ref))
    if inside.size > 1 and np.max(np.abs(spread)) > DEG:
        log.warning("TDC channel %r: marks spread by %.2f deg (largest deviation); using their "
                    "mean", name, np.rad2deg(np.max(np.abs(spread))))
    tdc = ref + np.deg2rad(offset_deg)
    return AngleTrace(time=trace.time, angle=trace.angle - tdc, pulses_per_rev=trace.pulses_per_rev,
                      reference="reference mark", tdc_offset=float(np.deg2rad(offset_deg)))


# ------------------------------------------------------------------------------ resampling
def _lagrange4(values, u):
    """Cubic (4-point Lagrange) interpolation of evenly sampled ``values`` at fractional index u."""
    n = values.size
    i = np.clip(np.floor(u).astype(np.int64), 1, n - 3)
    f = u - i
    return (values[i - 1] * (-f * (f - 1) * (f - 2) / 6) + values[i] * ((f + 1) * (f - 1)
            * (f - 2) / 2) + values[i + 1] * (-(f + 1) * f * (f - 2) / 2)
            + values[i + 2] * ((f + 1) * f * (f - 1) / 6))


def _cut(theta, p, t, base, psi, period):
    """Cycles of ``p`` on the grid ``psi`` around firing TDCs at ``base + k period``."""
    first = int(np.ceil((theta[0] - psi[0] - base) / period - 1e-9))
    last = int(np.floor((theta[-1] - (psi[-1] + (psi[1] - psi[0])) - base) / period + 1e-9))
    if last < first:
        return np.empty((0, psi.size)), np.empty(0), np.empty(0), np.empty((0, psi.size))
    centres = base + np.arange(first, last + 1) * period
    cycles = np.empty((centres.size, psi.size))
    t_grid = np.empty_like(cycles)
    index = np.arange(theta.size, dtype=float)
    for a in range(0, centres.size, 64):             # bounded temporaries on long records
        target = centres[a:a + 64, None] + psi[None, :]
        u = np.interp(target.ravel(), theta, index)
        cycles[a:a + 64] = _lagrange4(p, u).reshape(target.shape)
        t_grid[a:a + 64] = np.interp(target.ravel(), theta, t).reshape(target.shape)
    t_c = np.interp(centres, theta, t)
    t0 = np.interp(centres + psi[0], theta, t)
    t1 = np.interp(centres - psi[0], theta, t)
    rpm = period / TWO_PI * 60.0 / (t1 - t0)
    return cycles, t_c, rpm, t_grid


def _phase(theta, p, cyl_offset, period, phase_marks, record_name):
    """Angle (rad, in θ) of one firing TDC of the cylinder, and how it was chosen."""
    cands = [cyl_offset, cyl_offset + TWO_PI] if period > TWO_PI + 1e-9 else [cyl_offset]
    if len(cands) == 1:
        return cands[0], "2-stroke: every TDC fires"
    if phase_marks is not None:
        # firing TDC of cylinder 1 = first TDC (multiple of 2π) at or after a phase mark (or
        # the one it sits on, within 30°); the
        # parity (which of the two TDCs of a cycle) is taken by majority over all marks
        if phase_marks.size == 0:
            raise AnalysisError(f"phase channel {record_name!r}: no mark within the pulse train")
        # a mark on a TDC (within 30°, timing noise either side) counts as that TDC
        parity = np.mod(np.ceil(phase_marks / TWO_PI - 30.0 / 360.0).astype(np.int64), 2)
        odd = float(np.mean(parity))
        if 0.1 < odd < 0.9:
            log.warning("phase channel %r: marks disagree on the firing TDC (%.0f%% one way)",
                        record_name, 100 * max(odd, 1 - odd))
        return int(odd > 0.5) * TWO_PI + cyl_offset, \
            f"phase channel {record_name!r}: firing TDC of cylinder 1 is the first TDC at or " \
            "after each mark"
    means = _tdc_means(theta, p, cands, period)
    k = int(np.argmax(means))
    other = means[1 - k]
    text = (f"from the pressure: mean {means[k] / BAR:.3g} bar within ±30 deg of the chosen "
            f"TDC against {other / BAR:.3g} bar at the other")
    return cands[k], text


def _tdc_means(theta, p, cands, period):
    """Mean pressure within ±30° of each candidate TDC (rad, in θ), Pa."""
    means = []
    for c in cands:
        rel = np.mod(theta - c + period / 2, period) - period / 2
        sel = np.abs(rel) <= 30 * DEG
        means.append(float(np.mean(p[sel])) if sel.any() else -np.inf)
    return means


#: the pressure decides the firing TDC of a 4-stroke only when the mean pressure within ±30°
#: of one TDC exceeds the other's by this factor (a compression alone gives 5-20)
PHASE_CONTRAST = 1.25


def _cycle_mark_phase(theta, p, base, cyl_offset, period, mark_angles, name, warnings):
    """Firing TDC of a 4-stroke checked against a once-per-cycle TDC mark.

    ``mark_angles``: crank angles (rad, in θ) of the TDC marks. When they come once per cycle
    (spacing 720°) their relation to the firing TDC chosen from the pressure is stated (at
    the firing TDC, or at the gas-exchange TDC 360° away); when the pressure cannot tell the
    two TDCs apart (contrast below :data:`PHASE_CONTRAST`) the marks are taken as the firing
    TDC of cylinder 1 (stated, with a warning). With once-per-revolution marks and such a
    pressure the choice is flagged as a guess. Returns ``(base, text)`` to append to the
    phase description ("" when there is nothing to add).
    """
    if period <= TWO_PI + 1e-9:
        return base, ""
    cands = [cyl_offset, cyl_offset + TWO_PI]
    means = _tdc_means(theta, p, cands, period)
    lo, hi = sorted(means)
    clear = lo > 0 and hi >= PHASE_CONTRAST * lo
    per_cycle = mark_angles is not None and mark_angles.size >= 2 and abs(
        np.median(np.diff(mark_angles)) - 2 * TWO_PI) < 0.25 * TWO_PI
    if per_cycle:
        # which of cylinder 1's two TDCs of the cycle (θ = 0 or 2π mod 4π) the marks sit on
        parity = np.mod(np.rint(mark_angles / TWO_PI).astype(np.int64), 2)
        odd = int(np.mean(parity) > 0.5)
        if 0.1 < float(np.mean(parity)) < 0.9:
            warnings.append(f"TDC mark {name!r}: its once-per-cycle marks fall on both TDCs of "
                            "the cycle (a slipping cam or a once-per-revolution mark with "
                            "dropouts); the majority is used")
        mark_tdc = cyl_offset + odd * TWO_PI
        if not clear:
            warnings.append(
                f"the pressure does not tell the firing TDC from the gas-exchange TDC (mean "
                f"{hi / BAR:.3g} against {lo / BAR:.3g} bar within ±30 deg); the once-per-cycle "
                f"TDC mark {name!r} is taken as the firing TDC of cylinder 1 (give "
                "phase_channel= for a cam/phase mark if it is not)")
            return mark_tdc, (f"; pressure inconclusive: the once-per-cycle mark {name!r} taken "
                              "as the firing TDC of cylinder 1")
        same = abs(np.mod(base - mark_tdc + period / 2, period) - period / 2) < 0.5 * TWO_PI
        where = "on the firing TDC" if same else "on the gas-exchange TDC, 360 deg from firing"
        return base, f"; the once-per-cycle TDC mark {name!r} sits {where} of cylinder 1"
    if not clear:
        warnings.append(f"the pressure does not tell the firing TDC from the gas-exchange TDC "
                        f"(mean {hi / BAR:.3g} against {lo / BAR:.3g} bar within ±30 deg) and "
                        "there is no once-per-cycle mark: the 4-stroke phase is a guess; give "
                        "phase_channel= (a cam/phase mark)")
        return base, "; inconclusive (see the warnings)"
    return base, ""


def _coarse_tdc(theta, p, period):
    """Angle (mod period) of the highest mean pressure in 1-degree bins."""
    nb = int(round(period / DEG))
    b = np.mod(np.floor(np.mod(theta, period) / DEG).astype(np.int64), nb)
    s = np.bincount(b, weights=p, minlength=nb)
    c = np.bincount(b, minlength=nb)
    mean = np.where(c > 0, s / np.maximum(c, 1), -np.inf)
    return (int(np.argmax(mean)) + 0.5) * DEG
