"""Piston-acceleration series: truncation error against cost.

Rows, for λ = 0.25 and λ = 0.45:

* ``series max_order=N`` (N = 2…12): the harmonic series truncated after order N, evaluated by
  Clenshaw's recurrence; error = max |a_series − a_exact| / (r ω²) over 3600 crank angles,
  against the exact closed form; bound = :func:`predict.kinematics.truncation_bound` (the sum of
  the dropped |aₙ|, attained at TDC); time per call on 10⁵ angles (2·10⁴ with ``--quick``),
  baseline = the exact closed form, all timed in interleaved rounds
  (:func:`analysis.bench.compare`);
* ``series_coefficients``: the exact Fourier coefficients a₂…a₂₀ against mpmath quadrature at
  60 digits (max relative error; bound 1e-13), timed against one mpmath coefficient;
* ``exact formula``: the closed form against mpmath's second derivative of the piston
  position (max error relative to r ω²; bound 1e-12).
"""

from __future__ import annotations

import numpy as np

from . import Row, compare

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

        def series(th=theta_eval, n=2):
            return kin.piston_acceleration(th, crank_radius=r, rod_length=l, omega=w,
                                           max_order=n)

        cands = {"exact": exact}
        cands.update({f"N={n}": (lambda n=n: series(n=n)) for n in range(2, 13)})
        timing = compare(cands, rounds=repeats, min_time=0.01)
        t_exact = timing.time("exact")
        ref = exact(theta_err)
        for n in range(2, 13):
            err = float(np.abs(series(theta_err, n) - ref).max())
            rows.append(timing.row(
                SUITE, f"series λ={lam:g}", f"N={n}", ("exact", "exact closed form"),
                f"max_order={n}", err, "max abs / (r ω²)", "exact closed form",
                throughput_items=n_eval, throughput_unit="angles/s",
                bound=kin.truncation_bound(lam, n) * (1 + 1e-9) + 1e-15,
                note="bound = Σ|a_n| beyond N"))
        rows.append(timing.row(SUITE, f"exact λ={lam:g}", "exact", None, "closed form", 0.0,
                               "max abs / (r ω²)", "itself", throughput_items=n_eval,
                               throughput_unit="angles/s", note="baseline"))

        # coefficients against mpmath quadrature
        orders = range(2, 21, 2) if not quick else range(2, 13, 2)
        with mp.workdps(60):
            lm = mp.mpf(lam)

            def mp_coef(n):
                c = mp.quad(lambda t: mp.sqrt(1 - lm**2 * mp.sin(t) ** 2) * mp.cos(n * t),
                            [0, mp.pi / 2, mp.pi]) * 2 / mp.pi
                return float(n**2 * c / lm)

            refs = {n: mp_coef(n) for n in orders}
            top = max(orders)
            timing = compare({"ours": lambda: (kin._sqrt_coefficients.cache_clear(),
                                               kin.series_coefficients(lam, top)),
                              "mpmath": lambda: mp_coef(8)}, rounds=3 if quick else 5,
                             min_time=0.005)
        a = kin.series_coefficients(lam, top)
        rel = max(abs(a[n] - v) / abs(v) for n, v in refs.items())
        rows.append(timing.row(SUITE, f"series_coefficients λ={lam:g}", "ours",
                               ("mpmath", "one mpmath coefficient"), f"orders 2..{top}",
                               float(rel), "max rel", "mpmath quad, 60 digits", bound=1e-13))

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
                        bound=1e-12, paired=True))
    return rows
