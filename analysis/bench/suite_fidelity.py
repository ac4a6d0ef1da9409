"""Model only what a scene needs: does the automatic fidelity choice land on the speed–error
front?

For every entry point that picks its own fidelity from a tolerance, the suite times a sweep of
manual settings and the automatic choice on the same problem, each with its error against an
independent reference, and adds one ``pareto distance`` row per entry point and tolerance.

Entry points with an automatic choice (the others take a fixed fidelity and are swept in their
own suites):

* ``predict.kinematics.acceleration_series(lam, tol=...)`` — series order from a tolerance
  relative to r ω². Sweep ``max_order`` = 2, 4, …, 24 (20 quick; λ = 0.25 and 0.45);
  error = max
  |a − a_exact| / (r ω²) over 3600 crank angles (TDC included, where the truncation error is
  largest), reference = the exact closed form (itself checked against mpmath in the kinematics
  suite); time = one evaluation on 2·10⁴ angles (10⁵ in the full run).
* ``predict.lateral.approx.stodola(shaft, rtol=...)`` — iteration count from the Collatz
  bracket. Sweep ``rtol`` = 1e-1 … 1e-12 (the manual knob: every setting is a stop after a
  fixed number of iterations; ``extra['iterations']``); error = |ω − ω_ref| / ω_ref with
  ω_ref from the dense symmetric eigen-solve of the same lumped model (``lumped_exact``);
  time = one call. The shaft: a steel shaft with its own mass (20 lumps) and three disks.

* ``measure.synth.profile.exponential_coastdown(..., tolerance_rpm=...)`` — number of linear
  pieces of the synthetic speed profile from a speed tolerance. Sweep: 1 … 512 equal pieces
  (``from_table``) plus one piece fewer than each automatic choice; error =
  max |n_pw(t) − n0 e^{−t/τ}| (rpm) on 2·10⁵ times against the closed form; time = the crank
  angle at 2·10⁴ times (what the synthesis evaluates).

Metric of the ``pareto distance`` rows (``error_kind = "excess cost rel"``): with f_auto the
fidelity the automatic choice picked (series order, iteration count, piece count) and f* the
lowest manual fidelity whose error is within the same tolerance, distance = max(0,
t(f_auto) / t(f*) − 1), where the two times are taken side by side — alternating calls,
median of the per-pair ratios of CPU time — so a loaded machine slows both alike. Every other
time of the suite comes from one interleaved comparison of all settings of a sweep
(:func:`analysis.bench.compare`). It is 0 when the
automatic choice is f* itself (nothing cheaper meets the tolerance) or extends the front (no
manual setting meets the tolerance); ``inf`` if the automatic choice misses the tolerance. The
cost compared is that of running the chosen setting: for the kinematic series the one-off
choice (``order_for_tolerance``, which sums the dropped tail for every candidate order) is
reported in its own ``choice cost`` row, since the series object is built once and evaluated
many times. ``bound`` (documented tolerance of the metric):

* kinematics 0.25 — the choice uses the rigorous tail bound Σ|aₙ|, attained at TDC within
  15 %, so it may pick one even order above the oracle at most when the tolerance falls inside
  that 15 % band: one more multiply-add per angle, ≤ 25 % of the cost;
* coast-down 0.25 — the piece count comes from the chord-error bound at the start speed, the
  largest one, so it is the cheapest equal spacing meeting the tolerance or one piece more;
* stodola 1.0 — the stop criterion is a guaranteed bracket, whose width shrinks like the
  vector error (ratio ω₁²/ω₂² per step), while the Rayleigh-quotient error shrinks like its
  square; an oracle that knew the true error could stop after about half the iterations, so
  up to twice the oracle's cost is what a guaranteed criterion is documented to pay.

The automatic rows themselves (setting ``tol=…`` / ``rtol=…`` auto) carry ``bound`` = the
tolerance asked for: the bench fails if the automatic choice does not deliver it.
"""

from __future__ import annotations

import numpy as np

from . import Row, compare

__all__ = ["run", "pareto_distance", "paired_ratio"]

SUITE = "fidelity"


def pareto_distance(auto_fidelity, auto_error: float, manual, tol: float, *,
                    cost_ratio) -> float:
    """Relative excess cost of the automatic choice over the cheapest manual setting meeting
    ``tol``.

    Parameters
    ----------
    auto_fidelity : float
        The fidelity the automatic choice used (order, iterations, pieces).
    auto_error : float
        Its error against the reference (same units as ``tol``).
    manual : sequence of (fidelity, error)
        The manual sweep (cost grows with fidelity).
    tol : float
        The tolerance the automatic choice was asked to meet.
    cost_ratio : callable
        ``cost_ratio(f)`` → time of the automatic choice / time of manual fidelity ``f``,
        measured side by side; called only when ``f`` differs from ``auto_fidelity``.

    Returns
    -------
    float
        ``max(0, cost_ratio(f*) − 1)`` with f* the lowest fidelity with error ≤ ``tol``;
        0 if f* is the automatic fidelity or none meets ``tol`` (the automatic choice extends
        the front); ``inf`` if the automatic choice misses ``tol``.

    Examples
    --------
    >>> sweep = [(2, 1e-3), (4, 1e-7), (6, 1e-9), (8, 1e-12)]
    >>> pareto_distance(4, 1e-7, sweep, 1e-6, cost_ratio=lambda f: 9.9)
    0.0
    >>> round(pareto_distance(8, 1e-12, sweep, 1e-6, cost_ratio=lambda f: 1.45), 6)
    0.45
    >>> pareto_distance(2, 1e-3, sweep, 1e-6, cost_ratio=lambda f: 1.0)
    inf
    """
    if not (np.isfinite(auto_error) and auto_error <= tol):
        return float("inf")
    meeting = [f for f, e in manual if np.isfinite(e) and e <= tol]
    if not meeting or min(meeting) >= auto_fidelity:
        return 0.0
    return max(0.0, float(cost_ratio(min(meeting))) - 1.0)


def paired_ratio(func_a, func_b, *, pairs: int = 7, min_time: float = 0.005,
                 cpu_clock=None) -> float:
    """Median over ``pairs`` interleaved rounds of CPU time(func_a) / CPU time(func_b)
    (:func:`analysis.bench.compare`; ``cpu_clock`` as there, default the process's CPU time).

    Each measurement loops the call for about ``min_time`` seconds; alternating A and B makes
    a slow-down of the machine hit both alike.
    """
    extra = {} if cpu_clock is None else {"cpu_clock": cpu_clock}
    return compare({"a": func_a, "b": func_b}, rounds=pairs, min_time=min_time,
                   **extra).ratio("a", "b")[0]


def _timed(quick: bool, cands: dict):
    """All candidates of one sweep in interleaved rounds."""
    if quick:
        return compare(cands, rounds=5, min_time=0.008)
    return compare(cands, rounds=11, min_time=0.02)


def _distance_row(method, tol, auto, manual, label, bound, quick):
    """The ``pareto distance`` row of one entry point and tolerance.

    ``auto`` = (fidelity, error, time, call); ``manual`` = [(fidelity, time, error, call)].
    """
    f_auto, e_auto, t_auto, call_auto = auto
    calls = {f: c for f, _, _, c in manual}
    meeting = [f for f, _, e, _ in manual if e <= tol] + ([f_auto] if e_auto <= tol else [])
    cheapest = min(meeting) if meeting else None
    measured = {}

    def ratio(f):
        measured[f] = paired_ratio(call_auto, calls[f], pairs=9 if quick else 15,
                                   min_time=0.01 if quick else 0.02)
        return measured[f]

    dist = pareto_distance(f_auto, e_auto, [(f, e) for f, _, e, _ in manual], tol,
                           cost_ratio=ratio)
    return Row(suite=SUITE, method=method, setting=f"pareto distance tol={tol:g}", error=dist,
               error_kind="excess cost rel",
               reference=f"cheapest manual setting meeting tol ({label}={cheapest})",
               time_s=t_auto, baseline=f"{label}={cheapest} (side by side)",
               ratio=measured.get(cheapest, 1.0 if cheapest == f_auto else float("nan")),
               bound=bound, note=f"auto {label}={f_auto} vs cheapest {cheapest}",
               extra={"auto": f_auto, "cheapest": cheapest}, paired=bool(measured))


def _kinematics_rows(quick: bool) -> list[Row]:
    from crankbench.predict import kinematics as kin

    rows: list[Row] = []
    n_eval = 20_000 if quick else 100_000
    theta_eval = np.linspace(0.0, 2 * np.pi, n_eval)
    theta_err = np.linspace(0.0, 2 * np.pi, 3600, endpoint=False)
    tols = (1e-3, 1e-6, 1e-10) if quick else (1e-2, 1e-3, 1e-6, 1e-8, 1e-10, 1e-12)
    for lam in (0.25, 0.45):
        method = f"acceleration_series λ={lam:g}"
        l = 1.0 / lam
        ref = kin.piston_acceleration(theta_err, crank_radius=1.0, rod_length=l, omega=1.0)
        series = {n: kin.acceleration_series(lam, max_order=n)
                  for n in range(2, 21 if quick else 25, 2)}
        chosen = {tol: kin.acceleration_series(lam, tol=tol) for tol in tols}
        cands = {"exact": lambda: kin.piston_acceleration(theta_eval, crank_radius=1.0,
                                                          rod_length=l, omega=1.0)}
        for key, s in [*series.items(), *((f"tol={t:g}", c) for t, c in chosen.items())]:
            cands[str(key)] = (lambda s=s: s.acceleration(theta_eval, crank_radius=1.0,
                                                          omega=1.0))
        timing = _timed(quick, cands)
        base = ("exact", "exact closed form")
        manual = []
        for n, s in series.items():
            err = float(np.abs(s.acceleration(theta_err, crank_radius=1.0, omega=1.0)
                               - ref).max())
            manual.append((n, timing.time(str(n)), err, cands[str(n)]))
            rows.append(timing.row(SUITE, method, str(n), base, f"max_order={n} (manual)", err,
                                   "max abs / (r ω²)", "exact closed form",
                                   throughput_items=n_eval, throughput_unit="angles/s",
                                   note="manual sweep (informational)"))
        for tol in tols:
            s = chosen[tol]
            key = f"tol={tol:g}"
            err = float(np.abs(s.acceleration(theta_err, crank_radius=1.0, omega=1.0)
                               - ref).max())
            rows.append(timing.row(SUITE, method, key, base,
                                   f"tol={tol:g} auto → max_order={s.max_order}", err,
                                   "max abs / (r ω²)", "exact closed form",
                                   throughput_items=n_eval, throughput_unit="angles/s",
                                   bound=tol, note=f"stated error bound {s.error_bound:.3g}",
                                   extra={"max_order": s.max_order,
                                          "error_bound": s.error_bound}))
            auto = (s.max_order, err, timing.time(key), cands[key])
            rows.append(_distance_row(method, tol, auto, manual, "max_order", 0.25, quick))
            choice = compare({"choose": lambda tol=tol: (kin._sqrt_coefficients.cache_clear(),
                                                         kin.acceleration_series(lam, tol=tol)),
                              "eval": cands[key]}, rounds=3, min_time=0.005)
            rows.append(choice.row(SUITE, method, "choose",
                                   ("eval", "one evaluation of the chosen series"),
                                   f"choice cost tol={tol:g}", 0.0, "(informational)",
                                   "order_for_tolerance + coefficients, caches cleared",
                                   note="one-off per (λ, tol); amortised over evaluations"))
    return rows


def _stodola_rows(quick: bool) -> list[Row]:
    from crankbench.predict.lateral.approx import MassShaft, lumped_exact, stodola

    rows: list[Row] = []
    d, length = 0.05, 1.2
    shaft = MassShaft(length=length, youngs_modulus=2.11e11, area_moment=np.pi * d ** 4 / 64,
                      masses=[30.0, 50.0, 20.0], positions=[0.3, 0.6, 1.0],
                      mass_per_length=7810.0 * np.pi * d ** 2 / 4)
    method = "stodola (3 disks + shaft mass)"
    ref = lumped_exact(shaft, n_segments=20)
    sweep, seen = [], set()
    for rtol in (3e-1, 1e-1, 1e-2, 1e-3, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-14):
        res = stodola(shaft, rtol=rtol, max_iter=2000)
        if res.iterations not in seen:
            seen.add(res.iterations)
            sweep.append((rtol, res))
    tols = (1e-3, 1e-6, 1e-10) if quick else (1e-2, 1e-3, 1e-4, 1e-6, 1e-8, 1e-10)
    cands = {"ref": lambda: lumped_exact(shaft, n_segments=20)}
    cands.update({f"manual {r:g}": (lambda r=r: stodola(shaft, rtol=r, max_iter=2000))
                  for r, _ in sweep})
    cands.update({f"auto {t:g}": (lambda t=t: stodola(shaft, rtol=t, max_iter=2000))
                  for t in tols})
    timing = _timed(quick, cands)
    base = ("ref", "lumped_exact (dense eigh)")
    manual = []
    for rtol, res in sweep:
        key = f"manual {rtol:g}"
        err = abs(res.omega - ref.omega) / ref.omega
        manual.append((res.iterations, timing.time(key), err, cands[key]))
        rows.append(timing.row(SUITE, method, key, base,
                               f"{res.iterations} iterations (manual)", err, "rel",
                               "dense eigh of the lumped model",
                               note="manual sweep: a stop after this many iterations "
                                    "(informational)", extra={"iterations": res.iterations}))
    for tol in tols:
        key = f"auto {tol:g}"
        res = stodola(shaft, rtol=tol, max_iter=2000)
        err = abs(res.omega - ref.omega) / ref.omega
        rows.append(timing.row(SUITE, method, key, base,
                               f"rtol={tol:g} auto → {res.iterations} iterations", err, "rel",
                               "dense eigh of the lumped model", bound=tol,
                               extra={"iterations": res.iterations}))
        auto = (res.iterations, err, timing.time(key), cands[key])
        rows.append(_distance_row(method, tol, auto, manual, "iterations", 1.0, quick))
    return rows


def _coastdown_rows(quick: bool) -> list[Row]:
    from crankbench.measure.synth.profile import RPM, exponential_coastdown, from_table

    rows: list[Row] = []
    n0, n1, tau = 1500.0, 300.0, 8.0
    total = tau * np.log(n0 / n1)
    t_err = np.linspace(0.0, total, 200_001)
    exact = n0 * np.exp(-t_err / tau)
    t_eval = np.linspace(0.0, total, 20_000 if quick else 100_000)
    method = "exponential_coastdown (synthetic speed profile)"

    def error(profile):
        return float(np.abs(profile.speed(t_err) / RPM - exact).max())

    def table(pieces):
        knots = np.linspace(0.0, total, pieces + 1)
        return from_table(knots, n0 * np.exp(-knots / tau))

    tols = (5.0, 0.5, 0.01) if quick else (5.0, 1.0, 0.5, 0.1, 0.01)
    auto = {tol: exponential_coastdown(n0, n1, time_constant=tau, tolerance_rpm=tol)
            for tol in tols}
    swept = (1, 2, 4, 8, 16, 32, 64, 128, 256, 512)
    profiles = {p: table(p) for p in swept}
    for prof in auto.values():  # one piece fewer than each automatic choice: the front is
        fewer = prof.time.size - 2  # resolved right below it
        if fewer >= 1 and fewer not in profiles:
            profiles[fewer] = table(fewer)
    cands = {f"{p} pieces": (lambda prof=prof: prof.angle(t_eval))
             for p, prof in sorted(profiles.items())}
    cands.update({f"tol {t:g}": (lambda prof=prof: prof.angle(t_eval))
                  for t, prof in auto.items()})
    timing = _timed(quick, cands)
    manual = []
    for pieces, prof in sorted(profiles.items()):
        key = f"{pieces} pieces"
        err = error(prof)
        manual.append((pieces, timing.time(key), err, cands[key]))
        if pieces in swept:
            rows.append(timing.row(SUITE, method, key, None, f"{pieces} pieces (manual)", err,
                                   "max abs rpm", "n0 exp(-t/tau)",
                                   throughput_items=t_eval.size, throughput_unit="angles/s",
                                   note="manual sweep (informational)"))
    for tol, prof in auto.items():
        key = f"tol {tol:g}"
        pieces = prof.time.size - 1
        err = error(prof)
        rows.append(timing.row(SUITE, method, key, None,
                               f"tolerance_rpm={tol:g} auto → {pieces} pieces", err,
                               "max abs rpm", "n0 exp(-t/tau)", throughput_items=t_eval.size,
                               throughput_unit="angles/s", bound=tol, extra={"pieces": pieces}))
        rows.append(_distance_row(method, tol, (pieces, err, timing.time(key), cands[key]),
                                  manual, "pieces", 0.25, quick))
    return rows


def run(quick: bool) -> list[Row]:
    """All rows of the fidelity suite (see the module docstring)."""
    return _kinematics_rows(quick) + _stodola_rows(quick) + _coastdown_rows(quick)
