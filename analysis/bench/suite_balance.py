"""Balance: the order-domain rotating-vector sums against the time-domain route.

Rows, for sample engines (I4, V8 cross-plane, 5-cylinder radial with articulated rods, 6L
marine):

* ``unbalance (rotating vectors)``: forward/backward force and moment phasors of orders
  1…8 from the exact per-order coefficients; error = largest phasor difference against the
  second route (exact per-cylinder forces summed in time over 1024 samples of one revolution,
  FFT), relative to the engine's total centrifugal force; bound 1e-9. Baseline = that
  time-domain route, timed in interleaved rounds (:func:`analysis.bench.compare`).
* ``time-domain FFT, N samples`` (N = 16…256): aliasing error of the FFT route with fewer
  samples against the exact order-domain phasors (informational: shows how many samples the
  time-domain route needs for a given accuracy), timed against the order-domain route.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import Row, compare

__all__ = ["run"]

SUITE = "balance"
ENGINES = ("i4", "v8_crossplane", "radial5", "marine_6l")


def _engines_dir() -> Path:
    return Path(__file__).resolve().parents[2] / "sample_data" / "engines"


def _fft_route(engine, omega, orders, npts):
    from crankbench.predict.balance import shaking_forces

    th = 2 * np.pi * np.arange(npts) / npts
    ds = shaking_forces(engine, th, omega=omega)
    f = np.fft.fft(ds["force_vertical"].values + 1j * ds["force_horizontal"].values) / npts
    m = np.fft.fft(ds["moment_pitch"].values + 1j * ds["moment_yaw"].values) / npts
    o = np.asarray(orders)
    return f[o], f[npts - o], m[o], m[npts - o]


def run(quick: bool) -> list[Row]:
    from crankbench.predict.balance import unbalance
    from crankbench.predict.engine import Engine

    rows: list[Row] = []
    orders = tuple(range(1, 9))
    repeats = 3 if quick else 7
    for name in ENGINES if not quick else ("i4", "radial5"):
        engine = Engine.from_toml(_engines_dir() / f"{name}.toml")
        omega = engine.rated_speed_rpm * np.pi / 30
        scale = float(np.sum(engine.reciprocating_mass + engine.rotating_mass)
                      * engine.crank_radius) * omega**2
        span = max(float(np.ptp(engine.cylinder_positions)), engine.crank_radius)

        def order_domain():
            return unbalance(engine, omega=omega, orders=orders)

        def time_domain(n=1024):
            return _fft_route(engine, omega, orders, n)

        ns = (16, 32, 64, 256) if not quick else (16, 64)
        cands = {"order": order_domain, "time": time_domain}
        cands.update({f"N={n}": (lambda n=n: time_domain(n)) for n in ns})
        timing = compare(cands, rounds=repeats, min_time=0.01)
        ds = order_domain()
        P, Q, PM, QM = time_domain()
        err = max(np.abs(ds["force_forward_phasor"].values - P).max() / scale,
                  np.abs(ds["force_backward_phasor"].values - Q).max() / scale,
                  np.abs(ds["moment_forward_phasor"].values - PM).max() / (scale * span),
                  np.abs(ds["moment_backward_phasor"].values - QM).max() / (scale * span))
        rows.append(timing.row(SUITE, f"unbalance {name}", "order",
                               ("time", "time-domain sum + FFT (1024)"), "orders 1..8",
                               float(err), "max |Δphasor| / Σ m r ω²",
                               "time-domain sum + FFT, 1024 samples/rev", bound=1e-9))
        for n in ns:
            P, Q, PM, QM = time_domain(n)
            e = max(np.abs(ds["force_forward_phasor"].values - P).max() / scale,
                    np.abs(ds["force_backward_phasor"].values - Q).max() / scale)
            rows.append(timing.row(SUITE, f"time-domain FFT {name}", f"N={n}",
                                   ("order", "order domain"), f"N={n}", float(e),
                                   "max |Δphasor| / Σ m r ω²", "order-domain exact phasors",
                                   note="aliasing of orders > N/2 - 8"))
    return rows
