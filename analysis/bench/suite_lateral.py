"""Lateral vibration: speed against error of the approximations and the beam finite elements.

Rows:

* Rayleigh, Dunkerley, Stodola (rtol 1e-3 / 1e-6 / 1e-10) on (a) two equal disks at the third
  points of a massless pinned shaft — closed form ω² = 486 EI/(15 m L³) — and (b) a steel shaft
  with its own mass carrying three disks — reference: Euler-Bernoulli FE with 64 elements
  (h⁴ error ~1e-12, round-off ~1e-10). Baseline: the dense symmetric eigen-solve of the lumped flexibility
  (``lumped_exact``). Rayleigh/Dunkerley rows note whether their bound direction held; the
  bench fails on a wrong direction (bound 0 on the signed error then).
* Rotor FE, Euler-Bernoulli pinned uniform shaft, n = 2…64 elements: max relative error of the
  first three frequencies against (nπ/L)²√(EI/ρA); Timoshenko thick shaft (L/d = 5) against the
  exact Timoshenko frequency equation. The observed convergence rate is in ``extra``; the bound
  is 3× the result's own Richardson error estimate (the method's stated error). Baseline: the
  bare ``scipy.linalg.eigh(K, M)`` of the same assembled matrices (the solver floor; the ratio
  is the cost of building the model and classifying the modes).
* ``ross-rotordynamics`` side by side (full run only: importing ROSS and its numba JIT take
  ≈ 45 s) on Friswell et al. Example 5.9.1 (6 Timoshenko elements, and a 48-element version):
  natural frequencies at 0 and 4000 rpm and synchronous critical speeds, error = max relative
  difference to ROSS (bound 1e-4), ratio = our time / ROSS time for build + solve.

Every ratio comes from interleaved rounds after a warm-up (:func:`analysis.bench.compare`).
"""

from __future__ import annotations

import contextlib
import io
import logging
import os
import sys
import warnings

import numpy as np
import scipy.linalg

from . import Row, compare

__all__ = ["run"]

SUITE = "lateral"

_E, _RHO = 2.11e11, 7810.0


def _approx_rows(quick: bool) -> list[Row]:
    from crankbench.predict.lateral.approx import MassShaft, dunkerley, lumped_exact, rayleigh, stodola
    from crankbench.predict.lateral.fe import Bearing, Disk, Material, Rotor, ShaftSection

    rows = []
    cases = []
    ei = 1.0
    a = MassShaft(length=1.0, youngs_modulus=ei, area_moment=1.0, masses=[1.0, 1.0],
                  positions=[1 / 3, 2 / 3])
    cases.append(("2 disks, massless shaft", a, np.sqrt(486 / 15), "closed form 486EI/(15mL³)"))
    d, L = 0.05, 1.2
    masses, positions = [30.0, 50.0, 20.0], [0.3, 0.6, 1.0]
    b = MassShaft(length=L, youngs_modulus=_E, area_moment=np.pi * d**4 / 64, masses=masses,
                  positions=positions, mass_per_length=_RHO * np.pi * d**2 / 4)
    mat = Material(_E, _RHO, poisson_ratio=0.3)
    # 64 elements: discretisation error ~1e-12, round-off ~1e-10 (it grows as n⁴ beyond)
    ref = Rotor(shaft=[ShaftSection(L, d, material=mat, n_elements=64)],
                disks=[Disk(p, m) for m, p in zip(masses, positions)],
                bearings=[Bearing(0.0, np.inf), Bearing(L, np.inf)], theory="euler-bernoulli",
                rotary_inertia=False).natural_frequencies(n_modes=1, error_estimate=False).omega[0]
    cases.append(("shaft mass + 3 disks", b, ref, "EB FE 64 elements (error < 1e-9)"))
    repeats = 3 if quick else 7
    for label, shaft, exact, reference in cases:
        methods = [("rayleigh", lambda: rayleigh(shaft), "", "upper"),
                   ("dunkerley", lambda: dunkerley(shaft), "", "lower")]
        for tol in ((1e-3, 1e-6) if quick else (1e-3, 1e-6, 1e-10)):
            methods.append(("stodola", lambda tol=tol: stodola(shaft, rtol=tol, n_segments=80),
                            f"rtol={tol:g}", "bracket"))
        cands = {"base": lambda: lumped_exact(shaft)}
        cands.update({f"{name} {setting}": func for name, func, setting, _ in methods})
        timing = compare(cands, rounds=repeats, min_time=0.01)
        for name, func, setting, bound_kind in methods:
            res = func()
            signed = (res.omega - exact) / exact
            err = abs(signed)
            if bound_kind == "upper":
                held = signed >= -1e-12
            elif bound_kind == "lower":
                held = signed <= 1e-12
            else:
                held = res.lower <= exact * (1 + 1e-9) and exact <= res.upper * (1 + 1e-9)
            if bound_kind == "bracket":
                # lumping the shaft mass (80 segments) adds ~2e-8
                bound = 2 * float(setting.split("=")[1]) + (5e-8 if shaft.mass_per_length else 0)
            else:
                bound = float("inf") if held else 0.0
            rows.append(timing.row(SUITE, name, f"{name} {setting}",
                                   ("base", "lumped_exact (dense eigh)"),
                                   f"{label}; {setting}".rstrip("; "), err, "rel", reference,
                                   bound=bound, note=f"{bound_kind} bound held: {held}",
                                   extra={"iterations": res.iterations, "bound": bound_kind}))
    return rows


def _fe_rows(quick: bool) -> list[Row]:
    from crankbench.predict.lateral.fe import Bearing, Material, Rotor, ShaftSection

    mat = Material(_E, _RHO, poisson_ratio=0.3)
    rows = []
    repeats = 3 if quick else 7

    def pinned(n, theory, length, diameter, rotary):
        return Rotor(shaft=[ShaftSection(length, diameter, material=mat, n_elements=n)],
                     bearings=[Bearing(0.0, np.inf), Bearing(length, np.inf)], theory=theory,
                     rotary_inertia=rotary)

    def eb_exact(length, diameter):
        area, inertia = np.pi * diameter**2 / 4, np.pi * diameter**4 / 64
        return np.array([(k * np.pi / length) ** 2 * np.sqrt(_E * inertia / (_RHO * area))
                         for k in (1, 2, 3)])

    def timo_exact(length, diameter):
        area, inertia = np.pi * diameter**2 / 4, np.pi * diameter**4 / 64
        nu = mat.poisson_ratio
        kga = 6 * (1 + nu) / (7 + 6 * nu) * mat.shear_modulus * area
        out = []
        for k in (np.pi / length * n for n in (1, 2, 3)):
            a = _RHO * area * _RHO * inertia
            b = -(_RHO * area * (_E * inertia * k**2 + kga) + _RHO * inertia * kga * k**2)
            c = kga * k**2 * (_E * inertia * k**2 + kga) - (kga * k) ** 2
            out.append(np.sqrt((-b - np.sqrt(b * b - 4 * a * c)) / (2 * a)))
        return np.array(out)

    cases = [("euler-bernoulli", 1.0, 0.05, False, eb_exact(1.0, 0.05),
              "closed form (nπ/L)²√(EI/ρA)"),
             ("timoshenko", 0.5, 0.1, True, timo_exact(0.5, 0.1),
              "exact Timoshenko pinned-pinned (L/d = 5)")]
    ns = (4, 8, 16, 32) if quick else (2, 4, 8, 16, 32, 64)
    for theory, length, diameter, rotary, exact, reference in cases:
        errors = []
        for n in ns:
            if n < 3 and theory == "timoshenko":
                continue
            modes = pinned(n, theory, length, diameter, rotary).natural_frequencies(n_modes=6)
            om = modes.omega[::2]
            err = float(np.max(np.abs(om - exact) / exact))
            estimate = float(np.max(modes.error_estimate[::2] / exact))
            errors.append((n, err))
            model = pinned(n, theory, length, diameter, rotary)._assemble()
            timing = compare(
                {"ours": lambda n=n: pinned(n, theory, length, diameter, rotary)
                    .natural_frequencies(n_modes=6, error_estimate=False),
                 "eigh": lambda m=model: scipy.linalg.eigh(m.K, m.M)},
                rounds=repeats, min_time=0.01)
            rate = (np.log2(errors[-2][1] / err) if len(errors) > 1 else float("nan"))
            rows.append(timing.row(SUITE, f"fe {theory}", "ours",
                                   ("eigh", "scipy.linalg.eigh(K, M) alone"), f"n={n}", err,
                                   "max rel (3 modes)", reference,
                                   bound=max(3 * estimate, 1e-12),
                                   note="bound = 3 × Richardson estimate",
                                   extra={"rate_vs_previous": rate,
                                          "error_estimate": estimate}))
    return rows


@contextlib.contextmanager
def _silenced_fds():
    """Redirect the process's stdout/stderr file descriptors to /dev/null (C-level prints)."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        os.dup2(null, 2)
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            yield
    finally:
        sys.stdout.flush()
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, null):
            os.close(fd)


def _ross_rows(quick: bool) -> list[Row]:
    try:
        logging.getLogger("ross").setLevel(logging.ERROR)
        # ROSS's dependencies (CoolProp) print set-up chatter from C on import; keep it out
        # of --json output by silencing the file descriptors themselves
        with warnings.catch_warnings(), _silenced_fds():
            warnings.simplefilter("ignore")
            import ross as rs
    except Exception as exc:  # noqa: BLE001 - optional, any import failure means skip
        logging.getLogger("crankbench").warning("lateral bench: ross not available (%s)", exc)
        return []
    from crankbench.predict.lateral.fe import Bearing, Disk, Material, Rotor, ShaftSection

    steel = rs.Material(name="crankbench_steel", rho=7810.0, E=211e9, G_s=81.2e9)
    ours_mat = Material(211e9, 7810.0, shear_modulus=81.2e9)
    rows = []
    for n_el in (6, 48):
        def build_ross(n_el=n_el):
            h = 1.5 / n_el
            shaft = [rs.ShaftElement(L=h, idl=0.0, odl=0.05, material=steel)
                     for _ in range(n_el)]
            disks = [rs.DiskElement.from_geometry(n=round(0.5 / h), material=steel, width=0.07,
                                                  i_d=0.05, o_d=0.28),
                     rs.DiskElement.from_geometry(n=round(1.0 / h), material=steel, width=0.07,
                                                  i_d=0.05, o_d=0.35)]
            brg = [rs.BearingElement(n=0, kxx=1e6, cxx=0.0),
                   rs.BearingElement(n=n_el, kxx=1e6, cxx=0.0)]
            return rs.Rotor(shaft, disks, brg)

        def build_ours(n_el=n_el):
            return Rotor(shaft=[ShaftSection(1.5, 0.05, material=ours_mat, n_elements=n_el)],
                         disks=[Disk.from_geometry(position=0.5, outer_diameter=0.28,
                                                   inner_diameter=0.05, width=0.07,
                                                   density=7810.0),
                                Disk.from_geometry(position=1.0, outer_diameter=0.35,
                                                   inner_diameter=0.05, width=0.07,
                                                   density=7810.0)],
                         bearings=[Bearing(0.0, 1e6), Bearing(1.5, 1e6)])

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for rpm in (0.0, 4000.0):
                speed = rpm * np.pi / 30
                ours = build_ours().natural_frequencies(speed, n_modes=6,
                                                        error_estimate=False).omega
                theirs = build_ross().run_modal(speed=speed, num_modes=24, sparse=False).wd
                diff = max(np.min(np.abs(theirs - w)) / w for w in ours)
                timing = compare(
                    {"ours": lambda s=speed: build_ours().natural_frequencies(
                        s, n_modes=6, error_estimate=False),
                     "ross": lambda s=speed: build_ross().run_modal(speed=s, num_modes=24,
                                                                    sparse=False)},
                    rounds=5, min_time=0.02)
                rows.append(timing.row(SUITE, "fe vs ross: natural frequencies", "ours",
                                       ("ross", "ross build + run_modal"),
                                       f"Friswell 5.9.1, {n_el} el, {rpm:g} rpm", float(diff),
                                       "max rel", "ross-rotordynamics run_modal (dense)",
                                       bound=1e-4,
                                       note="6 lateral modes matched to nearest ROSS mode"))
            ours_c = build_ours().critical_speeds(n_modes=6).omega[:5]
            theirs_c = np.asarray(build_ross().run_critical_speed(num_modes=24, rtol=1e-8).wn())
            diff = max(np.min(np.abs(theirs_c - w)) / w for w in ours_c)
            timing = compare(
                {"ours": lambda: build_ours().critical_speeds(n_modes=6),
                 "ross": lambda: build_ross().run_critical_speed(num_modes=24, rtol=1e-8)},
                rounds=3, min_time=0.0)
            rows.append(timing.row(SUITE, "fe vs ross: critical speeds", "ours",
                                   ("ross", "ross build + run_critical_speed"),
                                   f"Friswell 5.9.1, {n_el} el", float(diff), "max rel",
                                   "ross run_critical_speed(rtol=1e-8)", bound=1e-4,
                                   note="ours: Hermitian eigen-solve; ROSS: root search on "
                                        "the Campbell lines"))
    return rows


def run(quick: bool) -> list[Row]:
    """Run the lateral suite; ``quick`` drops the ROSS comparison and the finest meshes."""
    rows = _approx_rows(quick) + _fe_rows(quick)
    if not quick:
        rows += _ross_rows(quick)
    return rows
