"""The plan's view of the speed: the chunks of a resampling split until the speed varies less
than 2:1 in each (:func:`analysis.resample.plan_chunks`), and the extremes of any span of the
speed without a pass over it per span (:class:`SpanExtremes`). Moved out of
:mod:`analysis.resample` (one concept per module)."""

from __future__ import annotations

import math

import numpy as np

from crankbench.predict.errors import AnalysisError

__all__ = ["SpanExtremes"]


class SpanExtremes:
    """Lowest and highest value of any span of a record from the extremes of its blocks of
    ``block`` samples (two vectorised passes over the record, then only the part blocks at a
    span's ends are read): what :func:`plan_chunks` asks of the speed, span after span, without
    a pass over the samples per span. NaN propagates (numpy's minimum and maximum)."""

    def __init__(self, values: np.ndarray, block: int = 4096):
        self.values, self.block = values, block
        n = values.shape[0]
        whole = n - n % block
        body = values[:whole].reshape(-1, block)
        self.lows, self.highs = body.min(axis=1), body.max(axis=1)
        if whole < n:
            self.lows = np.append(self.lows, values[whole:].min())
            self.highs = np.append(self.highs, values[whole:].max())

    def limits(self) -> tuple[float, float]:
        """The record's lowest and highest value."""
        return float(self.lows.min()), float(self.highs.max())

    def __call__(self, a: int, b: int) -> tuple[float, float]:
        """``(min, max)`` of ``values[a:b]`` (a < b)."""
        k0, k1 = -(-a // self.block), b // self.block        # whole blocks inside
        if k0 >= k1:
            seg = self.values[a:b]
            return float(seg.min()), float(seg.max())
        lo, hi = float(self.lows[k0:k1].min()), float(self.highs[k0:k1].max())
        for seg in (self.values[a:k0 * self.block], self.values[k1 * self.block:b]):
            if seg.shape[0]:
                lo, hi = min(lo, float(seg.min())), max(hi, float(seg.max()))
        return lo, hi


def _split_chunks(speed, n: int, chunk: int, limits=None, extremes=None):
    """Chunk limits of at most ``chunk`` samples, split until speed varies < 2:1 in each, and
    the (min, max) speed of each. ``speed(a, b)`` returns the speed (rpm) of samples a..b-1;
    ``limits``, the whole record's (min, max) when already known; ``extremes(a, b)``, a
    span's (min, max) without reading it whole (:class:`SpanExtremes`)."""
    n_chunks = max(1, int(math.ceil(n / chunk)))
    pending = [int(v) for v in np.round(np.linspace(0, n, n_chunks + 1))]
    out = [pending[0]]
    ranges = []
    for b0 in pending[1:]:
        a = out[-1]
        ext = extremes if extremes is not None else _span_reader(speed, a, b0, n, limits)
        low = ext(a, b0)[0]
        if low <= 0:
            raise AnalysisError(f"rpm must be > 0 throughout; found {low:.6g} rpm "
                                f"between samples {a} and {b0}")
        stack = [b0]
        while stack:
            b = stack[-1]
            lo, hi = ext(a, b)
            if hi <= 2.0 * lo or b - a <= 256:
                out.append(b)
                ranges.append((lo, hi))
                stack.pop()
                a = b
            else:
                stack.append((a + b) // 2)
    return np.asarray(out, dtype=np.int64), ranges


def _span_reader(speed, a0: int, b0: int, n: int, limits):
    """``(min, max)`` of sub-spans of samples ``a0..b0-1``, read once through ``speed(a, b)``
    (the whole record's from ``limits`` when known; the last answer kept)."""
    sp = speed(a0, b0)
    memo = {}

    def ext(a, b):
        if (a, b) not in memo:
            if limits is not None and (a, b) == (0, n):
                memo.clear()
                memo[a, b] = float(limits[0]), float(limits[1])
            else:
                seg = sp[a - a0:b - a0]
                memo.clear()
                memo[a, b] = float(seg.min()), float(seg.max())
        return memo[a, b]

    return ext
