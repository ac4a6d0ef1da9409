"""Where the gap of a pulse wheel is, and how wide: read from which pitch positions hold edges.

Once each interval between edges is counted in pitches (:func:`measure.tacho.count_pitches`),
every edge has a provisional pitch number and so a wheel position ``pitch mod N``. A tooth
gives an edge at its position in every revolution but for the odd dropout; the gap of a
missing-tooth wheel gives none, ever. So the gap is the stretch of positions that the record
passes over and never finds an edge at, and the number of passes (its *support*) says how sure
that is: a double dropout leaves two positions empty once; the gap of a 26-revolution record
is empty 26 times. This is robust where the position of the longest intervals is not:

* a tooth next to the gap that never fires (a runt pulse below the trigger) widens the empty
  stretch by one, at the same wheel position every revolution: recognised, decoded with that
  tooth bridged, and named in a warning — or, if the stretch is wider than one lost tooth,
  refused with the numbers seen;
* a double dropout in a record of 1–2 revolutions, which empties two positions as the gap
  does, can only tie with the gap when each was passed the same number of times: then no
  guess is made (an error says so) — the gap is never chosen by array order;
* with ``missing_teeth`` unknown, the width of the consistently empty stretch is the layout;
* teeth that stay silent elsewhere on the wheel, and dropouts piling up at one position (a
  weak tooth), are named in a warning instead of being bridged quietly as random dropouts.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from crankbench.predict.errors import AnalysisError

__all__ = ["GapLayout", "locate_gap", "empty_runs"]

log = logging.getLogger("crankbench")


@dataclass(frozen=True)
class GapLayout:
    """The wheel layout read from the pitch pattern.

    Attributes
    ----------
    phase : int or None
        Provisional wheel position (``pitch mod N``) of the first tooth after the gap (None for
        a wheel without gap).
    missing_teeth : int
        Teeth missing to form the gap (declared or inferred).
    width : int
        Consecutive positions never holding an edge at the gap (``missing_teeth`` plus lost
        teeth beside it).
    lost : tuple of int
        Teeth, numbered from the first tooth after the gap (0 .. N-1), that gave no edge in any
        revolution the record passes (bridged).
    notes : tuple of str
        Warnings (lost or weak teeth, an unusual inferred layout).
    """

    phase: int | None
    missing_teeth: int
    width: int
    lost: tuple = ()
    notes: tuple = ()


def empty_runs(pitch, n_rev):
    """Stretches of wheel positions the edges never occupy, with how often each was passed.

    Parameters
    ----------
    pitch : array_like of int
        Provisional pitch number of each edge, increasing.
    n_rev : int
        Pitch positions per revolution.

    Returns
    -------
    list of (start, length, support)
        ``start`` position (mod N), ``length`` positions, ``support`` = the fewest passes over
        any of its positions (every pass found no edge). Longest support first.

    Examples
    --------
    >>> p = np.arange(0, 300)
    >>> p = p[np.mod(p, 60) < 58]                          # a 60-2 wheel, 5 revolutions
    >>> empty_runs(p, 60)
    [(58, 2, 4)]
    """
    pitch = np.asarray(pitch, dtype=np.int64)
    n = int(n_rev)
    pos = np.mod(pitch, n)
    occ = np.bincount(pos, minlength=n)
    span = int(pitch[-1] - pitch[0]) + 1
    full, rem = divmod(span, n)
    cov = full + (np.mod(np.arange(n) - pitch[0], n) < rem)
    empty = (occ == 0) & (cov > 0)
    if not empty.any() or empty.all():
        return []
    # circular runs: rotate so position 0 of the scan is occupied
    first_occ = int(np.flatnonzero(~empty)[0])
    order = np.mod(np.arange(n) + first_occ, n)
    e = empty[order].astype(np.int8)
    d = np.diff(np.concatenate(([0], e, [0])))
    runs = []
    for a, b in zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)):
        members = order[a:b]
        runs.append((int(order[a]), int(b - a), int(cov[members].min())))
    runs.sort(key=lambda r: (-r[2], -r[1], r[0]))
    return runs


def _positions(start, length, n):
    return [(start + i) % n for i in range(length)]


def _passes(k):
    return f"{k} time{'s' if k != 1 else ''}"


def locate_gap(pitch, counts, *, pulses_per_rev, missing_teeth, n_edges):
    """Locate (and, with ``missing_teeth=None``, size) the gap of a wheel from its edges.

    Parameters
    ----------
    pitch : numpy.ndarray of int
        Provisional pitch number of each edge (first edge 0).
    counts : numpy.ndarray of int
        Pitches counted in each interval (``diff(pitch)``).
    pulses_per_rev : int
        Pitch positions per revolution, N (> 1).
    missing_teeth : int or None
        Declared gap (> 0), 0 for a wheel without gap (then only consistently silent teeth are
        reported), or None to infer it.
    n_edges : int
        Number of edges (for messages).

    Returns
    -------
    GapLayout

    Raises
    ------
    AnalysisError
        No stretch wide enough for the declared gap, one much wider (teeth lost beside it or
        a wrong ``missing_teeth``), two candidates passed equally often (a record too short
        to tell the gap from dropouts), or a layout that cannot be inferred — naming what was
        seen.

    Examples
    --------
    A 60-2 wheel whose last tooth before the gap is a runt (never triggers):

    >>> p = np.arange(0, 600)
    >>> p = p[np.mod(p, 60) < 57]
    >>> lay = locate_gap(p, np.diff(p), pulses_per_rev=60, missing_teeth=2, n_edges=p.size)
    >>> lay.phase, lay.width, lay.lost
    (0, 3, (57,))
    """
    n = int(pulses_per_rev)
    m = missing_teeth
    revs = (int(pitch[-1]) - int(pitch[0]) + 1) / n
    runs = empty_runs(pitch, n)
    notes = []
    seen = f"{n_edges} edges, {revs:.1f} revolutions of a {n}-pitch wheel"
    if m == 0:
        silent = [r for r in runs if r[2] >= 3 and r[2] >= 0.8 * revs]
        lost = []
        for s, length, sup in silent:
            lost += _positions(s, length, n)
            where = ", ".join(str(p) for p in _positions(s, length, n))
            notes.append(f"pitch position(s) {where} (counted from the first edge) give no "
                         f"edge in any of the {sup} revolutions passing them: the wheel has a "
                         f"gap (missing_teeth={length}?) or lost teeth; bridged as dropouts")
        return GapLayout(phase=None, missing_teeth=0, width=0, lost=tuple(sorted(lost)),
                         notes=tuple(notes))
    if m is None:
        consistent = [r for r in runs if r[2] >= 2]
        if not consistent:
            if revs >= 2.0:
                log.info("tacho: missing_teeth inferred as 0: every pitch position has edges "
                         "(%s)", seen)
                return GapLayout(phase=None, missing_teeth=0, width=0)
            raise AnalysisError(f"cannot infer the wheel layout from {seen}: every pitch "
                                "position must be passed at least twice to tell a gap from a "
                                "dropout; give missing_teeth")
        if len(consistent) > 1:
            text = "; ".join(f"{length} at position {s} (passed {_passes(sup)})"
                             for s, length, sup in consistent[:4])
            raise AnalysisError(f"cannot infer the wheel layout from {seen}: "
                                f"{len(consistent)} stretches of pitch positions never hold an "
                                f"edge ({text}); a wheel with several gaps, or a wrong "
                                "pulses_per_rev; give missing_teeth")
        s, width, sup = consistent[0]
        m = width
        if m >= 3 or m > n // 4:
            notes.append(f"missing_teeth inferred as {m} (a {n}-{m} wheel, gap passed "
                         f"{sup} times): unusual — a {n}-{m - 1} wheel whose tooth next to "
                         f"the gap never triggers reads the same; set missing_teeth={m - 1} "
                         "if that is the wheel")
        return GapLayout(phase=(s + width) % n, missing_teeth=m, width=width,
                         notes=tuple(notes))
    # declared gap of m teeth
    cands = [r for r in runs if r[1] >= m]
    if not cands:
        if revs < 1.0:
            raise AnalysisError(f"no gap of {m} missing teeth found in {seen}: the record "
                                "must span at least one full revolution of the wheel")
        widest = max(runs, key=lambda r: (r[1], r[2]), default=None)
        if widest is None or widest[2] < 2:
            raise AnalysisError(
                f"no gap of {m} missing teeth found in {seen}: every pitch position holds "
                "edges (a plain wheel or encoder: missing_teeth=0?, or a wrong "
                "pulses_per_rev)")
        s, width, sup = widest
        raise AnalysisError(
            f"no gap of {m} missing teeth found in {seen}: the widest stretch without edges "
            f"is {width} pitch(es) at one wheel position (passed {_passes(sup)}), i.e. "
            f"intervals of {width + 1} pitches where a {n}-{m} wheel has {m + 1}: "
            f"missing_teeth is {width}?")
    best = cands[0]
    rivals = [r for r in cands[1:] if r[2] == best[2]]
    if rivals:
        where = ", ".join(f"positions {s}..{(s + w - 1) % n}" for s, w, _ in [best] + rivals)
        raise AnalysisError(
            f"cannot tell the gap of {m} missing teeth from dropped pulses in {seen}: "
            f"{1 + len(rivals)} stretches of at least {m} empty pitch positions ({where}) "
            f"were each passed {_passes(best[2])} without an edge; the record is too short "
            "(or too damaged) to locate the gap — use a longer record")
    s, width, sup = best
    extra = width - m
    if extra >= 2:
        raise AnalysisError(
            f"{sup} intervals of {width + 1} pitches at one wheel position, where a "
            f"{n}-{m} wheel has a gap of {m + 1} pitches ({seen}): {extra} teeth next to the "
            f"gap are lost, or missing_teeth is {width}")
    lost = []
    if extra == 1:
        lost = [n - m - 1]
        notes.append(
            f"{sup} intervals of {width + 1} pitches at one wheel position where a {n}-{m} "
            f"wheel has {m + 1}: tooth {n - m - 1} (the last before the gap, counting the "
            f"first after it as 0) gives no edge in any of the {sup} revolutions (a runt "
            f"pulse?) — decoded with it bridged; if the wheel has {width} missing teeth set "
            f"missing_teeth={width}; if it is the first tooth after the gap that is lost, "
            f"angles are one pitch ({360.0 / n:g}°) early")
    phase = (s + width) % n
    for rs, length, rsup in runs:
        if (rs, length) == (s, width) or rsup < 3 or rsup < 0.8 * revs:
            continue
        teeth = [(p - phase) % n for p in _positions(rs, length, n)]
        lost += teeth
        notes.append(f"tooth {', '.join(map(str, teeth))} (counting the first after the gap "
                     f"as 0) gives no edge in any of the {rsup} revolutions passing it "
                     "(broken or runt tooth?); bridged")
    return GapLayout(phase=phase, missing_teeth=m, width=width, lost=tuple(sorted(lost)),
                     notes=tuple(notes))
