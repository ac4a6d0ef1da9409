"""Piston-acceleration series: truncation error against cost.

Rows, for λ = 0.25 and λ = 0.45:

* ``series max_order=N`` (N = 2…12): the harmonic series truncated after order N, evaluated by
  Clenshaw's recurrence; error = max |a_series − a_exact| / (r ω²) over 3600 crank angles,
  against the exact closed form; bound = :func:`predict.kinematics.truncation_bound` (the sum of
  the dropped |aₙ|, attained at TDC); time per call on 10⁵ angles (2·10⁴ with ``--quick``),
  baseline = the exact closed form timed side by side in the same run;
* ``series_coefficients``: the exact Fourier coefficients a₂…a₂₀ against mpmath quadrature at
  60 digits (max relative error; bound 1e-13), timed against one mpmath coefficient;
* ``exact formula``: the closed form against mpmath's second derivative of the piston
  position (max error relative to r ω²; bound 1e-12).
"""

from __future__ import annotations

import numpy as np

from . import Row, median_time

__all__ = ["run"]

SUITE = "kinematics"


def run(quick: bool) -> list[Row]:
    import mpmath as mp

    from crankbench.predict import kinematics as kin

    rows: list[Row] = []
    n_eval = 20_000 if quick else 100_000
    repeats = 3 if quick else 7
    theta_eval = np.linspace(0.0, 2 * np.pi, n_eval)
    theta_err = np.linspace(0.0, 2 * np.pi, 3600, endpoint=False)
    for lam in (0.25, 0.45):
        r, l, w = 1.0, 1.0 / lam, 1.0

        def exact(th=theta_eval):
            return kin.piston_acceleration(th, crank_radius=r, rod_length=l, omega=w)

        t_exact = median_time(exact, repeats=repeats, min_time=0.01)
        ref = exact(theta_err)
        for n in range(2, 13):
            def series(th=theta_eval, n=n):
                return kin.piston_acceleration(th, crank_radius=r, rod_length=l, omega=w,
                                               max_order=n)

            t = median_time(series, repeats=repeats, min_time=0.01)
            err = float(np.abs(series(theta_err) - ref).max())
            rows.append(Row(
                suite=SUITE, method=f"series λ={lam:g}", setting=f"max_order={n}", error=err,
                error_kind="max abs / (r ω²)", reference="exact closed form", time_s=t,
                baseline="exact closed form", ratio=t / t_exact,
                throughput=n_eval / t, throughput_unit="angles/s",
                bound=kin.truncation_bound(lam, n) * (1 + 1e-9) + 1e-15,
                note="bound = Σ|a_n| beyond N"))
        rows.append(Row(suite=SUITE, method=f"exact λ={lam:g}", setting="closed form",
                        error=0.0, error_kind="max abs / (r ω²)", reference="itself",
                        time_s=t_exact, baseline="exact closed form", ratio=1.0,
                        throughput=n_eval / t_exact, throughput_unit="angles/s",
                        note="baseline"))

        # coefficients against mpmath quadrature
        orders = range(2, 21, 2) if not quick else range(2, 13, 2)
        with mp.workdps(60):
            lm = mp.mpf(lam)

            def mp_coef(n):
                c = mp.quad(lambda t: mp.sqrt(1 - lm**2 * mp.sin(t) ** 2) * mp.cos(n * t),
                            [0, mp.pi / 2, mp.pi]) * 2 / mp.pi
                return float(n**2 * c / lm)

            refs = {n: mp_coef(n) for n in orders}
            t_mp = median_time(lambda: mp_coef(8), repeats=1, warmup=0)
        top = max(orders)
        kin._sqrt_coefficients.cache_clear()
        t_coef = median_time(lambda: (kin._sqrt_coefficients.cache_clear(),
                                      kin.series_coefficients(lam, top)),
                             repeats=repeats, min_time=0.005)
        a = kin.series_coefficients(lam, top)
        rel = max(abs(a[n] - v) / abs(v) for n, v in refs.items())
        rows.append(Row(suite=SUITE, method=f"series_coefficients λ={lam:g}",
                        setting=f"orders 2..{top}", error=float(rel), error_kind="max rel",
                        reference="mpmath quad, 60 digits", time_s=t_coef,
                        baseline="one mpmath coefficient", ratio=t_coef / t_mp, bound=1e-13))

        # exact closed form against mpmath's derivative of the position
        pts = np.linspace(0.05, 2 * np.pi, 12 if quick else 48)
        with mp.workdps(30):
            def pos(t):
                return mp.cos(t) + l * mp.sqrt(1 - (mp.sin(t) / l) ** 2)

            mref = np.array([float(mp.diff(pos, float(t), 2)) for t in pts])
        err = float(np.abs(exact(pts) - mref).max())
        rows.append(Row(suite=SUITE, method=f"exact formula λ={lam:g}", setting="closed form",
                        error=err, error_kind="max abs / (r ω²)",
                        reference="mpmath diff of x(θ), 30 digits", time_s=t_exact,
                        baseline="exact closed form", ratio=1.0, bound=1e-12))
    return rows
