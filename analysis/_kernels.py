"""Inner loops of the angle resampling, compiled when numba is installed.

Each function has a plain-numpy twin that gives the same result to rounding; the compiled one
runs the loop once over the samples instead of several whole-array passes (the sinc
interpolation gathers 16 taps per output: about 10× faster compiled). numba is a core
dependency; where it cannot be imported everything works, slower (the README's tracker-speed
figures, bench suite ``orders``, give both). :func:`accelerated` says which is in use (``crankbench bench`` prints it);
``CRANKBENCH_NO_NUMBA=1`` forces the numpy forms. ``tests/analysis/test_kernels.py`` checks
that both forms agree.
"""

from __future__ import annotations

import functools

import numpy as np

__all__ = ["accelerated", "integrate_speed", "positions", "lerp", "positions_and_values",
           "sinc_interp", "halfband_decimate", "angle_grid"]


@functools.lru_cache(maxsize=1)
def _numba():
    """The compiled kernels, or None (numba not installed, or disabled by
    ``CRANKBENCH_NO_NUMBA=1``)."""
    import os

    if os.environ.get("CRANKBENCH_NO_NUMBA"):
        return None
    try:
        from numba import njit
    except ImportError:
        return None

    @njit(cache=True)
    def integrate(speed, scale, start):   # pragma: no cover - compiled
        n = speed.shape[0]
        phi = np.empty(n)
        if n == 0:
            return phi
        phi[0] = start
        acc = start
        for i in range(n - 1):
            acc = acc + (speed[i + 1] + speed[i]) * scale
            phi[i + 1] = acc
        return phi

    @njit(cache=True)
    def invert_lerp(phi, targets, offset, values):   # pragma: no cover - compiled
        # both sorted: one merge pass, the same interpolation formula as numpy.interp for the
        # positions, and interp_at's for `values` there
        n, m = phi.shape[0], targets.shape[0]
        out = np.empty(m)
        at = np.empty(m)
        i = 0
        for k in range(m):
            x = targets[k]
            if x <= phi[0]:
                out[k] = offset
                at[k] = values[0]
                continue
            if x >= phi[n - 1]:
                out[k] = offset + n - 1.0
                at[k] = values[n - 1]
                continue
            while phi[i + 1] <= x:
                i += 1
            frac = (1.0 / (phi[i + 1] - phi[i])) * (x - phi[i])
            out[k] = frac + (offset + i)
            at[k] = (values[i + 1] - values[i]) * frac + values[i]
        return out, at

    @njit(cache=True)
    def interp_at(values, pos, offset):   # pragma: no cover - compiled
        n = values.shape[0]
        out = np.empty(pos.shape[0])
        for k in range(pos.shape[0]):
            u = pos[k] - offset
            i = int(np.floor(u))
            if i < 0:
                out[k] = values[0]
            elif i >= n - 1:
                out[k] = values[n - 1]
            else:
                out[k] = (values[i + 1] - values[i]) * (u - i) + values[i]
        return out

    # the weights are table[r] + f (table[r + 1] - table[r]) (linear between tabulated
    # phases), so the sum is two dot products of the samples: with the row and with the
    # row's difference to the next (``steps``), combined once per output instead of forming
    # each weight; the numpy form's result within 1e-13 of the signal
    # (tests/analysis/test_kernels.py); reassociated (vectorised) and fused, NaN/inf kept
    @njit(cache=True, fastmath={"reassoc", "contract"})
    def sinc(y, pos, table, steps, half, phases):  # pragma: no cover - compiled
        m = y.shape[0]
        taps = 2 * half
        out = np.empty(pos.shape[0])
        for k in range(pos.shape[0]):
            u = pos[k]
            i0 = int(np.floor(u))
            if i0 < half - 1:
                i0 = half - 1
            if i0 > m - 1 - half:
                i0 = m - 1 - half
            p = (u - i0) * phases
            r = int(p)
            if r > phases - 1:
                r = phases - 1
            if r < 0:
                r = 0
            f = p - r
            base = i0 - (half - 1)
            row = table[r]
            step = steps[r]
            ys = y[base:base + taps]
            a0 = 0.0
            a1 = 0.0
            for j in range(taps):
                a0 += row[j] * ys[j]
                a1 += step[j] * ys[j]
            out[k] = a0 + f * a1
        return out

    @njit(cache=True, fastmath={"reassoc", "contract"})
    def halfband(x, taps):   # pragma: no cover - compiled
        # y[j] = x[2j]/2 + sum_k taps[k] (x[2j-2k-1] + x[2j+2k+1]), zeros outside x. The odd
        # samples are copied out first, zero padded (o[8 + i] = x[2i + 1]), so the sum reads
        # o[j+7-k] + o[j+8+k]: unit stride, the 8 taps written out (vectorised: a loop over
        # the taps on x itself ran 4x slower)
        n = x.shape[0]
        m = (n + 1) // 2
        n_odd = n // 2
        o = np.empty(n_odd + 16)
        o[:8] = 0.0
        o[n_odd + 8:] = 0.0
        for i in range(n_odd):
            o[8 + i] = x[2 * i + 1]
        out = np.empty(m)
        t0, t1, t2, t3 = taps[0], taps[1], taps[2], taps[3]
        t4, t5, t6, t7 = taps[4], taps[5], taps[6], taps[7]
        for j in range(m):
            b = j + 8
            out[j] = (0.5 * x[2 * j] + t0 * (o[b - 1] + o[b]) + t1 * (o[b - 2] + o[b + 1])
                      + t2 * (o[b - 3] + o[b + 2]) + t3 * (o[b - 4] + o[b + 3])
                      + t4 * (o[b - 5] + o[b + 4]) + t5 * (o[b - 6] + o[b + 5])
                      + t6 * (o[b - 7] + o[b + 6]) + t7 * (o[b - 8] + o[b + 7]))
        return out

    @njit(cache=True)
    def grid(speed, scale, dphi, first, last, bound):   # pragma: no cover - compiled
        # integrate's running sum, and in the same pass the positions (invert_lerp's
        # formula) where it reaches j·dphi, j from ceil(phi[first]/dphi) to
        # floor(phi[last]/dphi), with the speed interpolated there
        n = speed.shape[0]
        phi = np.empty(n)
        pos = np.empty(bound)
        at = np.empty(bound)
        phi[0] = 0.0
        acc = 0.0
        j = 0
        x = 0.0
        m = 0
        for i in range(n - 1):
            nxt = acc + (speed[i + 1] + speed[i]) * scale
            phi[i + 1] = nxt
            if i == first:
                j = int(np.ceil(acc / dphi))
                x = j * dphi
            if first <= i <= last:
                while x < nxt and (i < last or x <= acc) and m < bound:
                    frac = (1.0 / (nxt - acc)) * (x - acc)
                    pos[m] = frac + i
                    at[m] = (speed[i + 1] - speed[i]) * frac + speed[i]
                    m += 1
                    j += 1
                    x = j * dphi
            acc = nxt
        return phi, pos[:m], at[:m], j - m

    return {"integrate": integrate, "interp_at": interp_at, "sinc": sinc,
            "invert_lerp": invert_lerp, "halfband": halfband, "grid": grid}


def accelerated() -> bool:
    """True when the compiled kernels are in use."""
    return _numba() is not None



def integrate_speed(speed_rpm: np.ndarray, fs: float, start: float) -> np.ndarray:
    """Trapezoidal shaft angle (rad) of a speed (rpm) span, ``start`` at its first sample;
    sequential, so consecutive spans chain exactly."""
    scale = np.pi / (60.0 * fs)
    kernels = _numba()
    speed = np.ascontiguousarray(speed_rpm, dtype=float)
    if kernels is not None:
        return kernels["integrate"](speed, scale, float(start))
    phi = np.empty(speed.shape[0])
    if phi.shape[0] == 0:
        return phi
    phi[0] = start
    if phi.shape[0] > 1:
        inc = speed[1:] + speed[:-1]
        inc *= scale
        phi[1:] = inc
        np.cumsum(phi, out=phi)
    return phi


def positions(phi: np.ndarray, targets: np.ndarray, offset: int) -> np.ndarray:
    """Fractional sample positions (``offset`` + index) where the increasing ``phi`` reaches
    the increasing ``targets``; like ``numpy.interp(targets, phi, offset + arange)``."""
    kernels = _numba()
    if kernels is not None and phi.shape[0] > 1:
        phi = np.ascontiguousarray(phi, dtype=float)
        return kernels["invert_lerp"](phi, np.ascontiguousarray(targets, dtype=float),
                                      float(offset), phi)[0]
    return np.interp(targets, phi, np.arange(offset, offset + phi.shape[0], dtype=float))


def positions_and_values(phi: np.ndarray, targets: np.ndarray, offset: int,
                         values: np.ndarray):
    """:func:`positions` and :func:`lerp` of ``values`` (samples ``offset …``, like ``phi``)
    at those positions, in one pass when compiled: ``(positions, values there)``."""
    kernels = _numba()
    if kernels is not None and phi.shape[0] > 1:
        return kernels["invert_lerp"](np.ascontiguousarray(phi, dtype=float),
                                      np.ascontiguousarray(targets, dtype=float),
                                      float(offset), np.ascontiguousarray(values, dtype=float))
    pos = positions(phi, targets, offset)
    return pos, lerp(values, pos, offset)


def lerp(values: np.ndarray, pos: np.ndarray, offset: int) -> np.ndarray:
    """``values`` (samples ``offset …``) interpolated linearly at fractional positions."""
    kernels = _numba()
    if kernels is not None and values.shape[0] > 1:
        return kernels["interp_at"](np.ascontiguousarray(values, dtype=float),
                                    np.ascontiguousarray(pos, dtype=float), float(offset))
    return np.interp(pos, np.arange(offset, offset + values.shape[0], dtype=float), values)


def sinc_interp(y: np.ndarray, pos: np.ndarray, table: np.ndarray, steps: np.ndarray,
                half: int, phases: int):
    """Band-limited interpolation with the tabulated kernel: ``table`` (``phases + 1`` rows of
    ``2·half`` weights) and ``steps`` (``table[1:] - table[:-1]``, C-contiguous), linear
    between rows (``None`` without numba: the caller then uses its numpy form)."""
    kernels = _numba()
    if kernels is None:
        return None
    return kernels["sinc"](np.ascontiguousarray(y, dtype=float),
                           np.ascontiguousarray(pos, dtype=float), table, steps, half, phases)


def halfband_decimate(x: np.ndarray, taps: np.ndarray) -> np.ndarray:
    """Half-band low-pass and decimation by 2: ``y[j] = x[2j]/2 + Σ_k taps[k] (x[2j−2k−1] +
    x[2j+2k+1])`` (the half-band filter's even taps other than the centre are zero), samples
    outside ``x`` taken as zero; ``ceil(len(x)/2)`` outputs."""
    x = np.ascontiguousarray(x, dtype=float)
    taps = np.ascontiguousarray(taps, dtype=float)
    kernels = _numba()
    if kernels is not None and taps.shape[0] == 8:
        return kernels["halfband"](x, taps)
    q = taps.shape[0]
    reach = 2 * q - 1
    padded = np.zeros(x.shape[0] + 2 * reach + 1)
    padded[reach:reach + x.shape[0]] = x
    m = (x.shape[0] + 1) // 2
    out = 0.5 * padded[reach:reach + 2 * m:2]
    for k in range(q):
        d = 2 * k + 1
        out += taps[k] * (padded[reach - d:reach - d + 2 * m:2] +
                          padded[reach + d:reach + d + 2 * m:2])
    return out


def angle_grid(speed_rpm: np.ndarray, fs: float, dphi: float, first: int, last: int, *,
               speed_max: float | None = None):
    """The trapezoidal shaft angle (rad, 0 at the first sample; :func:`integrate_speed`) and
    the angle samples ``j·dphi`` from ``ceil(φ[first]/dphi)`` to ``floor(φ[last]/dphi)``:
    ``(phi, j0, positions, speed there)`` — :func:`positions_and_values` of that grid, in the
    same pass as the integration when compiled (0 < first < last < len - 1; ``speed_max``,
    when known, saves a pass)."""
    speed = np.ascontiguousarray(speed_rpm, dtype=float)
    scale = np.pi / (60.0 * fs)
    kernels = _numba()
    if kernels is not None:
        # at most (phi[last] - phi[first]) / dphi + 1 samples; phi[last] <= the sum bound
        top = (float(np.max(speed)) if speed_max is None else speed_max) * 2.0 * scale * (
            last - first + 1)
        bound = int(top / dphi) + 2
        phi, pos, at, j0 = kernels["grid"](speed, scale, float(dphi), int(first), int(last),
                                           bound)
        return phi, int(j0), pos, at
    phi = integrate_speed(speed, fs, 0.0)
    j0 = int(np.ceil(phi[first] / dphi))
    j1 = int(np.floor(phi[last] / dphi))
    grid = np.arange(j0, j1 + 1) * dphi
    pos, at = positions_and_values(phi, grid, 0, speed)
    return phi, j0, pos, at
