"""The noise floor of computed order tracking's blocks, with the signal's other lines left out.

:meth:`analysis.blocks.BlockFit.fit` reads each block's noise as the median power per bin of
its residual (the block less the tracked orders and trend). An engine signal has a line at
every half order whether it is tracked or not, and with the window's main lobes they fill most
bins of a short block: with every half order 0.5-10 in the signal, 4-revolution blocks stated
0.13 of amplitude noise where the estimates were within 0.003 -- an uncertainty 40 times too
wide, which no verdict can use.

An order-locked line has the same complex value, referred to the shaft angle, in every block;
noise does not. :func:`differenced_floor` takes the difference of each block's residual
spectrum (referred to the shaft angle at its start) and that of the next block that does not
overlap it: the lines on bins cancel, the noise, independent in the two, doubles in power.
Its median per bin is the block's noise floor where it is below half the direct one (lines
were there); elsewhere the direct floor stands (white noise: both read the same). Lines off
the bins (an order not a multiple of ``1/revolutions``) and envelopes that change between the
two blocks do not cancel and keep the floor up: never lower than the noise.
"""

from __future__ import annotations

import numpy as np

__all__ = ["differenced_floor"]


def differenced_floor(spectra: np.ndarray, floor: np.ndarray, angle0: np.ndarray,
                      bins: np.ndarray, revolutions: int, length: int, hop: int,
                      scale: float) -> np.ndarray:
    """Per-block noise floor (mean square per bin) with order-locked lines differenced out.

    Parameters
    ----------
    spectra : ndarray, complex, shape (blocks, bins)
        Windowed DFT of each block's residual at the bins of ``bins``.
    floor : ndarray, shape (blocks,)
        The direct floor: median power per bin of the same bins / ln 2.
    angle0 : ndarray, shape (blocks,)
        Shaft angle at each block's first sample, rad.
    bins : ndarray of int
        The DFT bin numbers of the columns (bin ``k`` is order ``k / revolutions``).
    revolutions, length : int
        Block length in revolutions and in samples.
    hop : int
        Samples from one block's start to the next (uniform).
    scale : float
        Power per bin of a unit ``|X|²`` (``2 / (length · Σw²)``, as
        :func:`analysis.blocks._scale_spectrum` scales).

    Returns
    -------
    ndarray, shape (blocks,)
        The floor: the differenced one where below half the direct one, else the direct one.
        Unchanged when the record holds no two blocks that do not overlap.

    Examples
    --------
    Every half order 0.5-4 and no noise beyond rounding, in 4-revolution blocks: the lines and
    their main lobes fill every bin, so the direct floor reads them; the differenced one
    nothing.

    >>> from scipy.signal import get_window
    >>> spr, revs, hop = 16, 4, 32
    >>> w = get_window("hann", spr * revs)
    >>> angle = 2 * np.pi * np.arange(400) / spr
    >>> x = sum(np.cos(o * angle + o) / o for o in np.arange(0.5, 4.1, 0.5))
    >>> starts = np.arange(0, 400 - spr * revs + 1, hop)
    >>> X = np.fft.rfft(x[starts[:, None] + np.arange(spr * revs)] * w, axis=1)[:, 1:17]
    >>> scale = 2 / (spr * revs * np.sum(w ** 2))
    >>> direct = np.median(np.abs(X) ** 2 * scale, axis=1) / np.log(2)
    >>> got = differenced_floor(X, direct, angle[starts], np.arange(1, 17), revs, spr * revs,
    ...                         hop, scale)
    >>> bool(np.all(got < 1e-20 * direct))
    True
    """
    nb = spectra.shape[0]
    m = -(-length // max(hop, 1))             # blocks apart that share no sample
    if nb <= m:
        return floor
    orders = np.asarray(bins, float) / revolutions
    index = np.arange(nb)
    partner = np.where(index + m < nb, index + m, index - m)  # nb > m: one of them exists
    step = angle0[m] - angle0[0]
    if np.allclose(angle0[partner] - angle0, np.where(partner > index, step, -step),
                   rtol=0.0, atol=1e-9 * max(abs(step), 1.0)):
        # blocks a uniform angle apart (the resampled grid): one phase factor per bin and
        # direction, |X_b e^{-i o θ_b} - X_p e^{-i o θ_p}| = |X_b - X_p e^{-i o (θ_p - θ_b)}|
        turn = np.exp(-1j * step * orders)
        diff = spectra - spectra[partner] * np.where((partner > index)[:, None], turn,
                                                     turn.conj())
    else:  # referred to the shaft angle block by block
        ref = spectra * np.exp(-1j * np.outer(angle0, orders))
        diff = ref - ref[partner]
    # independent noise in the two blocks: the difference carries twice the power
    power = 0.5 * scale * (diff.real ** 2 + diff.imag ** 2)
    low = np.median(power, axis=1) / np.log(2.0)
    return np.where(low < 0.5 * floor, low, floor)
