"""Smearing of block (computed order tracking) estimates of an order's envelope.

A block estimate averages the envelope over the block's shaft angle with the window's weight;
for a smooth envelope the error is ``(μ₂/2) span² A''`` with the angle-domain second
derivative (:func:`smearing_bias`). Where the envelope changes within a block that estimate
itself reads low, and :func:`warn_block_smearing` says so with the setting to use.
"""

from __future__ import annotations

import warnings

import numpy as np

__all__ = ["smearing_bias", "warn_block_smearing"]


def smearing_bias(coef: np.ndarray, t: np.ndarray, span_s: np.ndarray, mu2: float,
                  speed_rpm=None):
    """Estimated envelope-smearing error of block (or filter) estimates: ``(μ₂/2) span² |A''|``.

    The second derivative is taken by finite differences of neighbouring estimates (exact for
    a quadratic envelope; it under-reads a peak much narrower than the span, which the
    automatic settings avoid). With ``speed_rpm`` the blocks average over shaft angle, so the
    derivative is the angle-domain one, ``(A'' − A' ṙ/r)/ω²`` scaled back by the span: in a
    sweep the first-derivative term is what a time-domain ``A''`` misses (a 2-rev block at
    100 rpm/s read up to 6e-4 off where ``A''`` stated 1e-4). The larger of each estimate and
    its two neighbours is returned: ``A''`` passes through zero on a flank where the error
    does not.

    Parameters
    ----------
    coef : ndarray, complex, shape (blocks, orders)
        Block estimates of each order's complex amplitude (signal units).
    t : ndarray, shape (blocks,)
        Time of each estimate, s.
    span_s : ndarray, shape (blocks,)
        Duration each estimate averages over, s.
    mu2 : float
        Second moment of the averaging weight in units of the span² (Hann: 0.0327).
    speed_rpm : ndarray, shape (blocks,), optional
        Shaft speed at each estimate, rpm (angle-domain averaging).

    Returns
    -------
    ndarray, shape (blocks, orders)
        Smearing error (signal units, ≥ 0).

    Examples
    --------
    >>> t = np.linspace(0.0, 10.0, 101)
    >>> coef = (2.0 + 0.5 * t ** 2)[:, None] + 0j            # A'' = 1 (units/s²)
    >>> b = smearing_bias(coef, t, np.full(101, 0.2), 1.0 / 12.0)
    >>> round(float(b[50, 0]), 6)                            # (1/12)/2 · 0.2² · 1
    0.001667
    """
    n = coef.shape[0]
    out = np.zeros(coef.shape)
    if n < 3:
        return out
    d1 = np.gradient(coef, t, axis=0)
    d2 = np.gradient(d1, t, axis=0)
    if speed_rpm is not None:
        r = np.asarray(speed_rpm, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            rel = np.where(r > 0, np.gradient(r, t) / r, 0.0)
        d2 = d2 - d1 * rel[:, None]
    bias = 0.5 * mu2 * (span_s ** 2)[:, None] * np.abs(d2)
    out[:] = bias
    out[1:] = np.maximum(out[1:], bias[:-1])
    out[:-1] = np.maximum(out[:-1], bias[1:])
    return out


#: stated smearing (relative to the block's amplitude) above which COT warns: beyond it the
#: envelope changes within a block and the finite-difference A'' itself under-reads (a Q = 20
#: crossing at 1000 rpm/s with 2-rev blocks: 4 % stated, 8 % lost at the peak)
_SMEAR_WARN = 0.02

#: the resampled angle samples' numerical error relative to the block's level: the band-limited
#: interpolator's documented bound (5e-6 up to a quarter of the rate, ``analysis.resample``).
#: An order whose block estimates are that small (an order the record does not have, read
#: from what the other orders leave behind) has no curvature to judge: a clean two-order
#: signal's absent order 6 (3.6e-7 of the level) had been warned of as "smearing 38 %"
_NUMERICAL_FLOOR = 5e-6


def warn_block_smearing(coef, bias, speed_rpm, fitter, label, noise=None, level=None, *,
                        leaked=False):
    """Warn (:class:`analysis.orders.OrderWarning`) when the stated smearing of a block
    estimate passes 2 % (``_SMEAR_WARN``) of its amplitude; blocks in a dip below 5 % of the
    order's largest amplitude are not judged, nor smearing within 3× the estimate's floor:
    its noise and the resampling's numerical error (``_NUMERICAL_FLOOR`` × the block's level).

    Parameters
    ----------
    coef : ndarray, complex, shape (blocks, orders)
        Block estimates (signal units).
    bias : ndarray, shape (blocks, orders)
        Their stated smearing (:func:`smearing_bias`, signal units).
    speed_rpm : ndarray, shape (blocks,)
        Shaft speed at each block, rpm (named in the warning).
    fitter : analysis.orders.BlockFit
        The block fit (orders and revolutions per block, named in the warning).
    label : str
        Channel name.
    noise : ndarray, shape (blocks, orders), optional
        1-σ amplitude noise of each estimate (signal units): a smearing below 3× it is the
        noise's own curvature (finite differences of noisy estimates), not judged.
    level : ndarray, shape (blocks,), optional
        Each block's rms (the orders and the residual; signal units), the scale of the
        numerical floor (default: the largest estimate of the block).
    leaked : bool
        A line not tracked was found leaking into the blocks (:mod:`analysis.leakage`): its
        beat with the order swings the block estimates as an envelope change would, and the
        warning says so.
    """
    from .orders import OrderWarning

    amp = np.abs(coef)
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(amp > 0, bias / amp, 0.0)
    rel = np.where(amp >= 0.05 * amp.max(axis=0, initial=0.0), rel, 0.0)   # not in dips
    if level is None:
        level = amp.max(axis=1, initial=0.0) / np.sqrt(2.0)
    floor = _NUMERICAL_FLOOR * np.asarray(level, dtype=float)[:, None]
    if noise is not None:
        floor = np.hypot(floor, np.broadcast_to(noise, bias.shape))
    rel = np.where(bias > 3.0 * floor, rel, 0.0)
    if rel.size == 0 or not np.nanmax(rel) > _SMEAR_WARN:
        return
    i, j = np.unravel_index(int(np.nanargmax(rel)), rel.shape)
    warnings.warn(
        f"{label}: order {fitter.orders[j]:g} changes within a {fitter.revolutions}-revolution "
        f"block near {float(speed_rpm[i]):.0f} rpm: stated smearing {100 * rel[i, j]:.2g} % of the "
        "amplitude, and where the envelope changes this fast within a block the estimate of "
        "it reads low (the loss can be twice that); use method='auto' (adaptive Vold-Kalman) "
        "or method='vkf' with a bandwidth wider than the envelope's changes"
        + ("; or the swing is the beat of the leaking line warned of above (track it, or "
           "lengthen the blocks as said there)" if leaked else ""),
        OrderWarning, stacklevel=4)
