"""Crossfade between the anti-alias filters of neighbouring chunks of an angle resampling.

:func:`analysis.resample.plan_chunks` gives each chunk of a record its own anti-alias low-pass
(pass band to ``samples_per_rev/4`` at the chunk's top speed, stop band from ``3/4
samples_per_rev`` at its lowest). In the pass band every chunk's filter is flat (ripple 1e-5),
but in the transition band two neighbours differ: at the boundary of a 1000–2000 and a
2000–3000 rpm chunk, order 24 at 2000 rpm (800 Hz) is stopped by the first and passed by the
second. A signal with content there (any engine record: high firing orders, gear mesh) then
switches it on or off at the boundary, and the step spreads over every order of the analysis
block that straddles it: on a 1000→3000 rpm run-up at 20 kHz a unit tone at order 20–30
read 1.5–1.9e-3 at order 16 and moved order 4.5's amplitude by up to 4e-3 (measured with the
order map, 16-revolution blocks, before this module).

Here the switch is made gradual: within ``BLEND_REVOLUTIONS`` revolutions (at the faster
chunk's top speed) either side of a boundary, the angle samples are ``(1 − λ) y_k + λ y_{k+1}``
with ``λ`` a raised cosine from 0 to 1, ``y_k`` and ``y_{k+1}`` the two chunks' filtered,
interpolated signals. Both are computed from short windows around the boundary (one small FFT
low-pass each, with each chunk's own filter: the response of a Kaiser-windowed ideal
low-pass is its exact Fourier transform, so any transform length longer than the impulse
response applies the same filter), so the zone needs nothing but the input samples around the
boundary: the in-memory and the streamed resampling compute it alike. In the pass band both
signals agree to the filters' ripple, so the blend changes nothing there; a transition-band
component is faded over 4 revolutions instead of switched, and what leaks from the fade into
orders 4 or more away falls below 1e-5 (``tests/analysis/test_ordermap_antialias.py``).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["BLEND_REVOLUTIONS", "blend_widths", "zone_input", "zone_values"]

#: revolutions of the crossfade on either side of a chunk boundary (at the faster chunk's top
#: speed; more at lower speeds)
BLEND_REVOLUTIONS = 2.0


def blend_widths(bounds, ranges, bands, halves, reach, fs: float, n: int) -> tuple:
    """Half-width (input samples) of the crossfade at each chunk's upper boundary.

    Parameters
    ----------
    bounds : ndarray
        Chunk limits (input sample indices), ``len = chunks + 1``.
    ranges : list of (float, float)
        Each chunk's lowest and highest speed, rpm.
    bands : sequence
        Each chunk's ``(f_pass, f_stop)`` (Hz) or None (no filter).
    halves, reach : sequence of int
        Each chunk's filter margin and interpolation reach, input samples.
    fs : float
        Input sample rate, Hz.
    n : int
        Input samples in the record.

    Returns
    -------
    tuple of int
        Per chunk (the last: 0); 0 where the two filters are the same (nothing switches) or
        where the zone with its margins would not fit inside the chunks and the record.
    """
    widths = []
    for k in range(len(bands) - 1):
        if bands[k] == bands[k + 1]:
            widths.append(0)
            continue
        top = max(ranges[k][1], ranges[k + 1][1])
        w = int(math.ceil(BLEND_REVOLUTIONS * 60.0 * fs / top))
        c0, c1, c2 = int(bounds[k]), int(bounds[k + 1]), int(bounds[k + 2])
        w = min(w, (c1 - c0) // 2, (c2 - c1) // 2)
        margin = max(halves[k] + reach[k], halves[k + 1] + reach[k + 1])
        if w <= 0 or c1 - w - margin < 0 or c1 + w + margin > n:
            w = 0
        widths.append(w)
    widths.append(0)
    return tuple(widths)


def zone_input(plan, k: int) -> tuple[int, int]:
    """Input samples ``[a, b)`` that the crossfade at chunk ``k``'s upper boundary reads (an
    empty range at ``bounds[k + 1]`` without one)."""
    c1 = int(plan.bounds[k + 1])
    if not (plan.blends and plan.blends[k]):
        return c1, c1
    a, size = _patch(plan, k)
    return a, min(a + size, plan.n)


def _patch(plan, k: int) -> tuple[int, int]:
    """First input sample and transform length of the zone at boundary ``k``: the zone with
    the wider of the two sides' margins (filter and interpolation reach) either side."""
    from .antialias import _good_size

    w = plan.blends[k]
    margin = max(plan.filter_half[k] + plan.reach[k],
                 plan.filter_half[k + 1] + plan.reach[k + 1])
    return int(plan.bounds[k + 1]) - w - margin, _good_size(2 * (w + margin))


def zone_values(plan, k: int, values: np.ndarray, start: int, u: np.ndarray) -> np.ndarray:
    """The crossfaded signal at input positions ``u`` inside the zone at chunk ``k``'s upper
    boundary (``values`` are input samples from index ``start``; they cover
    :func:`zone_input`)."""
    c1, w = int(plan.bounds[k + 1]), plan.blends[k]
    a, size = _patch(plan, k)
    data = values[a - start:min(a + size, plan.n) - start]
    lam = 0.5 - 0.5 * np.cos(np.pi * (u - (c1 - w)) / (2.0 * w))
    spectra = {}                 # one transform per stage count: both sides usually share it
    lower = _side(plan, k, data, a, size, u, spectra)
    upper = _side(plan, k + 1, data, a, size, u, spectra)
    return lower + lam * (upper - lower)


def _side(plan, k: int, data: np.ndarray, a: int, size: int, u: np.ndarray,
          spectra: dict) -> np.ndarray:
    """Chunk ``k``'s filter (transform length ``size``; ``data``, input samples from ``a``,
    zero padded to it) and interpolation, read at positions ``u``; ``spectra`` holds the
    decimated transforms already made, by stage count."""
    from .antialias import _good_size, _lowpass_spectrum, _stage_spectrum
    from .resample import _interp

    band = plan.bands[k]
    if band is None:
        return _interp(data, u - a, plan.interpolation)
    stages = plan.halfband_stages[k] if plan.halfband_stages else 0
    while stages and size % (1 << stages):
        stages -= 1
    nfft, n_out = plan.lengths[k]
    out = size if n_out == nfft else min(size, _good_size(int(math.ceil(size * n_out / nfft))))
    if stages not in spectra:
        spectra[stages] = _stage_spectrum(data, plan.fs, size, stages)
    spectrum, fs_s, n_s = spectra[stages]
    filtered = _lowpass_spectrum(spectrum, fs_s, band[0], band[1], n_s, out, own=False)
    return _interp(filtered, (u - a) * (out / size), plan.interpolation)
