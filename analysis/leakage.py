"""Leakage of orders not asked for into computed order tracking (a check, not a correction).

Computed order tracking fits only the requested orders (and the trend) in each block; a
line of the signal at another order inside a tracked order's window main lobe biases that
order. On the half-order grid of an engine signal (a cylinder pressure has every half order)
this is the common case: orders 0.5 and 1 of a raw genset pressure export read 2.7x and 1.7x
their per-cycle Fourier values with 2-revolution Hann blocks. :func:`check_grid_leakage`
refits a sample of blocks with the grid orders inside the main lobes added and warns when a
tracked order moves (``tests/analysis/test_short_record_default.py``).
"""

from __future__ import annotations

import warnings

import numpy as np

from crankbench.predict.errors import AnalysisError

from .block_smearing import _NUMERICAL_FLOOR

__all__ = ["check_grid_leakage"]


def check_grid_leakage(fitter, y, starts, angle, coef, label) -> bool:
    """Warn when orders not asked for leak into the tracked ones (a second fit as the check).

    ``fitter`` the :class:`analysis.orders.BlockFit` used, ``y`` the angle-domain samples,
    ``starts`` the block starts (samples), ``angle`` the shaft angle (rad) per sample,
    ``coef`` the fitted complex amplitudes (blocks, orders), ``label`` the channel's name.
    Returns True when it warned.

    An engine signal has lines on the half-order grid (four-stroke) whether they are tracked
    or not; one inside a tracked order's window main lobe (``2/revolutions`` orders for Hann,
    ``1/revolutions`` for a rectangular window) biases that order's least-squares estimate.
    The blocks (up to 32, spread over the record) are fitted again with the grid orders
    inside the main lobes and on their edges added (a line on the edge, leaking nothing, would
    otherwise be mistaken by the second fit for one inside). A tracked order is named when it
    moves by more than 2 % of its level and by more than three standard errors: of its mean
    amplitude over the blocks, or -- for a leak whose sign alternates from block to block, as
    from a line half an order away in half-overlapping blocks -- of the per-block change
    against the per-block noise. The warning names the added lines the second fit finds in
    the signal (above three times their noise), those inside a main lobe first.
    """
    from fractions import Fraction

    from .orders import BlockFit, OrderWarning

    orders = fitter.orders
    k = orders.shape[0]
    half = (1.0 if fitter.window == "boxcar" else 2.0) / fitter.revolutions
    grid = []
    for o in orders:
        f = Fraction(float(o)).limit_denominator(12)
        grid.append(float(f) if abs(float(f) - o) < 1e-9 else None)
    if any(g is None for g in grid):
        return False
    step = min(0.5, float(np.gcd.reduce([int(round(g * 12)) for g in grid])) / 12.0)
    top = fitter.spr / 4.0
    cand = {round(q * step, 9) for o in orders
            for q in range(int(np.ceil((o - half) / step - 1e-9)),
                           int(np.floor((o + half) / step + 1e-9)) + 1)}
    extra = np.array(sorted(q for q in cand if 0.0 < q <= top
                            and np.min(np.abs(q - orders)) > 1e-9
                            and np.min(np.abs(q - orders)) <= half + 1e-9))
    if not extra.size:
        return False
    try:
        wide = BlockFit(np.concatenate([orders, extra]), fitter.spr, fitter.revolutions,
                        fitter.window)
    except AnalysisError:
        return False
    pick = np.unique(np.linspace(0, starts.shape[0] - 1, 32).astype(int))
    frames = y[starts[pick, None] + np.arange(fitter.length)[None, :]]
    refit, _, wide_floor, wide_level = wide.fit(frames, angle[starts[pick]])
    sigma = wide.noise(wide_floor)                       # (blocks, all orders), 1 σ
    again, before = refit[:, :k], coef[pick]
    moved = np.abs(np.abs(again).mean(axis=0) - np.abs(before).mean(axis=0))
    diff = np.abs(again) - np.abs(before)
    se = np.std(diff, axis=0, ddof=1) / np.sqrt(pick.size) if pick.size > 1 else np.inf
    # per block: the complex change (an alternating leak averages out of the mean amplitude)
    change = np.sqrt(np.mean(np.abs(again - before) ** 2, axis=0))
    noise = np.sqrt(np.mean(sigma[:, :k] ** 2, axis=0))
    level = np.maximum(np.abs(before).mean(axis=0), 1e-300)
    # (an order the record lacks reads what the others leave behind, at the resampling's
    # numerical floor of the block level: a move there is not leakage to warn of)
    floor = _NUMERICAL_FLOOR * float(np.mean(wide_level))
    shift = np.maximum(moved, change)
    bad = ((shift > 0.02 * level) & (shift > 3.0 * floor)
           & ((moved > 3.0 * se) | (change > 3.0 * noise)))
    if not bad.any():
        return False
    # the added lines the signal has: above three times their noise and the numerical floor
    size = np.sqrt(np.mean(np.abs(refit[:, k:]) ** 2, axis=0))
    present = (size > 3.0 * np.sqrt(np.mean(sigma[:, k:] ** 2, axis=0))) & (size > 3.0 * floor)
    dist = np.array([np.min(np.abs(q - orders)) for q in extra])
    inside = present & (dist < half - 1e-9)
    named = extra[inside] if inside.any() else extra[present] if present.any() else extra
    gap = float(np.min(dist[np.isin(extra, named)]))
    lobe = 2.0 if fitter.window != "boxcar" else 1.0
    text = ", ".join(f"order {o:g} by {100 * m / lv:.0f} %"
                     for o, m, lv in zip(orders[bad], shift[bad], level[bad]))
    warnings.warn(
        f"{label}: lines at orders {', '.join(f'{q:g}' for q in named)}, not tracked, lie "
        f"inside the {fitter.revolutions}-revolution window's main lobe and leak into the "
        f"tracked orders (fitted with them, rms over blocks: {text}); track those orders "
        f"too, or use revolutions >= {int(np.floor(lobe / gap + 1e-9)) + 1}",
        OrderWarning, stacklevel=3)
    return True
