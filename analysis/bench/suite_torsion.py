"""Torsional natural frequencies and forced response: speed against error.

Rows
----
* chains of 10, 100, 1000, 2000 equal masses (error against the closed form
  ω_k = 2√(k/J) sin(kπ/2n)): our bidiagonal dqds solver against dense ``scipy.linalg.eigh``
  (baseline) and, when importable, ``opentorsion`` (``Assembly.modal_analysis``, its
  state-space eigen-solve; ``pip install opentorsion``);
* hard chains (stiffness ratio 1e9 / inertia ratio 1e6, and 1e12 / 1e8) against mpmath at 50-60
  digits: the same three solvers;
* a branched (tree) system against mpmath: tree bisection vs dense eigh;
* forced response of a 20-mass engine model over 1000 speeds × 24 orders: batched tree
  elimination (per-order) and with cycle superposition, against a batched dense complex solve.

``--quick`` drops the 2000-mass chain, the peer beyond 10 masses and the 1e12 case, and runs
the forced response over 300 speeds.
"""

from __future__ import annotations

import numpy as np

from . import Row, median_time

SUITE = "torsion"


def _closed_form(n, j, k):
    return 2 * np.sqrt(k / j) * np.sin(np.arange(n) * np.pi / (2 * n))


def _rel_error(got, ref):
    got, ref = np.sort(np.asarray(got, float)), np.sort(np.asarray(ref, float))
    mask = ref > 0
    return float(np.max(np.abs(got[mask] - ref[mask]) / ref[mask]))


def _eigh_omega(system):
    import scipy.linalg as sl

    rj = 1 / np.sqrt(system.inertias)
    lam = sl.eigh(system.stiffness_matrix() * rj[:, None] * rj[None, :], eigvals_only=True)
    return np.sqrt(np.clip(lam, 0, None))


def _opentorsion():
    try:
        import opentorsion  # noqa: F401

        return opentorsion
    except Exception:  # noqa: BLE001 - any import failure means "not available"
        return None


def _ot_omega(ot, inertias, stiffnesses):
    shafts = [ot.Shaft(i, i + 1, k=float(k), I=0.0) for i, k in enumerate(stiffnesses)]
    disks = [ot.Disk(i, I=float(j)) for i, j in enumerate(inertias)]
    assembly = ot.Assembly(shafts, disk_elements=disks)
    wn, _, _ = assembly.modal_analysis()
    return np.sort(np.asarray(wn, float))[::2]


def _mp_reference(inertias, stiffnesses, dps):
    import mpmath

    mpmath.mp.dps = dps
    n = len(inertias)
    h = mpmath.zeros(n, n)
    r = [1 / mpmath.sqrt(mpmath.mpf(float(j))) for j in inertias]
    for i, k in enumerate(stiffnesses):
        k = mpmath.mpf(float(k))
        h[i, i] += k * r[i] ** 2
        h[i + 1, i + 1] += k * r[i + 1] ** 2
        h[i, i + 1] -= k * r[i] * r[i + 1]
        h[i + 1, i] -= k * r[i] * r[i + 1]
    ev = mpmath.eigsy(h, eigvals_only=True)
    return np.array([float(mpmath.sqrt(max(e, 0))) for e in sorted(ev)])


def _hard_chain(n, k_ratio, j_ratio, seed):
    rng = np.random.default_rng(seed)
    j = 10 ** rng.uniform(0, np.log10(j_ratio), n)
    j[[0, 1]] = [1.0, j_ratio]
    k = 10 ** rng.uniform(0, np.log10(k_ratio), n - 1)
    k[[0, 1]] = [1.0, k_ratio]
    return j, k


def _sterf_row(n, j, k, ref, t_ours):
    """LAPACK dsterf (Pal-Walker-Kahan QR, values only, *not* relatively accurate) on the
    scaled tridiagonal: the speed floor of any O(n²) tridiagonal eigenvalue routine here."""
    from scipy.linalg import lapack

    d = np.full(n, 2 * k / j)
    d[[0, -1]] = k / j
    e = np.full(n - 1, -k / j)

    def sterf():
        w, info = lapack.dsterf(d.copy(), e.copy())
        return np.sqrt(np.clip(w, 0, None))

    t = median_time(sterf, repeats=5, min_time=0.02)
    return Row(SUITE, "LAPACK dsterf (speed floor, normwise only)", f"uniform chain n={n}",
               _rel_error(sterf(), ref), "max rel", "closed form", t,
               "bidiagonal dqds (ours)", t / t_ours,
               note="context: fastest LAPACK tridiagonal eigenvalues, not relatively accurate")


def _frequency_rows(quick: bool) -> list[Row]:
    from crankbench.predict.torsion import chain

    ot = _opentorsion()
    rows = []
    sizes = (10, 100, 1000) if quick else (10, 100, 1000, 2000)
    for n in sizes:
        j, k = 1.5, 4.0e5
        inertias, stiffnesses = np.full(n, j), np.full(n - 1, k)
        ref = _closed_form(n, j, k)

        def ours():
            return chain(inertias, stiffnesses).natural_frequencies("rad/s")

        sys_ = chain(inertias, stiffnesses)
        t_ours = median_time(ours, repeats=7 if n <= 1000 else 3, min_time=0.02)
        t_base = median_time(lambda: _eigh_omega(sys_), repeats=1 if n >= 1000 else 5,
                             warmup=0 if n >= 1000 else 1)
        err_ours = _rel_error(ours(), ref)
        err_base = _rel_error(_eigh_omega(sys_), ref)
        rows.append(Row(SUITE, "bidiagonal dqds (ours)", f"uniform chain n={n}", err_ours,
                        "max rel", "closed form", t_ours, "scipy.linalg.eigh dense",
                        t_ours / t_base, n / t_ours, "masses/s", bound=1e-13))
        rows.append(Row(SUITE, "scipy.linalg.eigh dense (baseline)", f"uniform chain n={n}",
                        err_base, "max rel", "closed form", t_base, "", np.nan, n / t_base,
                        "masses/s"))
        if n >= 1000:
            rows.append(_sterf_row(n, j, k, ref, t_ours))
        if ot is not None and (n <= 10 or not quick):
            reps = 3 if n <= 100 else 1
            t_ot = median_time(lambda: _ot_omega(ot, inertias, stiffnesses), repeats=reps,
                               warmup=1 if n <= 100 else 0)
            err_ot = _rel_error(_ot_omega(ot, inertias, stiffnesses), ref)
            rows.append(Row(SUITE, "opentorsion modal_analysis (peer)", f"uniform chain n={n}",
                            err_ot, "max rel", "closed form", t_ot, "bidiagonal dqds (ours)",
                            t_ot / t_ours, n / t_ot, "masses/s",
                            note=f"ours is {t_ot / t_ours:.0f}x faster"))
    cases = [(1e9, 1e6, 50)] + ([] if quick else [(1e12, 1e8, 60)])
    for k_ratio, j_ratio, dps in cases:
        n = 24
        inertias, stiffnesses = _hard_chain(n, k_ratio, j_ratio, seed=7)
        ref = _mp_reference(inertias, stiffnesses, dps)
        sys_ = chain(inertias, stiffnesses)
        setting = f"hard chain n={n}, k ratio {k_ratio:.0e}, J ratio {j_ratio:.0e}"
        t_ours = median_time(lambda: chain(inertias, stiffnesses).natural_frequencies(),
                             repeats=7, min_time=0.02)
        t_base = median_time(lambda: _eigh_omega(sys_), repeats=7, min_time=0.02)
        rows.append(Row(SUITE, "bidiagonal dqds (ours)", setting,
                        _rel_error(sys_.natural_frequencies("rad/s"), ref), "max rel",
                        f"mpmath {dps} digits", t_ours, "scipy.linalg.eigh dense",
                        t_ours / t_base, bound=1e-12))
        rows.append(Row(SUITE, "scipy.linalg.eigh dense (baseline)", setting,
                        _rel_error(_eigh_omega(sys_), ref), "max rel", f"mpmath {dps} digits",
                        t_base))
        if ot is not None:
            t_ot = median_time(lambda: _ot_omega(ot, inertias, stiffnesses), repeats=3)
            rows.append(Row(SUITE, "opentorsion modal_analysis (peer)", setting,
                            _rel_error(_ot_omega(ot, inertias, stiffnesses), ref), "max rel",
                            f"mpmath {dps} digits", t_ot, "bidiagonal dqds (ours)",
                            t_ot / t_ours))
    return rows


def _tree_rows(quick: bool) -> list[Row]:
    import mpmath

    from crankbench.predict.torsion import TorsionalSystem

    rng = np.random.default_rng(11)
    n = 30 if quick else 60
    parent = [-1] + [int(rng.integers(0, i)) for i in range(1, n)]
    edges = [(parent[i], i) for i in range(1, n)]
    j = 10 ** rng.uniform(0, 6, n)
    k = 10 ** rng.uniform(0, 9, n - 1)
    mpmath.mp.dps = 50
    h = mpmath.zeros(n, n)
    r = [1 / mpmath.sqrt(mpmath.mpf(float(v))) for v in j]
    for (a, b), kk in zip(edges, k):
        kk = mpmath.mpf(float(kk))
        h[a, a] += kk * r[a] ** 2
        h[b, b] += kk * r[b] ** 2
        h[a, b] -= kk * r[a] * r[b]
        h[b, a] -= kk * r[a] * r[b]
    ref = np.array([float(mpmath.sqrt(max(e, 0)))
                    for e in sorted(mpmath.eigsy(h, eigvals_only=True))])
    s = TorsionalSystem(j, edges, k)
    t_ours = median_time(lambda: TorsionalSystem(j, edges, k).natural_frequencies(), repeats=5)
    t_base = median_time(lambda: _eigh_omega(s), repeats=5, min_time=0.02)
    setting = f"random tree n={n}, k ratio 1e9, J ratio 1e6"
    return [Row(SUITE, "tree bisection (ours)", setting,
                _rel_error(s.natural_frequencies("rad/s"), ref), "max rel", "mpmath 50 digits",
                t_ours, "scipy.linalg.eigh dense", t_ours / t_base, bound=1e-12),
            Row(SUITE, "scipy.linalg.eigh dense (baseline)", setting,
                _rel_error(_eigh_omega(s), ref), "max rel", "mpmath 50 digits", t_base)]


def _forced_rows(quick: bool) -> list[Row]:
    from crankbench.predict.torsion import chain
    from crankbench.predict.torsion.forced import cylinder_forcing, harmonic_solve

    rng = np.random.default_rng(0)
    n = 20
    s = chain(rng.uniform(1, 5, n), rng.uniform(1e6, 5e6, n - 1)).replace(
        cylinder_nodes=list(range(2, 8)), firing_angles_deg=[0, 480, 240, 600, 120, 360],
        edge_damping=np.full(n - 1, 30.0), node_damping=np.r_[np.full(n - 1, 3.0), 300.0],
        edge_loss_factor=np.full(n - 1, 0.02))
    n_speeds = 300 if quick else 1000
    rpm = np.linspace(100, 1500, n_speeds)
    orders = np.arange(0.5, 12.01, 0.5)
    torque = 1e3 / orders
    speed = rpm * np.pi / 30

    def dense():
        f = cylinder_forcing(s, torque, orders, n_speeds)
        w = (speed[:, None] * orders[None, :]).reshape(-1)
        kk, jj = s.stiffness_matrix(), s.inertia_matrix()
        cv = s.damping_matrix()
        keta = s._laplacian(s.stiffnesses * s.edge_loss_factor)
        z = (kk[None] + 1j * keta[None] + 1j * w[:, None, None] * cv[None]
             - (w * w)[:, None, None] * jj[None])
        return np.linalg.solve(z, f.reshape(-1, n)[..., None])[..., 0]

    def per_order():
        return s.forced_response(rpm, torque=torque, orders=orders, superpose=False)

    def full():
        return s.forced_response(rpm, torque=torque, orders=orders)

    x_ref = dense().reshape(n_speeds, orders.size, n)
    x = harmonic_solve(s, speed, orders, cylinder_forcing(s, torque, orders, n_speeds))
    err = float(np.max(np.abs(x - x_ref)) / np.max(np.abs(x_ref)))
    t_dense = median_time(dense, repeats=1 if quick else 3)
    t_po = median_time(per_order, repeats=3 if quick else 5)
    t_full = median_time(full, repeats=3)
    setting = f"{n} masses, {n_speeds} speeds x {orders.size} orders"
    pairs = n_speeds * orders.size
    return [
        Row(SUITE, "forced response, tree elimination (ours)", setting, err,
            "max abs / max |x|", "batched dense complex solve", t_po,
            "numpy batched dense solve", t_po / t_dense, pairs / t_po, "(speed, order)/s",
            bound=1e-10, note="per-order amplitudes, stresses; totals = sum of amplitudes"),
        Row(SUITE, "forced response + cycle superposition (ours)", setting, err,
            "max abs / max |x|", "batched dense complex solve", t_full,
            "numpy batched dense solve", t_full / t_dense, pairs / t_full, "(speed, order)/s",
            bound=1e-10, note="peak over the cycle, 8 samples/period + parabolic refinement"),
        Row(SUITE, "numpy batched dense solve (baseline)", setting, 0.0, "max abs / max |x|",
            "itself", t_dense, "", np.nan, pairs / t_dense, "(speed, order)/s"),
    ]


def run(quick: bool) -> list[Row]:
    """All torsion rows (see module docstring)."""
    return _frequency_rows(quick) + _tree_rows(quick) + _forced_rows(quick)
