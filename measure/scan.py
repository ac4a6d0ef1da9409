"""Scans of a channel's samples for the Record checks: NaN/inf spans and clipping.

Both checks read every sample. :func:`shared_scans` lets them share one cache-friendly pass of
per-block minimum and maximum (NaN and inf propagate through both) -- or none, where a reader
took those extremes while the samples were still in cache from the file
(:func:`note_block_extremes`, :mod:`measure.readers._h5raw`). The record's validator
(:func:`measure.record.validate`) and :func:`measure.io.read` use them; they are re-exported by
:mod:`measure.record`.
"""

from __future__ import annotations

import contextlib
import functools
import math
import os
import sys
import threading

import numpy as np

__all__ = ["shared_scans", "note_block_extremes", "BlockExtremes", "nonfinite_spans",
           "clipped_spans", "CLIP_QUANTITIES"]


#: samples per block of the cache-friendly scans below (128 KB of float64: numpy's min and max
#: of a block read it from memory once; the clipping check compares only the blocks holding an
#: extreme, 2 x 16 k samples in the usual record instead of 2 x 131 k with blocks of 2**17)
_SCAN_BLOCK = 1 << 14


_SCAN_CACHE = threading.local()


@contextlib.contextmanager
def shared_scans():
    """Within the block, :func:`nonfinite_spans` and :func:`clipped_spans` share one scan of
    each array (``measure.read`` validates, then flags clipping, on samples nobody changes in
    between). Per thread; forgotten on exit."""
    outer = getattr(_SCAN_CACHE, "table", None)
    _SCAN_CACHE.table = {} if outer is None else outer
    try:
        yield
    finally:
        if outer is None:
            _SCAN_CACHE.table = None


def _scan_key(x: np.ndarray) -> tuple:
    return x.__array_interface__["data"][0], x.shape, x.strides, x.dtype.str


def note_block_extremes(x: np.ndarray, lows: np.ndarray, highs: np.ndarray) -> None:
    """Inside :func:`shared_scans`, give the scans the per-block extremes of ``x`` computed by
    whoever filled it (a reader that scanned each block while it was in cache): ``lows[b]`` and
    ``highs[b]`` the minimum and maximum of ``x[b * _SCAN_BLOCK:(b + 1) * _SCAN_BLOCK]``, NaN
    propagated. ``x`` must not change afterwards within the block; it is kept alive until the
    block ends (so its address is not reused by another array). Outside the block: no-op."""
    table = getattr(_SCAN_CACHE, "table", None)
    blocks = (-(-x.size // _SCAN_BLOCK),)
    if table is None or x.ndim != 1 or lows.shape != blocks or highs.shape != blocks:
        return
    table[_scan_key(x)] = (lows, highs)
    table.setdefault("_alive", []).append(x)


def _block_extremes(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Minimum and maximum of each block of :data:`_SCAN_BLOCK` samples (NaN propagates): one
    pass over memory where ``x.min()`` then ``x.max()`` are two."""
    table = getattr(_SCAN_CACHE, "table", None)
    if table is not None:
        key = _scan_key(x)
        if key not in table:
            table[key] = _block_extremes_uncached(x)
        return table[key]
    return _block_extremes_uncached(x)


def _block_extremes_uncached(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    acc = BlockExtremes(x.size, x.dtype)
    acc.fold(x, 0, x.size)
    return acc.result()


class BlockExtremes:
    """Per-block minimum and maximum of a 1-D float array of ``n`` samples, folded in piece
    by piece (a reader folds each piece right after reading it, while it is in cache).

    Blocks are :data:`_SCAN_BLOCK` samples. A block holding NaN has NaN as both its low and its
    high; +inf and -inf show as its high or low, as numpy's ``min``/``max`` give them.

    Two forms give the same numbers, exactly. Once numba is loaded in the process (the
    analysis kernels load it; ``CRANKBENCH_NO_NUMBA`` unset), one compiled pass keeps four
    integer extremes of the samples' bit patterns per block -- the largest and smallest as
    signed and as unsigned integers, whose order is the floats' among non-negative and (in
    reverse) among negative values -- and derives the float extremes from them: 1.8-2.1x
    faster than numpy's ``min`` then ``max`` per block on 5 M float32 samples (bench suite
    ``io``, rows ``record scan``). The read does not import numba for it (about 0.3 s, more
    than it saves on any one record). Without it, numpy's reductions.

    Parameters
    ----------
    n : int
        Samples of the array.
    dtype : numpy.dtype
        Its float dtype.
    block : int
        Samples per block.
    """

    def __init__(self, n: int, dtype, block: int = _SCAN_BLOCK):
        self.dtype = np.dtype(dtype)
        self.block = block
        nb = -(-n // block)
        kernel = _bits_kernel() if self.dtype.kind == "f" else None
        self.bits = None
        if kernel is not None and self.dtype.itemsize in (4, 8):
            w = self.dtype.itemsize * 8
            si, ui = np.dtype(f"i{w // 8}"), np.dtype(f"u{w // 8}")
            ii, iu = np.iinfo(si), np.iinfo(ui)
            # largest and smallest signed, largest and smallest unsigned: start empty
            self.bits = (kernel, si, ui,
                         np.full(nb, ii.min, si), np.full(nb, ii.max, si),
                         np.full(nb, 0, ui), np.full(nb, iu.max, ui))
        else:
            self.lows = np.full(nb, np.inf, self.dtype)
            self.highs = np.full(nb, -np.inf, self.dtype)

    def fold(self, x: np.ndarray, a: int, b: int) -> None:
        """Fold the samples ``x[a:b]`` (``x`` the whole 1-D array, ``a < b``) into their
        blocks."""
        if self.bits is not None:
            kernel, si, ui, *acc = self.bits
            if x.flags.c_contiguous:
                kernel(x.view(si), x.view(ui), 0, a, b, self.block, *acc)
            else:  # a strided view: the piece copied (its samples at a..b)
                piece = np.ascontiguousarray(x[a:b])
                kernel(piece.view(si), piece.view(ui), a, a, b, self.block, *acc)
            return
        block, lows, highs = self.block, self.lows, self.highs
        k0 = -(-a // block)               # first block starting inside the piece
        full_end = (b // block) * block   # whole full-length blocks end here
        with np.errstate(invalid="ignore"):
            if k0 * block < full_end:  # whole blocks: no other piece holds a sample of them
                rows = x[k0 * block:full_end].reshape(-1, block)
                k1 = k0 + rows.shape[0]
                np.minimum.reduce(rows, axis=1, out=lows[k0:k1])
                np.maximum.reduce(rows, axis=1, out=highs[k0:k1])
            for lo, hi in ((a, min(b, k0 * block)), (max(a, full_end, k0 * block), b)):
                if hi > lo:  # within one block: combined with what other pieces found
                    k = lo // block
                    piece = x[lo:hi]
                    lows[k] = np.minimum(lows[k], np.minimum.reduce(piece))
                    highs[k] = np.maximum(highs[k], np.maximum.reduce(piece))

    def result(self) -> tuple[np.ndarray, np.ndarray]:
        """``(lows, highs)``: per-block minimum and maximum (NaN in both for a block with NaN).
        """
        if self.bits is None:
            return self.lows, self.highs
        _, si, ui, hs, ls, hu, lu = self.bits
        sign = ui.type(1 << (8 * self.dtype.itemsize - 1))
        # the largest float: the largest signed pattern if any sample has the sign bit clear
        # (non-negative floats order as their patterns), else the negative of least magnitude
        highs = np.where(hs >= 0, hs, lu.view(si)).view(self.dtype)
        # the smallest: the negative of greatest magnitude (largest unsigned pattern with the
        # sign bit set) if there is one, else the smallest non-negative
        lows = np.where(hu >= sign, hu, ls.view(ui)).view(self.dtype)
        nan = np.isnan(highs) | np.isnan(lows)
        if nan.any():  # as numpy's reductions give it: NaN both ways
            highs[nan] = lows[nan] = np.nan
        return lows, highs


@functools.lru_cache(maxsize=1)
def _bits_numba():
    from numba import njit

    @njit(cache=True, boundscheck=False)
    def fold(i, u, offset, a, b, block, hs, ls, hu, lu):   # pragma: no cover - compiled
        # samples a..b of the channel, held in i/u from channel sample `offset` on
        for k in range(a // block, (b - 1) // block + 1):
            s = max(a, k * block)
            e = min(b, (k + 1) * block)
            ib = i[s - offset:e - offset]
            ub = u[s - offset:e - offset]
            h1, l1, h2, l2 = hs[k], ls[k], hu[k], lu[k]
            for t in range(ib.size):  # four integer extremes in one vectorised pass
                v = ib[t]
                w = ub[t]
                h1 = max(h1, v)
                l1 = min(l1, v)
                h2 = max(h2, w)
                l2 = min(l2, w)
            hs[k], ls[k], hu[k], lu[k] = h1, l1, h2, l2

    return fold


def _bits_kernel():
    """The compiled fold of :class:`BlockExtremes`, or None: numba not yet loaded by this
    process (loading it costs more than it saves on a read), or ``CRANKBENCH_NO_NUMBA`` set."""
    if "numba" not in sys.modules or os.environ.get("CRANKBENCH_NO_NUMBA"):
        return None
    try:
        return _bits_numba()
    except Exception:  # noqa: BLE001 - a numba that cannot compile here: numpy's reductions
        return None


def nonfinite_spans(values: np.ndarray) -> list[tuple[int, int]]:
    """Index spans ``[start, stop)`` of consecutive NaN/inf values.

    Examples
    --------
    >>> nonfinite_spans(np.array([1.0, np.nan, np.nan, 2.0, np.inf]))
    [(1, 3), (4, 5)]
    """
    values = np.asarray(values)
    if values.size and values.dtype.kind == "f":
        lows, highs = _block_extremes(values.reshape(-1))
        if math.isfinite(lows.min()) and math.isfinite(highs.max()):
            return []  # min/max propagate NaN and inf: one pass clears the usual case
    bad = ~np.isfinite(values)
    if not bad.any():
        return []
    edges = np.diff(np.concatenate(([0], bad.view(np.int8), [0])))
    starts = np.flatnonzero(edges == 1)
    stops = np.flatnonzero(edges == -1)
    return [(int(a), int(b)) for a, b in zip(starts, stops)]


#: the block list of a channel of one block
_FIRST = np.zeros(1, np.intp)
_FIRST.flags.writeable = False

#: Quantities whose flat runs at the extremes mean saturation (speed plateaus are legitimate).
#: Voltage is left out: raw tacho signals are square waves whose flat tops are not clipping.
CLIP_QUANTITIES = ("acceleration", "velocity", "displacement", "pressure", "force", "torque",
                   "angular_velocity", "angle")


def clipped_spans(values: np.ndarray, *, min_run: int = 3) -> list[tuple[int, int]]:
    """Index spans ``[start, stop)`` where the signal sits flat at its own maximum or minimum.

    A saturated amplifier or ADC holds its limit value for consecutive samples. A level is
    taken as a clipping limit when (1) the channel sits on it, at its global maximum or
    minimum, in runs of at least ``min_run`` samples, (2) at least two such runs occur (a limit
    cuts every large peak, one flat peak is not evidence), and (3) the signal enters those runs
    with a median jump larger than two quantisation steps (the smallest gap between distinct
    values of the channel), so the flat crest of a slow, finely sampled, quantised peak is not mistaken for a
    limit. NaN/inf are ignored; a constant channel (max == min) returns no span.

    Examples
    --------
    >>> x = np.array([0, 0.5, 1, 1, 1, 0.5, 0, -0.5, -1, -1, -1, -1, 0, 0.6, 1, 1, 1, 0,
    ...               -1, -1, -1])
    >>> clipped_spans(x)
    [(2, 5), (8, 12), (14, 17), (18, 21)]
    """
    x = np.asarray(values)
    if x.dtype.kind != "f":
        x = x.astype(np.float64)
    if x.size == 0:
        return []
    x = x.reshape(-1)
    lows, highs = _block_extremes(x)
    hi, lo = highs.max(), lows.min()
    if math.isfinite(hi) and math.isfinite(lo):
        finite = None  # all finite (NaN/inf would propagate into min/max)
        # only blocks holding an extreme can hold a run at it (a run crossing a block edge
        # puts the level in both blocks): the equality scans below skip all others
        blocks = ({hi: _FIRST, lo: _FIRST} if highs.size == 1 else
                  {hi: np.flatnonzero(highs == hi), lo: np.flatnonzero(lows == lo)})
    else:
        finite = np.isfinite(x)
        if not finite.any():
            return []
        hi, lo = np.max(x, where=finite, initial=-np.inf), np.min(x, where=finite, initial=np.inf)
        blocks = None
    if hi == lo:
        return []
    spans = []
    step = None
    for level in (hi, lo):
        starts, stops = _runs_at(x, level, None if blocks is None else blocks[level],
                                 2 * min_run)
        if not starts.size or int(np.sum(stops - starts)) < 2 * min_run:
            continue
        keep = stops - starts >= min_run
        starts, stops = starts[keep], stops[keep]
        if starts.size < 2:
            continue
        if step is None:  # quantisation step: smallest gap between distinct values
            levels = np.unique(x if finite is None else x[finite])
            step = float(np.diff(levels).min()) if levels.size > 1 else 0.0
        entries = [abs(float(x[a - 1]) - level) for a in starts
                   if a > 0 and math.isfinite(float(x[a - 1]))]
        if entries and np.median(entries) <= 2 * step:
            continue
        spans += [(int(a), int(b)) for a, b in zip(starts, stops)]
    return sorted(spans)


def _runs_at(x: np.ndarray, level, blocks, min_count: int = 0
             ) -> tuple[np.ndarray, np.ndarray]:
    """Start and stop indices of the runs of ``x == level``, scanning only the given blocks of
    :data:`_SCAN_BLOCK` samples (all of ``x`` when ``blocks`` is None); none at all when fewer
    than ``min_count`` samples are at the level."""
    if blocks is None:
        groups = [(0, x.size)]
    elif blocks.size == 1:  # the usual case: one block holds the level
        groups = [(int(blocks[0]) * _SCAN_BLOCK, min((int(blocks[0]) + 1) * _SCAN_BLOCK, x.size))]
    else:  # contiguous groups of blocks
        cut = np.flatnonzero(np.diff(blocks) > 1) + 1
        groups = [(int(g[0]) * _SCAN_BLOCK, min((int(g[-1]) + 1) * _SCAN_BLOCK, x.size))
                  for g in np.split(blocks, cut) if g.size]
    # indices at the level: few (it is an extreme of the signal); groups are a block apart, so
    # no run spans two of them
    found = [np.flatnonzero(x[a:b] == level) + a if a else np.flatnonzero(x[:b] == level)
             for a, b in groups]
    at = found[0] if len(found) == 1 else np.concatenate(found)
    if at.size < max(min_count, 1):
        return np.zeros(0, int), np.zeros(0, int)
    cut = np.flatnonzero(np.diff(at) != 1) + 1  # gaps between runs
    return at[np.concatenate(([0], cut))], at[np.concatenate((cut - 1, [at.size - 1]))] + 1
