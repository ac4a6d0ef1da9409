"""Anti-alias low-pass of the angle resampling (:mod:`analysis.resample`): the Kaiser-window
design (100 dB), the FFT low-pass of a chunk and the compiled half-band stages before it.
Moved out of ``resample`` unchanged (one concept per module)."""

from __future__ import annotations

import functools

import numpy as np

_AA_BETA = 0.1102 * (100.0 - 8.7)   # Kaiser beta of the 100 dB anti-alias low-pass
_TWO_PI = 2.0 * np.pi


@functools.lru_cache(maxsize=1)
def _kaiser_step():
    """Cumulative integral ``C(v)`` of the Fourier transform of the Kaiser window (β =
    ``_AA_BETA``, half-length 1) over ``v`` (cycles per half-length), normalised to C(∞) = 1.

    The transform is ``(2/I0(β)) sinh(√(β² − (2πv)²))/√(β² − (2πv)²)`` (sin for 2π|v| > β);
    a Kaiser-windowed ideal low-pass of cut-off ``f_c`` then has the response
    ``H(f) = C((f + f_c)T) − C((f − f_c)T)`` (``T`` the half-length in s).
    """
    from scipy import special

    beta = _AA_BETA
    v = np.linspace(-6.0, 6.0, 12001)   # beyond |v| = 6 (main lobe β/2π ≈ 1.6) C is 0 or 1
    z2 = beta ** 2 - (_TWO_PI * v) ** 2
    root = np.sqrt(np.abs(z2))
    with np.errstate(invalid="ignore", divide="ignore"):
        core = np.where(z2 > 0, np.sinh(root) / root, np.sin(root) / root)
    core[root < 1e-12] = 1.0
    w = 2.0 / special.i0(beta) * core
    c = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(v))])
    return v, c / c[-1]          # the transform is even: C(0) = 1/2 by symmetry


def _lowpass_gain(f: np.ndarray, f_pass: float, f_stop: float) -> np.ndarray:
    """Response of the Kaiser-windowed low-pass passing ``f_pass`` and stopping ``f_stop``."""
    v, c = _kaiser_step()
    f_cut = 0.5 * (f_pass + f_stop)
    half = _aa_half_length(f_pass, f_stop)
    return np.interp((f + f_cut) * half, v, c) - np.interp((f - f_cut) * half, v, c)


def _aa_half_length(f_pass: float, f_stop: float) -> float:
    """Half-length ``T`` (s) of the anti-alias impulse response: β/(π (f_stop − f_pass))."""
    return _AA_BETA / (np.pi * (f_stop - f_pass))


@functools.lru_cache(maxsize=256)
def _good_size(n: int) -> int:
    """Smallest ``2^a 5^b 3^c ≥ n`` with ``b ≤ 2``, ``c ≤ 1``: transform lengths the FFT does
    fastest (measured: 102 400 points cost 0.66× of 101 250 = 2·3⁴·5⁴)."""
    best = 1 << int(np.ceil(np.log2(max(n, 1))))
    for odd in (1, 3, 5, 15, 25, 75):
        size = odd << max(0, int(np.ceil(np.log2(max(n, 1) / odd))))
        while size // 2 >= n and size % 2 == 0:
            size //= 2
        if n <= size < best:
            best = size
    return best


#: half-band stage: equiripple taps of a 31-tap filter (pass ≤ fs/8, stop ≥ 3fs/8, both
#: within 1.7e-7: 135 dB), the odd ones listed (the even ones are 0 but the centre, 1/2)
_HB_TAPS = 31
_HB_REACH = _HB_TAPS // 2          # input samples a stage output reaches on either side
_HB_MAX_STAGES = 4


@functools.lru_cache(maxsize=1)
def _halfband_taps() -> np.ndarray:
    """The odd taps ``h[1], h[3], …, h[15]`` of the half-band low-pass (Parks–McClellan,
    pass band ``[0, fs/8]``, stop band ``[3fs/8, fs/2]``); its deviation in both bands is
    ≤ 1.7e-7 (checked by ``tests/analysis/test_resample_halfband.py``). The half-band
    structure (even taps 0, centre 1/2) is imposed exactly (the design has it to 1e-11)."""
    from scipy import signal

    h = signal.remez(_HB_TAPS, [0.0, 0.125, 0.375, 0.5], [1.0, 0.0], fs=1.0, maxiter=200)
    odd = h[_HB_REACH + 1::2].copy()
    odd.flags.writeable = False
    return odd


def _fft_lowpass(data: np.ndarray, fs: float, f_pass: float, f_stop: float, nfft: int,
                 n_out: int, *, stages: int = 0):
    """Low-pass ``data`` in the frequency domain (transform length ``nfft``) and return it at
    ``n_out`` samples: output sample ``m`` is the filtered signal at input position
    ``m · nfft/n_out`` (keeping only the bins below the output's Nyquist frequency, where the
    filter has already reached its stop band).

    Circular convolution with an impulse response of half-length ``T``: the first and last
    ``ceil(T fs)`` samples are incomplete (the caller never uses them). ``data`` shorter than
    ``nfft`` is zero padded here (scipy's own padding of a long transform costs as much again
    as the transform, measured).

    ``stages`` half-band decimations by 2 (:func:`_halfband_taps`) come first: the transform
    then has ``nfft/2^stages`` points at the rate ``fs/2^stages``, its bins at the same
    frequencies. The caller guarantees that the pass band lies within a quarter of that rate
    (:func:`analysis.resample.plan_chunks`: flat there, nothing folded in); ``n_out`` may
    exceed ``nfft/2^stages`` (the output rate set by the interpolation): the spectrum is then
    zero padded, its Nyquist bin split between its two halves (exact band-limited
    upsampling)."""
    spectrum, fs, nfft = _stage_spectrum(data, fs, nfft, stages)
    return _lowpass_spectrum(spectrum, fs, f_pass, f_stop, nfft, n_out)


def _stage_spectrum(data: np.ndarray, fs: float, nfft: int, stages: int):
    """``(rfft, rate Hz, length)`` of ``data`` zero padded or cut to ``nfft`` samples and
    decimated by ``stages`` half-band stages: the first half of :func:`_fft_lowpass` (one
    spectrum serves several filters)."""
    from scipy import fft

    if data.shape[0] < nfft:
        padded = np.zeros(nfft)
        padded[:data.shape[0]] = data
        data = padded
    data = data[:nfft]
    if stages:
        from ._kernels import halfband_decimate

        taps = _halfband_taps()
        for _ in range(stages):
            data = halfband_decimate(data, taps)
        fs, nfft = fs / (1 << stages), nfft >> stages
    return fft.rfft(data), fs, nfft


def _lowpass_spectrum(spectrum: np.ndarray, fs: float, f_pass: float, f_stop: float,
                      nfft: int, n_out: int, *, own: bool = True) -> np.ndarray:
    """The second half of :func:`_fft_lowpass`: the low-pass applied to ``spectrum`` (rfft of
    ``nfft`` samples at ``fs``) and the filtered signal at ``n_out`` samples (``own``: the
    spectrum may be overwritten)."""
    from scipy import fft

    keep = n_out // 2 + 1
    gain = _lowpass_response(float(fs), float(f_pass), float(f_stop), int(nfft), int(n_out))
    if keep <= spectrum.shape[0]:
        out = spectrum[:keep] if own else spectrum[:keep].copy()
        out *= gain
    else:                           # a higher output rate: zero padded
        out = np.zeros(keep, dtype=spectrum.dtype)
        np.multiply(spectrum, gain, out=out[:spectrum.shape[0]])
        if nfft % 2 == 0:           # the Nyquist bin stands for both halves
            out[nfft // 2] *= 0.5
    return fft.irfft(out, n_out, overwrite_x=True)


@functools.lru_cache(maxsize=64)
def _lowpass_response(fs: float, f_pass: float, f_stop: float, nfft: int,
                      n_out: int) -> np.ndarray:
    """The low-pass response at the ``n_out//2 + 1`` kept bins of an ``nfft``-point transform,
    times the ``n_out/nfft`` of the shorter inverse transform (cached: a record's chunks, and
    the repeated calls of a batch or a bench, share their filters); at most the
    ``nfft//2 + 1`` bins the transform has."""
    keep = min(n_out // 2 + 1, nfft // 2 + 1)
    # the response is 1 below the transition band and 0 above it: interpolate only there
    half = _aa_half_length(f_pass, f_stop)
    f_cut = 0.5 * (f_pass + f_stop)
    reach = 6.0 / half                        # the tabulated step is flat beyond |v| = 6
    lo = int(np.clip(np.floor((f_cut - reach) * nfft / fs), 0, keep))
    hi = int(np.clip(np.ceil((f_cut + reach) * nfft / fs) + 1, lo, keep))
    gain = np.zeros(keep)
    gain[lo:hi] = _lowpass_gain(np.arange(lo, hi) * (fs / nfft), f_pass, f_stop)
    if lo > 0:                                # below the band: the tabulated 1 - C(-v) ≈ 1
        gain[:lo] = _lowpass_gain(np.array([0.0]), f_pass, f_stop)[0]
    gain *= n_out / nfft
    gain.flags.writeable = False
    return gain


# ---------------------------------------------------------------------------- chunk plan




