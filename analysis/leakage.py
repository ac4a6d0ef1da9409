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


def check_grid_leakage(fitter, y, starts, angle, coef, label) -> None:
    """Warn when orders not asked for leak into the tracked ones (a second fit as the check).

    ``fitter`` the :class:`analysis.orders.BlockFit` used, ``y`` the angle-domain samples,
    ``starts`` the block starts (samples), ``angle`` the shaft angle (rad) per sample,
    ``coef`` the fitted complex amplitudes (blocks, orders), ``label`` the channel's name.

    An engine signal has lines on the half-order grid (four-stroke) whether they are tracked
    or not; one inside a tracked order's window main lobe (``2/revolutions`` orders for Hann,
    ``1/revolutions`` for a rectangular window) biases that order's least-squares estimate.
    The blocks (up to 32, spread over the record) are fitted again with those grid orders
    added; a tracked order whose mean amplitude moves by more than 2 % and three standard
    errors is named, with the line's order and the setting to use.
    """
    from fractions import Fraction

    from .orders import BlockFit, OrderWarning

    orders = fitter.orders
    half = (1.0 if fitter.window == "boxcar" else 2.0) / fitter.revolutions
    grid = []
    for o in orders:
        f = Fraction(float(o)).limit_denominator(12)
        grid.append(float(f) if abs(float(f) - o) < 1e-9 else None)
    if any(g is None for g in grid):
        return
    step = min(0.5, float(np.gcd.reduce([int(round(g * 12)) for g in grid])) / 12.0)
    top = fitter.spr / 4.0
    cand = {round(q * step, 9) for o in orders
            for q in range(int(np.ceil((o - half) / step)), int(np.floor((o + half) / step)) + 1)}
    extra = sorted(q for q in cand if 0.0 < q <= top and np.min(np.abs(q - orders)) > 1e-9
                   and np.min(np.abs(q - orders)) < half - 1e-9)
    if not extra:
        return
    try:
        wide = BlockFit(np.concatenate([orders, extra]), fitter.spr, fitter.revolutions,
                        fitter.window)
    except AnalysisError:
        return
    pick = np.unique(np.linspace(0, starts.shape[0] - 1, 32).astype(int))
    frames = y[starts[pick, None] + np.arange(fitter.length)[None, :]]
    refit = wide.fit(frames, angle[starts[pick]])
    again = np.abs(refit[0][:, :orders.shape[0]])
    before = np.abs(coef[pick])
    moved = np.abs(again.mean(axis=0) - before.mean(axis=0))
    se = np.std(again - before, axis=0, ddof=1) / np.sqrt(pick.size) if pick.size > 1 else 0.0
    level = np.maximum(before.mean(axis=0), 1e-300)
    # (an order the record lacks reads what the others leave behind, at the resampling's
    # numerical floor of the block level: a move there is not leakage to warn of)
    floor = _NUMERICAL_FLOOR * float(np.mean(refit[3]))
    bad = (moved > 0.02 * level) & (moved > 3.0 * se) & (moved > 3.0 * floor)
    if bad.any():
        gap = min(abs(q - o) for q in extra for o in orders)
        text = ", ".join(f"order {o:g} by {100 * m / lv:.0f} %"
                         for o, m, lv in zip(orders[bad], moved[bad], level[bad]))
        warnings.warn(
            f"{label}: lines at orders {', '.join(f'{q:g}' for q in extra)}, not tracked, lie "
            f"inside the {fitter.revolutions}-revolution window's main lobe and leak into the "
            f"tracked orders (fitted with them, {text}); track those orders too, or use "
            f"revolutions >= {int(np.ceil((2.0 if fitter.window != 'boxcar' else 1.0) / gap))}",
            OrderWarning, stacklevel=3)
