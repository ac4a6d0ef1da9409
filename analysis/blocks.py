"""Angle-domain blocks: the window, the framing, the spectrum scaling and the block least squares.

The machinery shared by computed order tracking (:func:`analysis.orders.order_track`, the
streamed tracker, the steady-state table) and the order map: a periodic window by name
(:func:`get_window`), block starts (:func:`_frames`), the coherent-amplitude and mean-square
scaling of one-sided DFTs (:func:`_scale_spectrum`) and :class:`BlockFit`, the weighted least
squares of the orders and a trend in one block. Re-exported by :mod:`analysis.orders`.
"""

from __future__ import annotations

import warnings

import numpy as np

from crankbench.predict.errors import AnalysisError

__all__ = ["get_window", "BlockFit"]

_FRAMES_PER_BATCH = 256  # frames transformed at a time (bounds memory)


def get_window(window, length: int) -> np.ndarray:
    """A periodic (DFT-even) window from :func:`scipy.signal.get_window` by name.

    ``window`` is a name (``"hann"``, ``"flattop"``, ``"boxcar"``...) or a tuple such as
    ``("kaiser", 8.0)``; an unknown name raises :class:`AnalysisError` listing valid names.

    Examples
    --------
    >>> float(get_window("hann", 4)[2])
    1.0
    """
    from scipy.signal import get_window as scipy_window
    from scipy.signal.windows import _windows

    try:
        return scipy_window(window, length, fftbins=True)
    except (ValueError, TypeError) as exc:
        names = sorted(k for k in getattr(_windows, "_win_equiv", {}) if isinstance(k, str))
        from crankbench.predict._validate import suggest

        raise AnalysisError(f"window={window!r} is not a scipy window ({exc}); valid names "
                            f"include {', '.join(names[:30])}"
                            f"{suggest(str(window), names)}") from None


def _hop(length: int, overlap: float) -> int:
    """Samples from one frame's start to the next: frames of ``length`` samples with fractional
    ``overlap`` (in memory and streamed alike)."""
    return max(1, int(round(length * (1.0 - overlap))))


def _frames(n: int, length: int, overlap: float) -> np.ndarray:
    """Start indices of frames of ``length`` samples with fractional ``overlap``."""
    hop = _hop(length, overlap)
    if n < length:
        return np.zeros(0, dtype=np.int64)
    return np.arange(0, n - length + 1, hop, dtype=np.int64)


def _frame_batches(starts: np.ndarray, batch: int = _FRAMES_PER_BATCH):
    for i in range(0, starts.shape[0], batch):
        yield slice(i, min(starts.shape[0], i + batch))


def _scale_spectrum(X: np.ndarray, w: np.ndarray, scaling: str, factor: float) -> np.ndarray:
    """Coherent amplitude or mean-square per bin of one-sided DFTs ``X`` (rows; the first
    ``X.shape[1]`` bins of transforms of ``len(w)`` points). Bin 0 and, when ``X`` reaches it,
    the Nyquist bin of an even length stand for one frequency, not two: halved."""
    length = w.shape[0]
    nyquist = length % 2 == 0 and X.shape[1] == length // 2 + 1
    if scaling == "amplitude":
        out = np.abs(X) * (2.0 / w.sum())
        out[:, 0] *= 0.5
        if nyquist:
            out[:, -1] *= 0.5
        return out * factor
    # mean square per bin: P_k = 2|X_k|^2 / (M Σ w^2); band sums give A_rms^2 (Parseval)
    out = np.abs(X) ** 2 * (2.0 / (length * np.sum(w ** 2)))
    out[:, 0] *= 0.5
    if nyquist:
        out[:, -1] *= 0.5
    return out


class BlockFit:
    """Weighted least squares of every requested order and a trend in one angle-domain block.

    The model of a block of ``length`` angle samples (``samples_per_rev`` per revolution) is
    ``y(φ) ≈ Σ_d c_d P_d(s) + Σ_k Re{A_k e^{i o_k φ}}`` with ``P_d`` Legendre polynomials in the
    block position ``s ∈ [−1, 1]`` (``trend_degree`` + 1 terms), solved with the window as
    weights. The same matrix serves every block, so the fit of a batch of blocks is one matrix
    product (the cost of the windowed DFT it replaces). Used by :func:`order_track` and the
    streamed tracker alike.

    Parameters
    ----------
    orders : ndarray
        Orders (checked).
    samples_per_rev, revolutions : int
    window : str or tuple
    trend_degree : int
        Degree of the per-block trend polynomial (1: constant and slope).

    Attributes
    ----------
    noise_gain : ndarray
        Per order: amplitude noise of the fit relative to the windowed DFT at that order
        alone (1 when orders lie outside each other's main lobe).
    enbw : float
        Equivalent noise bandwidth of the window, bins.
    """

    def __init__(self, orders, samples_per_rev: int, revolutions: int, window="hann",
                 trend_degree: int = 1):
        self.orders = np.asarray(orders, float)
        self.spr, self.revolutions = int(samples_per_rev), int(revolutions)
        self.length = length = self.spr * self.revolutions
        self.window = window
        w = get_window(window, length)
        self.w = w
        self.enbw = float(length * np.sum(w ** 2) / np.sum(w) ** 2)
        local = 2.0 * np.pi * np.arange(length) / self.spr
        s = np.linspace(-1.0, 1.0, length)
        from numpy.polynomial import legendre

        trend = np.stack([legendre.legval(s, np.eye(trend_degree + 1)[d])
                          for d in range(trend_degree + 1)], axis=1)
        phase = np.outer(local, self.orders)
        basis = np.concatenate([trend, np.cos(phase), -np.sin(phase)], axis=1)
        self.n_trend = trend_degree + 1
        weight = np.clip(w, 0.0, None)             # flat-top windows dip below zero
        gram = basis.T @ (basis * weight[:, None])
        cond = np.linalg.cond(gram)
        k = self.orders.shape[0]
        # each order alone (windowed DFT): the reference noise level of its amplitude
        alone = 2.0 / w.sum() * np.sqrt(0.5 * np.sum(w ** 2))
        if cond > 1e12:
            raise AnalysisError(self._too_close(None))
        proj = np.linalg.solve(gram, (basis * weight[:, None]).T)   # (n_par, length)
        self.proj = np.ascontiguousarray(proj.T)                    # frames @ proj -> params
        self.basis = basis
        var = np.sum(proj ** 2, axis=1)                             # white-noise variance / σ²
        amp_std = np.sqrt(0.5 * (var[self.n_trend:self.n_trend + k]
                                 + var[self.n_trend + k:]))
        self.noise_gain = amp_std / alone
        # time second moment of the window (in blocks², scaled by the block duration later)
        x = (np.arange(length) + 0.5) / length - 0.5
        self.mu2 = float(np.sum(w * x ** 2) / np.sum(w))
        # the estimate's time is the window's centroid (samples from the block's first): a
        # periodic Hann's is L/2, half a sample later than the block's middle (L - 1)/2 (a
        # steady ramp envelope read 7e-5 high with the middle)
        self.centroid = float(np.sum(np.arange(length) * w) / np.sum(w))

    def _too_close(self, gain):
        o = np.sort(np.concatenate([[0.0], self.orders]))
        gap = float(np.min(np.diff(o)))
        need = int(np.ceil(2.0 / gap))
        return (f"orders {', '.join(f'{v:g}' for v in self.orders)} (and the channel's trend, "
                f"order 0) are closer ({gap:g} orders) than one bin of a "
                f"{self.revolutions}-revolution block (1/{self.revolutions}); they cannot be "
                f"separated: use revolutions >= {need} (or method='vkf')")

    def check_spacing(self) -> None:
        """Refuse orders closer than one bin; warn when they share a main lobe (noise × κ)."""
        from .orders import OrderWarning

        o = np.sort(np.concatenate([[0.0], self.orders]))
        gap = float(np.min(np.diff(o)))
        if gap < 1.0 / self.revolutions - 1e-12:
            raise AnalysisError(self._too_close(None))
        bad = self.noise_gain > 1.5
        if bad.any():
            worst = int(np.argmax(self.noise_gain))
            need = int(np.ceil(4.0 / gap))
            warnings.warn(
                f"orders {', '.join(f'{v:g}' for v in self.orders[bad])} lie inside another "
                f"order's (or order 0's) window main lobe in {self.revolutions}-revolution "
                f"blocks (spacing {gap:g} orders); they are separated by least squares with "
                f"the noise amplified up to {self.noise_gain[worst]:.2g}x; use revolutions >= "
                f"{need} for independent estimates", OrderWarning, stacklevel=4)

    def fit(self, frames: np.ndarray, phi0: np.ndarray, spectra: bool = False):
        """Complex amplitudes (blocks, orders) referred to the absolute angle, the block means,
        the broadband noise floor per bin of the residual (mean square per bin) and the
        block's level: the rms of what varies in it (the fitted orders and the residual, trend
        excluded; signal units), the scale of the resampling's numerical error. With
        ``spectra``, also the residual's windowed DFT at the floor's bins (:attr:`bins`)."""
        from scipy import fft

        k = self.orders.shape[0]
        params = frames @ self.proj
        nt = self.n_trend
        coef = params[:, nt:nt + k] + 1j * params[:, nt + k:]
        coef *= np.exp(-1j * np.outer(phi0, self.orders))
        resid = frames - params @ self.basis.T
        band = self.bins
        spec = fft.rfft(resid * self.w, axis=1)
        power = _scale_spectrum(spec, self.w, "power", 1.0)[:, band]
        # median of an exponential variable is ln 2 of its mean
        floor = np.median(power, axis=1) / np.log(2.0)
        level = np.sqrt(np.einsum("ij,ij->i", resid, resid) / resid.shape[1]
                        + 0.5 * np.einsum("ij,ij->i", coef.real, coef.real)
                        + 0.5 * np.einsum("ij,ij->i", coef.imag, coef.imag))
        out = coef, params[:, 0], floor, level
        return out + (spec[:, band],) if spectra else out

    @property
    def bins(self) -> slice:
        """DFT bins of the residual's noise floor: 1 up to the anti-alias band (order spr/4)."""
        return slice(1, min(self.length // 2, int(self.spr / 4.0 * self.revolutions)) + 1)

    def line_free_floor(self, spectra, floor, phi0, hop: int) -> np.ndarray:
        """The blocks' noise floor with the signal's order-locked lines differenced out
        (:func:`analysis.cot_noise.differenced_floor`): ``spectra`` and ``floor`` from
        :meth:`fit`, ``phi0`` the blocks' start angles (rad), ``hop`` samples between starts."""
        from .cot_noise import differenced_floor

        bins = np.arange(self.bins.start, self.bins.stop)
        return differenced_floor(spectra, floor, phi0, bins, self.revolutions, self.length, hop,
                                 2.0 / (self.length * np.sum(self.w ** 2)))

    def noise(self, floor: np.ndarray) -> np.ndarray:
        """1-σ amplitude error per (block, order) from the noise floor (mean square per bin)."""
        return np.sqrt(floor * self.enbw)[:, None] * self.noise_gain[None, :]
