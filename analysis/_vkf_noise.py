"""Noise and smearing estimates of the Vold–Kalman filter (:mod:`analysis.vkf`), compiled when
numba is present (as :mod:`analysis._vkf_kernels`, whose conventions they follow).

Each function has a numpy twin that gives the same result to rounding
(``tests/analysis/test_vkf_kernels.py`` runs both):

* :func:`lower_quartiles` — the lower quartile of the residual's spectrum beside each order
  (twin: ``np.percentile`` frame by frame);
* :func:`local_levels` — those quartiles per frame and order, as a noise density at every
  sample (twin: :func:`lower_quartiles` and ``np.interp`` per order);
* :func:`notch_depth` — the joint solve's own notches in the residual's short-time spectra
  (compiled form only; its twin is :func:`analysis.vkf._notch_depth`, one scatter of all lines'
  log factors);
* :func:`noise_smearing` — the noise part and the envelope-smearing estimate from the
  envelopes' second differences.

``CRANKBENCH_NO_NUMBA=1`` forces the twins; :func:`accelerated` says which are in use.
"""

from __future__ import annotations

import functools

import numpy as np

__all__ = ["accelerated", "lower_quartiles", "local_levels", "notch_depth", "noise_smearing"]

#: compiled helper called by another compiled kernel (set by :func:`_numba`)
_JIT_QUARTILES = None


@functools.lru_cache(maxsize=1)
def _numba():
    """The compiled kernels, or None (numba missing, or ``CRANKBENCH_NO_NUMBA`` set)."""
    from ._vkf_kernels import njit_or_none

    njit = njit_or_none()
    if njit is None:
        return None
    # kernels that call kernels reach them as module globals, not closure cells (numba keys its
    # on-disk cache on the pickled closure cells, which differ from process to process)
    global _JIT_QUARTILES

    @njit(cache=True)
    def quartiles(spec, freq, flat, f_frame, reach):  # pragma: no cover - compiled
        frames, bins = spec.shape
        level = np.zeros(frames)
        buf = np.empty(bins)
        for i in range(frames):
            f0 = f_frame[i]
            cnt = 0
            for b in range(bins):
                v = spec[i, b]
                if flat[b] and v == v and abs(freq[b] - f0) <= reach:
                    buf[cnt] = v
                    cnt += 1
            if cnt < 5:
                cnt = 0
                for b in range(bins):
                    v = spec[i, b]
                    if flat[b] and v == v:
                        buf[cnt] = v
                        cnt += 1
            if cnt == 0:
                continue
            v = np.sort(buf[:cnt])
            # numpy's default ('linear') percentile
            pos = 0.25 * (cnt - 1)
            lo = int(np.floor(pos))
            hi = min(lo + 1, cnt - 1)
            frac = pos - lo
            level[i] = v[lo] + (v[hi] - v[lo]) * frac
        return level

    _JIT_QUARTILES = quartiles

    @njit(cache=True)
    def levels(spec, freq, flat, centre, f_ord, reach):  # pragma: no cover - compiled
        nd, k = f_ord.shape
        frames = centre.shape[0]
        out = np.empty((nd, k))
        f_frame = np.empty(frames)
        last = nd - 1.0
        for j in range(k):
            for i in range(frames):             # np.interp(centre, arange(nd), f_ord[:, j])
                c = centre[i]
                if c <= 0.0:
                    f_frame[i] = f_ord[0, j]
                elif c >= last:
                    f_frame[i] = f_ord[nd - 1, j]
                else:
                    g = int(c)
                    f_frame[i] = (f_ord[g + 1, j] - f_ord[g, j]) * (c - g) + f_ord[g, j]
            level = _JIT_QUARTILES(spec, freq, flat, f_frame, reach[j]) / np.log(4.0 / 3.0)
            # np.interp(arange(nd), centre, level)
            i = 0
            for t in range(nd):
                if frames == 1 or t <= centre[0]:
                    out[t, j] = level[0]
                elif t >= centre[frames - 1]:
                    out[t, j] = level[frames - 1]
                else:
                    while centre[i + 1] <= t:
                        i += 1
                    slope = (level[i + 1] - level[i]) / (centre[i + 1] - centre[i])
                    out[t, j] = slope * (t - centre[i]) + level[i]
        return out

    @njit(cache=True, error_model="numpy")
    def notch(f_ord, bw_d, starts, offsets, weights, bins, df, trend_hz, fs_d, p,
              reach_per_hz):                   # pragma: no cover - compiled
        # analysis.vkf._notch_depth (the numpy twin) frame by frame: the product of the
        # (1 - H)² factors of every line near each bin at 3 instants, window-weighted
        nd, k = f_ord.shape
        frames = starts.shape[0]
        lines = 2 * k + (1 if trend_hz > 0 else 0)
        depth = np.zeros((frames, bins))
        if lines == 0:
            depth[:, :] = 1.0
            return depth
        inst = offsets.shape[0]
        centre = np.empty((inst, lines, frames))
        band = np.full((inst, lines, frames), trend_hz)
        if trend_hz > 0:
            centre[:, lines - 1, :] = 0.0
        for i in range(inst):
            for f in range(frames):
                at = min(max(starts[f] + offsets[i], 0.0), nd - 1.0)
                g = min(int(np.floor(at)), nd - 2) if nd > 1 else 0
                frac = at - g
                for m in range(k):
                    if nd > 1:
                        c = f_ord[g, m] + (f_ord[g + 1, m] - f_ord[g, m]) * frac
                        b = bw_d[g, m] + (bw_d[g + 1, m] - bw_d[g, m]) * frac
                    else:
                        c = f_ord[0, m]
                        b = bw_d[0, m]
                    centre[i, 2 * m, f] = c
                    centre[i, 2 * m + 1, f] = -c
                    b = max(b, 1e-12)
                    band[i, 2 * m, f] = b
                    band[i, 2 * m + 1, f] = b
        # bins from the line's lowest reach on, as many as its widest band there reaches
        span = np.empty((inst, lines), np.int64)
        for i in range(inst):
            for ln in range(lines):
                top = 0.0
                for f in range(frames):
                    top = max(top, band[i, ln, f])
                span[i, ln] = int(np.ceil(reach_per_hz * top / df)) + 1
        r2_scale = 0.5 * (np.sqrt(2.0) - 1.0)
        prod = np.empty(bins)
        for i in range(inst):
            w = weights[i]
            for f in range(frames):
                prod[:] = 1.0
                for ln in range(lines):
                    c = centre[i, ln, f]
                    b = band[i, ln, f]
                    d = 2.0 * np.sin(np.pi * b / (2.0 * fs_d))
                    r2 = r2_scale / d ** (2 * p)       # vkf_weight(b, fs_d, p)²
                    first = int(np.floor((c - reach_per_hz * b) / df))
                    for col in range(max(first, 0), min(first + 2 * span[i, ln] + 1, bins)):
                        s = 2.0 * np.sin(np.pi * (col * df - c) / fs_d)
                        s2 = s * s
                        h = 1.0 / (1.0 + 2.0 * r2 * (s2 if p == 1 else s2 * s2))
                        prod[col] *= (1.0 - h) * (1.0 - h)
                for col in range(bins):
                    depth[f, col] += w * prod[col]
        for f in range(frames):
            for col in range(bins):
                if not depth[f, col] >= 0.25:
                    depth[f, col] = np.nan
        return depth

    @njit(cache=True)
    def smearing(env, n0, bw_d, per_n0, b_med, span, p, kp, fs_d, enbw_per_hz):  # pragma: no cover
        n, k = env.shape
        noise = np.empty((n, k))
        out = np.empty((n, k))
        for i in range(n):
            for j in range(k):
                noise[i, j] = np.sqrt(n0[i, j] * (bw_d[i, j] * enbw_per_hz))
                out[i, j] = 0.0
        a2 = np.empty(n)
        x2 = np.empty(n)
        c = np.empty(n + 1)
        expo = 5 if p == 2 else 4
        fs2 = fs_d * fs_d
        for j in range(k):
            # |A''|² by central differences (ends: their neighbours'), cumulated
            c[0] = 0.0
            for i in range(n):
                ii = min(max(i, 1), n - 2)
                d = (env[ii + 1, j] - 2.0 * env[ii, j] + env[ii - 1, j]) * fs2
                x2[i] = d.real * d.real + d.imag * d.imag
                c[i + 1] = c[i] + x2[i]
            length = span[j]
            if length <= 1 or n <= length:
                a2[:] = x2
            else:
                pad = (length - 1) // 2
                n_mid = n - length + 1
                for i in range(n):
                    t = min(max(i - pad, 0), n_mid - 1)
                    a2[i] = (c[t + length] - c[t]) / length
            inv_med = 1.0 / b_med[j]
            noise_scale = 20.0 * per_n0[j]
            for i in range(n):
                # (products, not ** with a run-time exponent: a pow call per sample)
                bw = bw_d[i, j]
                rel = bw * inv_med
                rel4 = rel * rel
                rel4 *= rel4
                val = a2[i] - noise_scale * n0[i, j] * (rel4 * rel if expo == 5 else rel4)
                if val <= 0.0:
                    continue
                e = env[i, j]
                amp2 = e.real * e.real + e.imag * e.imag
                amp = np.sqrt(amp2)
                pb2 = np.pi * bw
                pb2 *= pb2
                if p == 2:                      # K_p (|A''|/(8|A|))² / (πB)⁴
                    loss = kp * val / (64.0 * max(amp2, 1e-300) * pb2 * pb2)
                else:
                    loss = kp * np.sqrt(val) / (8.0 * max(amp, 1e-300) * pb2)
                out[i, j] = min(loss, 1.0) * amp
        return noise, out

    return {"quartiles": quartiles, "levels": levels, "notch": notch, "smearing": smearing}


def accelerated() -> bool:
    """True when the compiled noise kernels are in use."""
    return _numba() is not None


def lower_quartiles(spec, freq, flat, f_frame, reach: float) -> np.ndarray:
    """Per frame ``i``: the 25th percentile (numpy's linear rule) of ``spec[i]`` over the bins
    of ``flat`` within ``reach`` of ``f_frame[i]``, NaN bins left out (all non-NaN ``flat``
    bins when fewer than 5 qualify; 0 when none)."""
    kernels = _numba()
    if kernels is not None:
        return kernels["quartiles"](np.ascontiguousarray(spec), np.ascontiguousarray(freq),
                                    np.ascontiguousarray(flat), np.ascontiguousarray(f_frame,
                                                                                     dtype=float),
                                    float(reach))
    level = np.zeros(spec.shape[0])
    for i, f0 in enumerate(f_frame):
        ok = flat & ~np.isnan(spec[i])
        near = ok & (np.abs(freq - f0) <= reach)
        if near.sum() < 5:
            near = ok
        if near.any():
            level[i] = float(np.percentile(spec[i, near], 25.0))
    return level


def notch_depth(f_ord, bw_d, starts, offsets, weights, bins: int, df: float, trend_hz: float,
                fs_d: float, p: int, reach_per_hz: float):
    """Compiled form of :func:`analysis.vkf._notch_depth` (its numpy twin, which calls this
    when :func:`accelerated`): the expected residual power per (frame, bin) relative to the
    input's, NaN below 1/4. ``offsets``/``weights``: the instants in each frame (samples from
    its start) and their weights."""
    return _numba()["notch"](np.ascontiguousarray(f_ord, dtype=float),
                             np.ascontiguousarray(bw_d, dtype=float),
                             np.ascontiguousarray(starts, dtype=float),
                             np.ascontiguousarray(offsets, dtype=float),
                             np.ascontiguousarray(weights, dtype=float), int(bins), float(df),
                             float(trend_hz), float(fs_d), int(p), float(reach_per_hz))


def local_levels(spec, freq, flat, centre, f_ord, reach) -> np.ndarray:
    """Noise density per sample and order (N, K): per frame, :func:`lower_quartiles` of
    ``spec`` within ``reach[j]`` of order ``j``'s frequency at the frame's centre (``centre``:
    sample positions, increasing; ``f_ord`` (N, K) in Hz), divided by ln(4/3) (the lower
    quartile of an exponential variable), then linearly interpolated to every sample."""
    kernels = _numba()
    reach = np.broadcast_to(np.asarray(reach, float), (f_ord.shape[1],))
    if kernels is not None:
        return kernels["levels"](np.ascontiguousarray(spec), np.ascontiguousarray(freq),
                                 np.ascontiguousarray(flat), np.ascontiguousarray(centre,
                                                                                  dtype=float),
                                 np.ascontiguousarray(f_ord, dtype=float),
                                 np.ascontiguousarray(reach))
    nd, k = f_ord.shape
    grid = np.arange(nd)
    out = np.empty((nd, k))
    for j in range(k):
        f_frame = np.interp(centre, grid, f_ord[:, j])
        level = lower_quartiles(spec, freq, flat, f_frame, float(reach[j])) / np.log(4.0 / 3.0)
        out[:, j] = np.interp(grid, centre, level)
    return out


# ---------------------------------------------------------------------------- smearing


def noise_smearing(env, n0, bw_d, per_n0, b_med, span, p: int, kp: float, fs_d: float,
                   enbw_per_hz: float):
    """(noise, smearing), each (N, K): the noise part ``sqrt(n0 · ENBW)`` with
    ``ENBW = enbw_per_hz · B``, and the smearing bias of each envelope (Lorentzian model),
    ``min(K_p (|A''|/(8|A|))^p/(πB)^{2p}, 1)·|A|`` with ``|A''|²`` (central
    differences) averaged over ``span[j]`` samples, less ten times its expected noise part
    ``2 n0 · per_n0[j] (B/b_med[j])^{5 (p = 2) or 4}``. See :func:`analysis.vkf._uncertainty`."""
    kernels = _numba()
    if kernels is not None:
        return kernels["smearing"](np.ascontiguousarray(env), np.ascontiguousarray(n0),
                                   np.ascontiguousarray(bw_d, dtype=float),
                                   np.asarray(per_n0, float), np.asarray(b_med, float),
                                   np.asarray(span, np.int64), int(p), float(kp), float(fs_d),
                                   float(enbw_per_hz))
    noise = np.sqrt(n0 * (bw_d * enbw_per_hz))
    n, k = env.shape
    d2 = np.zeros_like(env)
    d2[1:-1] = (env[2:] - 2.0 * env[1:-1] + env[:-2]) * fs_d ** 2
    d2[0], d2[-1] = d2[1], d2[-2]
    out = np.zeros((n, k))
    amp = np.abs(env)
    for j in range(k):
        bw = bw_d[:, j]
        noise2 = 20.0 * n0[:, j] * per_n0[j] * (bw / b_med[j]) ** (5 if p == 2 else 4)
        a2 = np.maximum(_moving_mean(np.abs(d2[:, j]) ** 2, int(span[j])) - noise2, 0.0)
        ratio = np.sqrt(a2) / np.maximum(amp[:, j], 1e-300)
        loss = kp * (ratio / 8.0) ** p / (np.pi * bw) ** (2 * p)
        out[:, j] = np.minimum(loss, 1.0) * amp[:, j]
    return noise, out


def _moving_mean(x, length):
    """Centred moving mean over ``length`` samples (the ends hold the first/last full mean)."""
    if length <= 1 or x.shape[0] <= length:
        return x
    c = np.concatenate([[0.0], np.cumsum(x)])
    out = (c[length:] - c[:-length]) / length
    pad_a = (length - 1) // 2
    return np.concatenate([np.full(pad_a, out[0]), out,
                           np.full(x.shape[0] - out.shape[0] - pad_a, out[-1])])
