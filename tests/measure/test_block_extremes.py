"""Per-block extremes of the record checks (:class:`measure.scan.BlockExtremes`), compiled and
numpy forms, against numpy's own ``min``/``max`` of each block (the independent reference):
equal on the sign patterns the integer form must get right -- all-negative and
all-positive blocks, signed zeros, subnormals, infinities, NaN with either sign bit -- in
float32 and float64, folded whole or in pieces that cross block edges."""

from __future__ import annotations

import numpy as np
import pytest

from crankbench.measure import scan
from crankbench.measure.scan import BlockExtremes

BLOCK = 64


@pytest.fixture(params=["compiled", "numpy"])
def form(request, monkeypatch):
    """Run with the compiled integer fold (numba loaded) or with numpy's reductions."""
    if request.param == "compiled":
        pytest.importorskip("numba")
        monkeypatch.delenv("CRANKBENCH_NO_NUMBA", raising=False)
    else:
        monkeypatch.setenv("CRANKBENCH_NO_NUMBA", "1")
    yield request.param
    acc = BlockExtremes(BLOCK, np.float32, BLOCK)
    assert (acc.bits is not None) == (request.param == "compiled")


def _hard(dtype) -> np.ndarray:
    """Blocks of every sign pattern, and the special values, in ``dtype``."""
    rng = np.random.default_rng(11)
    info = np.finfo(dtype)
    blocks = [
        rng.standard_normal(BLOCK),                       # mixed signs
        -np.abs(rng.standard_normal(BLOCK)) - 0.5,        # all negative
        np.abs(rng.standard_normal(BLOCK)) + 0.5,         # all positive
        np.full(BLOCK, -0.0),                             # negative zeros only
        np.r_[np.full(BLOCK // 2, 0.0), np.full(BLOCK // 2, -0.0)],
        np.r_[np.full(BLOCK - 1, -3.0), [-0.0]],          # negatives and -0.0
        np.r_[np.full(BLOCK - 1, 2.0), [0.0]],            # positives and +0.0
        np.r_[np.full(BLOCK - 2, info.smallest_subnormal), [-info.smallest_subnormal, 0]],
        np.r_[rng.standard_normal(BLOCK - 1), [np.inf]],
        np.r_[rng.standard_normal(BLOCK - 1), [-np.inf]],
        np.r_[-np.abs(rng.standard_normal(BLOCK - 1)), [np.inf]],   # +inf among negatives
        np.r_[np.abs(rng.standard_normal(BLOCK - 1)), [-np.inf]],   # -inf among positives
        np.full(BLOCK, info.max), np.full(BLOCK, info.min),
        np.r_[rng.standard_normal(BLOCK - 5), [info.max, info.min, 0, -0.0, 1]],
    ]
    x = np.concatenate(blocks).astype(dtype)
    return np.r_[x, rng.standard_normal(BLOCK // 3).astype(dtype)]  # a short last block


def _nan_with_sign(dtype, negative: bool):
    bits = np.array([np.nan], dtype).view(f"u{np.dtype(dtype).itemsize}")
    top = bits.dtype.type(1 << (8 * bits.dtype.itemsize - 1))
    bits = (bits | top) if negative else (bits & ~top)
    return bits.view(dtype)[0]


def _expected(x):
    with np.errstate(invalid="ignore"):
        blocks = [x[a:a + BLOCK] for a in range(0, x.size, BLOCK)]
        return np.array([b.min() for b in blocks]), np.array([b.max() for b in blocks])


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("piece", [None, 1, 37, BLOCK, 3 * BLOCK + 5])
def test_block_extremes_equal_numpys_on_every_sign_pattern(form, dtype, piece):
    x = _hard(dtype)
    acc = BlockExtremes(x.size, x.dtype, BLOCK)
    step = x.size if piece is None else piece
    for a in range(0, x.size, step):
        acc.fold(x, a, min(x.size, a + step))
    lows, highs = acc.result()
    want_lo, want_hi = _expected(x)
    # the same floats (a signed zero compares equal to the other sign's: numpy's own choice
    # between them is not specified)
    np.testing.assert_array_equal(lows, want_lo)
    np.testing.assert_array_equal(highs, want_hi)
    assert lows.dtype == highs.dtype == np.dtype(dtype)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("negative", [False, True])
def test_a_nan_of_either_sign_makes_its_block_nan_both_ways(form, dtype, negative):
    for where in (0, BLOCK - 1, BLOCK + 7):
        x = _hard(dtype)[:3 * BLOCK].copy()
        x[where] = _nan_with_sign(dtype, negative)
        acc = BlockExtremes(x.size, x.dtype, BLOCK)
        acc.fold(x, 0, x.size)
        lows, highs = acc.result()
        k = where // BLOCK
        assert np.isnan(lows[k]) and np.isnan(highs[k])
        others = [j for j in range(lows.size) if j != k]
        assert np.isfinite(lows[others]).all() and np.isfinite(highs[others]).all()


def test_a_strided_view_folds_the_same(form):
    base = _hard(np.float64)
    x = base[::2]
    acc = BlockExtremes(x.size, x.dtype, BLOCK)
    acc.fold(x, 0, x.size // 2)
    acc.fold(x, x.size // 2, x.size)
    lows, highs = acc.result()
    want_lo, want_hi = _expected(np.ascontiguousarray(x))
    np.testing.assert_array_equal(lows, want_lo)
    np.testing.assert_array_equal(highs, want_hi)


def test_the_record_checks_find_the_same_spans_in_both_forms(form):
    """NaN spans and clipping found through the shared scan, in blocks of the module's own
    size, at the hand-placed positions."""
    n = 3 * scan._SCAN_BLOCK + 17
    x = 0.3 * np.random.default_rng(4).standard_normal(n)
    x[scan._SCAN_BLOCK - 1:scan._SCAN_BLOCK + 2] = -1.0   # a clipped run across a block edge
    x[2 * scan._SCAN_BLOCK + 100:2 * scan._SCAN_BLOCK + 104] = -1.0
    x = np.maximum(x, -1.0)
    assert scan.clipped_spans(x) == [(scan._SCAN_BLOCK - 1, scan._SCAN_BLOCK + 2),
                                     (2 * scan._SCAN_BLOCK + 100, 2 * scan._SCAN_BLOCK + 104)]
    x[5:7] = -np.nan
    assert scan.nonfinite_spans(x) == [(5, 7)]
