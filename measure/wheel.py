"""Raw pulse channels decoded: a wheel (missing-tooth wheel, gear, encoder) or a TDC mark.

A test bench records the pick-up voltage, not edge times. :func:`decode_wheel` and
:func:`decode_marks` turn that voltage into the Record's pulse-train form (edge times on a
``pulse`` dim with ``pulses_per_rev``, ``missing_teeth``; see docs/DESIGN.md, data model), so
the speed reference and the crank angle (:mod:`measure.tacho`) work from it:

1. edges with levels adapted to the signal (:func:`measure.edges.find_edges`),
2. pitch counting with the wheel layout read from the pitch pattern
   (:func:`measure.tacho.count_pitches`, :mod:`measure.wheel_layout`),
3. where a tooth never gave a full edge but a runt pulse stands at its place in at least half
   of the revolutions, the runt's own half-height crossing is taken as that tooth's edge and
   the count is redone (the tooth is named in a warning, the decoding is right whichever side
   of the gap the runt is on),
4. for a TDC mark: the marks are one per revolution (or per cycle) — checked against the wheel
   when there is one (the wheel's angle between marks), else against their own spacing.

Every warning and error names the channel (``name``) and the numbers seen.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from crankbench.predict._validate import check_int
from crankbench.predict.errors import AnalysisError

from .edges import EdgeDetection, find_edges
from .record import RecordWarning

__all__ = ["DecodedPulses", "decode_wheel", "decode_marks", "edges_per_rev"]

#: share of revolutions in which a runt must stand at an empty tooth position to be taken
RUNT_SHARE = 0.5


@dataclass(frozen=True)
class DecodedPulses:
    """A raw pulse channel decoded into edge times.

    Attributes
    ----------
    edges : numpy.ndarray
        Edge times for the Record, s (spurious pulses removed, runt teeth included).
    role : str
        "wheel" or "tdc".
    pulses_per_rev : int
        Pitch positions per revolution of the wheel (1 for a mark).
    missing_teeth : int
        Declared or inferred.
    speed_ratio : float
        Turns of the pulse source per crankshaft turn (0.5 for a mark once per four-stroke
        cycle).
    revolutions : float
        Revolutions of the source the edges span.
    edges_per_rev : float
        Edges found per revolution (``pulses_per_rev - missing_teeth`` on a clean wheel).
    runt_teeth : tuple of int
        Teeth whose edges were taken from runt pulses (numbered from the first after the gap).
    lost_teeth : tuple of int
        Teeth that never gave an edge (bridged).
    notes : tuple of str
        Warnings raised while decoding (also issued as :class:`RecordWarning`).
    detection : EdgeDetection
        Levels, noise and runts of the edge detection.
    """

    edges: np.ndarray
    role: str
    pulses_per_rev: int
    missing_teeth: int
    speed_ratio: float
    revolutions: float
    edges_per_rev: float
    runt_teeth: tuple
    lost_teeth: tuple
    notes: tuple
    detection: EdgeDetection

    def attrs(self) -> dict:
        """Record channel attrs of the decoded pulse train.

        Examples
        --------
        >>> d = decode_wheel(np.sin(np.arange(4000) * 0.5), fs=1000.0, pulses_per_rev=4,
        ...                  missing_teeth=0)
        >>> sorted(d.attrs())[:4]
        ['decoding', 'missing_teeth', 'pulses_per_rev', 'role']
        """
        out = {"pulses_per_rev": int(self.pulses_per_rev),
               "missing_teeth": int(self.missing_teeth), "role": self.role}
        if self.speed_ratio != 1.0:
            out["speed_ratio"] = float(self.speed_ratio)
        if self.runt_teeth:
            out["runt_teeth"] = [int(k) for k in self.runt_teeth]
        if self.lost_teeth:
            out["lost_teeth"] = [int(k) for k in self.lost_teeth]
        det = self.detection
        out["decoding"] = (f"{det.level} level, hysteresis ±{det.hysteresis:.4g}, noise "
                           f"{det.noise_rms:.3g} rms, swing {det.swing:.4g} (signal units), "
                           f"envelope window {det.window_s:.4g} s; {self.edges.size} edges, "
                           f"{self.edges_per_rev:.2f} per revolution")
        return out


def _count(edges, ppr, missing, name):
    """count_pitches with its warnings collected (re-issued once by the caller)."""
    from .tacho import count_pitches

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            pc = count_pitches(edges, pulses_per_rev=ppr, missing_teeth=missing)
        except AnalysisError as exc:
            raise AnalysisError(f"{name}: {exc}") from None
    notes = [str(w.message).removeprefix("tacho: ") for w in caught
             if issubclass(w.category, RecordWarning)]
    return pc, notes


def _pitch_at(pc, times):
    """Fractional pitch number at ``times`` (linear between the edges around each)."""
    return np.interp(times, pc.edge_times, pc.pitch.astype(float))


def _runt_edges(pc, det_runts, ppr):
    """Runt times standing at tooth positions that never gave a full edge."""
    if det_runts.size == 0:
        return np.empty(0)
    inside = (det_runts > pc.edge_times[0]) & (det_runts < pc.edge_times[-1])
    runts = det_runts[inside]
    if runts.size == 0:
        return np.empty(0)
    frac = _pitch_at(pc, runts)
    k = np.rint(frac)
    near = np.abs(frac - k) < 0.3
    pos = np.mod(k.astype(np.int64), ppr)
    occupied = np.bincount(np.mod(pc.pitch, ppr), minlength=ppr) > 0
    keep = near & ~occupied[pos]
    if not keep.any():
        return np.empty(0)
    revs = (pc.pitch[-1] - pc.pitch[0]) / ppr
    per = np.bincount(pos[keep], minlength=ppr)
    good = per >= max(1.0, RUNT_SHARE * np.floor(revs))
    return np.sort(runts[keep & good[pos]])


def edges_per_rev(pitch, ppr):
    """Median number of edges in the record's complete revolutions (counted from pitch 0).

    Examples
    --------
    >>> p = np.arange(3, 400)
    >>> edges_per_rev(p[np.mod(p, 60) < 58], 60)
    58.0
    """
    if ppr == 1:
        return 1.0
    rev = np.floor_divide(pitch, ppr)
    complete = np.arange(rev[0] + 1, rev[-1])
    if complete.size == 0:
        return float((pitch.size - 1) * ppr / max(pitch[-1] - pitch[0], 1))
    counts = np.bincount(rev - rev[0])[complete - rev[0]]
    return float(np.median(counts))


def decode_wheel(signal, *, fs, pulses_per_rev, missing_teeth=None, t0=0.0, slope="rising",
                 level=None, hysteresis=None, name="wheel") -> DecodedPulses:
    """Decode a wheel's raw pick-up signal into edge times (missing-tooth wheel or encoder).

    Parameters
    ----------
    signal : array_like
        Pick-up voltage, uniformly sampled.
    fs : float
        Sample rate, Hz.
    pulses_per_rev : int
        Pitch positions per revolution, missing teeth included (60 for a 60-2 wheel, 360 for a
        360-line encoder).
    missing_teeth : int or None
        Teeth missing for the gap, 0 for an encoder; None infers it from the pitch pattern.
    t0 : float
        Time of the first sample, s.
    slope, level, hysteresis
        Edge detection (:func:`measure.edges.find_edges`).
    name : str
        Channel name for messages.

    Returns
    -------
    DecodedPulses

    Raises
    ------
    AnalysisError
        No pulses (noise only), too few edges, a gap that is not there or is ambiguous, too
        many faults to count — naming ``name`` and the numbers seen.

    Examples
    --------
    A 60-2 wheel at 1500 rpm on a square-wave pick-up whose last tooth before the gap is a
    runt reaching 11 % of the swing:

    >>> fs, pitch = 100_000.0, 1.0 / 1500.0
    >>> t = np.arange(int(0.5 * fs)) / fs
    >>> k = np.floor(t / pitch).astype(int)
    >>> tooth, phase = np.mod(k, 60), t / pitch - k
    >>> v = np.where((tooth < 58) & (phase < 0.5), 5.0, 0.0)
    >>> v[(tooth == 57) & (phase < 0.5)] = 0.55
    >>> import warnings
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     d = decode_wheel(v, fs=fs, pulses_per_rev=60, missing_teeth=2, name="crank")
    >>> d.runt_teeth, round(d.edges_per_rev, 3), d.missing_teeth
    ((57,), 58.0, 2)
    """
    ppr = check_int(pulses_per_rev, "pulses_per_rev", minimum=1, error=AnalysisError)
    try:
        det = find_edges(signal, fs=fs, slope=slope, level=level, hysteresis=hysteresis)
    except AnalysisError as exc:
        raise AnalysisError(f"{name}: {exc}") from None
    edges = det.edges + float(t0)
    if edges.size < 3:
        raise AnalysisError(f"{name}: {edges.size} edge(s) found in {len(signal) / fs:.4g} s "
                            f"(noise {det.noise_rms:.3g} rms); expected a pulse train of "
                            f"{ppr} pitches per revolution")
    pc, notes = _count(edges, ppr, missing_teeth, name)
    runt_teeth = ()
    if ppr > 1:
        extra = _runt_edges(pc, det.runt_times + float(t0), ppr)
        if extra.size:
            heights = det.runt_heights[np.isin(det.runt_times + float(t0), extra)]
            pc, notes = _count(np.sort(np.concatenate([pc.edge_times, extra])), ppr,
                               missing_teeth, name)
            teeth = sorted({int(k) for k in np.mod(np.rint(_pitch_at(pc, extra)), ppr)})
            runt_teeth = tuple(teeth)
            revs = (pc.pitch[-1] - pc.pitch[0]) / ppr
            notes.append(
                f"tooth {', '.join(map(str, teeth))} (counting the first after the gap as 0) "
                f"is a runt pulse: it reaches only {100 * float(np.median(heights)):.0f} % of "
                f"the swing, in {extra.size} of {revs:.0f} revolutions; its edges were taken at "
                "the runt's own half height (check the pick-up gap at that tooth)")
    revs = (pc.pitch[-1] - pc.pitch[0]) / ppr if ppr > 1 else float(pc.edge_times.size - 1)
    per_rev = edges_per_rev(pc.pitch, ppr)
    if pc.removed > 0.05 * pc.edge_times.size:
        notes.append(f"{pc.removed} spurious pulses removed ({100 * pc.removed / edges.size:.0f}"
                     " % of the edges): noise or ringing on the pick-up")
    for note in notes:
        warnings.warn(f"{name}: {note}", RecordWarning, stacklevel=2)
    return DecodedPulses(edges=pc.edge_times, role="wheel", pulses_per_rev=ppr,
                         missing_teeth=int(pc.missing_teeth), speed_ratio=1.0,
                         revolutions=float(revs), edges_per_rev=float(per_rev),
                         runt_teeth=runt_teeth, lost_teeth=tuple(
                             k for k in pc.lost_teeth if k not in runt_teeth),
                         notes=tuple(notes), detection=det)


def decode_marks(signal, *, fs, per_cycle=False, t0=0.0, slope="rising", level=None,
                 hysteresis=None, wheel=None, name="tdc") -> DecodedPulses:
    """Decode a TDC (or any once-per-revolution / per-cycle) mark into edge times.

    Parameters
    ----------
    signal : array_like
        Mark voltage, uniformly sampled (a mark may be one or two samples wide).
    fs : float
        Sample rate, Hz.
    per_cycle : bool
        One mark per four-stroke cycle (two revolutions) instead of one per revolution.
    t0 : float
        Time of the first sample, s.
    slope, level, hysteresis
        Edge detection (:func:`measure.edges.find_edges`).
    wheel : DecodedPulses, optional
        The decoded wheel of the same record: each interval between marks must span one
        revolution of it (two with ``per_cycle``).
    name : str
        Channel name for messages.

    Returns
    -------
    DecodedPulses
        ``pulses_per_rev = 1``; ``speed_ratio = 0.5`` for a per-cycle mark (it turns with the
        camshaft).

    Raises
    ------
    AnalysisError
        No marks, or marks that are not one per revolution (per cycle) — with the numbers of
        revolutions seen between them and the setting that would fit.

    Examples
    --------
    >>> fs = 50_000.0
    >>> x = np.zeros(int(fs))
    >>> x[np.rint(np.arange(0.01, 1.0, 0.05) * fs).astype(int)] = 1.0   # 1200 rpm, 1 sample
    >>> d = decode_marks(x, fs=fs)
    >>> d.edges.size, round(float(np.median(np.diff(d.edges))), 6)
    (20, 0.05)
    """
    try:
        det = find_edges(signal, fs=fs, slope=slope, level=level, hysteresis=hysteresis)
    except AnalysisError as exc:
        raise AnalysisError(f"{name}: {exc}") from None
    edges = det.edges + float(t0)
    per = 2.0 if per_cycle else 1.0
    unit = "cycle" if per_cycle else "revolution"
    if edges.size < 2:
        raise AnalysisError(f"{name}: {edges.size} mark(s) found in {len(signal) / fs:.4g} s; "
                            f"expected one per {unit} (at least two to use them)")
    notes = []
    if wheel is not None:
        from .tacho import count_pitches

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            pc = count_pitches(wheel.edges, pulses_per_rev=wheel.pulses_per_rev,
                               missing_teeth=wheel.missing_teeth)
        inside = edges[(edges > pc.edge_times[0]) & (edges < pc.edge_times[-1])]
        if inside.size >= 2:
            revs = np.diff(_pitch_at(pc, inside)) / pc.pulses_per_rev * wheel.speed_ratio
            bad = np.abs(revs - per) > 0.1 * per
            if bad.mean() > 0.5:
                typical = float(np.median(revs))
                hint = ("set per_cycle = true" if abs(typical - 2.0) < 0.2 and not per_cycle
                        else "set per_cycle = false" if abs(typical - 1.0) < 0.1 else
                        "check the channel and the wheel's pulses_per_rev")
                raise AnalysisError(
                    f"{name}: {int(bad.sum())} of {revs.size} intervals between marks are not "
                    f"one {unit} of the wheel (median {typical:.3g} revolutions between marks)"
                    f"; {hint}")
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                notes.append(f"{int(bad.sum())} of {revs.size} intervals between marks are not "
                             f"one {unit} of the wheel (first at {inside[i]:.6g} s: "
                             f"{revs[i]:.3g} revolutions): missed or spurious marks")
    else:
        dt = np.diff(edges)
        ratio = dt / np.median(dt)
        odd = np.abs(ratio - np.rint(ratio)) > 0.2
        if odd.mean() > 0.2 and edges.size >= 5:
            raise AnalysisError(f"{name}: {int(odd.sum())} of {dt.size} intervals between "
                                "marks are not whole multiples of the typical interval "
                                f"({float(np.median(dt)):.4g} s): not a once-per-{unit} mark "
                                "(noise, or several marks per revolution?)")
    for note in notes:
        warnings.warn(f"{name}: {note}", RecordWarning, stacklevel=2)
    return DecodedPulses(edges=edges, role="tdc", pulses_per_rev=1, missing_teeth=0,
                         speed_ratio=0.5 if per_cycle else 1.0,
                         revolutions=float(edges.size - 1) * per, edges_per_rev=1.0 / per,
                         runt_teeth=(), lost_teeth=(), notes=tuple(notes), detection=det)
