"""Textbook lower fidelities against the exact models: what each approximation costs in error
and saves in time.

Rows (each error against an independent or exact reference, time the median of repeated calls,
ratio against the exact model timed in the same process):

* piston acceleration — the textbook a = rω²(cos θ + λ cos 2θ) (``max_order=2,
  lambda_terms=1``), two λ terms, exact coefficients truncated at order 2 and 4, against the
  exact closed form; error = max |Δa|/(rω²) over 3600 angles (λ = 0.3); time = 2·10⁴ angles;
  bound = the rigorous tail bound Σ|aₙ| for exact coefficients, the measured value × 1.01 for
  the λ-truncated ones (a regression guard);
* two-mass connecting rod (residual couple dropped) against the exact rigid rod (residual
  couple included): error = max |ΔT| relative to the largest inertia torque; bound = 1.001 ×
  the closed form of the dropped term, the couple −ΔI ε of the rod (ε = rod angular
  acceleration) carried to the crank by the arm r cos θ/(l cos β):
  ΔT = ΔI ω² λ² (1 − λ²) sin θ cos θ/(1 − λ² sin²θ)² (ΔI = I_G − m a b), its maximum over a
  dense grid; the cruder product of maxima |ΔI| ω² λ²/(1 − λ²) is in the note;
* double-acting cylinder with the piston-rod area dropped (``piston_rod_diameter=0``, the
  lower fidelity) and with it, against the closed form of the net gas force
  (p(ψ) − p_cc) A − (p(ψ − π) − p_cc)(A − π d²/4) evaluated from the pressure trace;
  error = max |ΔF| / max |F|; bound for the full model 1e-12, for the lower fidelity 1.001 ×
  the stated error max |p(ψ − π) − p_cc| π d²/4 / max |F| (the annulus force it overstates);
  time paired (:func:`compare`) against the full model;
* Stodola, 1 to 4 iterates, against the dense eigen-solve of the same lumped shaft; bound = the
  Collatz bracket half-width of that iterate;
* heavy shaft split into N = 4 … 32 elements against the exact free-free uniform shaft (first
  3 modes); bound = 1.05 × the stated 1 − sin x/x;
* resonance amplitude by energy balance against the exact damped solve on the 6L32 sample
  (worst relative error on the damper-controlled mode 3; informational: the method's error
  with a damper comes from the undamped mode shape it assumes, for which no stated error
  formula exists — the tests' −39…−27 % are an observed band on this sample, not a bound);
* Lanchester friction damper by harmonic balance against time integration of the non-linear
  hub + ring (3 speeds across the resonance); bound 5 %;
* crank-throw equivalent inertia with the truncated textbook factor m r² (1/2 + λ²/8) against
  the exact energy mean m ⟨x'²⟩ (λ = 0.25 and 0.4); bound 1.2 × (λ⁴/16 + 5λ⁶/128)/(1/2 + λ²/8),
  the next series terms;
* journal bearing: short-bearing closed form against the finite-length Reynolds solution at
  L/D = 0.5 (eccentricity under the same load), and the finite solution against Raimondi &
  Boyd's table (L/D = 1, ε = 0.6: S = 0.121); bound 1.5 %.

``--quick`` drops the 32-element shaft, the 4th Stodola iterate and one friction speed.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import Row, median_time

SUITE = "textbook"


def _time(quick):
    return (lambda f: median_time(f, repeats=3, min_time=0.005)) if quick else (
        lambda f: median_time(f, repeats=7, min_time=0.02))


def _piston_rows(quick, timer):
    from crankbench.predict.kinematics import (piston_acceleration, series_error,
                                               truncation_bound)

    r, l, w = 0.06, 0.2, 400.0
    lam = r / l
    th = np.linspace(0, 2 * np.pi, 20000)
    t_exact = timer(lambda: piston_acceleration(th, crank_radius=r, rod_length=l, omega=w))
    rows = []
    for label, order, terms in (("textbook cos θ + λ cos 2θ", 2, 1), ("two λ terms", 2, 2),
                                ("exact coefficients", 2, None), ("exact coefficients", 4, None)):
        err = series_error(lam, max_order=order, lambda_terms=terms)
        t = timer(lambda o=order, k=terms: piston_acceleration(
            th, crank_radius=r, rod_length=l, omega=w, max_order=o, lambda_terms=k))
        bound = truncation_bound(lam, order) * (1 + 1e-9) if terms is None else 1.01 * err
        rows.append(Row(SUITE, "piston_acceleration", f"{label}, max_order={order}", err,
                        "max rel (r ω²)", "exact closed form", t, "exact closed form",
                        t / t_exact, bound=bound, note=f"λ = {lam:g}"))
    return rows


def _rod_row(timer):
    from crankbench.predict.engine import Engine
    from crankbench.predict.forces import engine_torque
    from crankbench.predict.masses import Rod

    rod = Rod(mass=3.0, length=0.2, cg_from_big_end=0.06, inertia_cg=0.012)
    two = rod.two_point()
    kw = dict(crank_angles_deg=[0], crank_radius=0.06, rod_length=0.2,
              reciprocating_mass=two.small_end + 1.5, rotating_mass=two.big_end)
    simple = Engine(**kw)
    exact = Engine(rod_inertia_correction=two.inertia_error, **kw)
    th = np.linspace(0, 4 * np.pi, 4000)
    w = 400.0
    t0 = engine_torque(simple, th, omega=w)
    t1 = engine_torque(exact, th, omega=w)
    err = float(np.max(np.abs(t0 - t1)) / np.max(np.abs(t1)))
    ts = timer(lambda: engine_torque(simple, th, omega=w))
    te = timer(lambda: engine_torque(exact, th, omega=w))
    lam = 0.06 / 0.2
    grid = np.linspace(0, 2 * np.pi, 200001)
    di = abs(two.inertia_error)
    stated = float(np.max(np.abs(di * w * w * lam ** 2 * (1 - lam ** 2) * np.sin(grid)
                                 * np.cos(grid) / (1 - (lam * np.sin(grid)) ** 2) ** 2)))
    crude = di * w * w * lam ** 2 / (1 - lam ** 2)
    scale = float(np.max(np.abs(t1)))
    return Row(SUITE, "two-mass connecting rod", "residual couple dropped", err,
               "max rel torque", "rigid rod (residual couple included)", ts,
               "rigid rod", ts / te, bound=1.001 * stated / scale,
               note=f"inertia torque only, 400 rad/s; bound: closed form of the dropped "
                    f"couple; product of maxima {crude / scale:.3g}")


def _double_acting_rows(quick):
    from crankbench.predict.engine import Engine
    from crankbench.predict.pressure import synthetic_pressure

    from . import compare

    bore, rod_d, p_cc = 0.5, 0.16, 1.0e5
    kw = dict(crank_angles_deg=[0], crank_radius=0.5, rod_length=2.0, reciprocating_mass=900.0,
              bore=bore, cycle=2, compression_ratio=12.0, double_acting=True)
    full = Engine(piston_rod_diameter=rod_d, **kw)
    low = Engine(**kw)
    trace = synthetic_pressure(Engine(**{**kw, "double_acting": False}), imep=8e5)
    psi = np.linspace(0, 2 * np.pi, 20000, endpoint=False)
    area = np.pi * bore ** 2 / 4
    rod_area = np.pi * rod_d ** 2 / 4
    # closed form of the net force from the two chambers, straight from the trace
    upper = trace.at(psi) - p_cc
    lower = trace.at(psi - np.pi) - p_cc
    ref = upper * area - lower * (area - rod_area)
    scale = float(np.max(np.abs(ref)))
    timing = compare({"full": lambda: full.net_gas_force(trace, psi, p_cc),
                      "low": lambda: low.net_gas_force(trace, psi, p_cc)},
                     rounds=3 if quick else 7, min_time=0.005 if quick else 0.02)
    e_full = float(np.max(np.abs(full.net_gas_force(trace, psi, p_cc) - ref))) / scale
    e_low = float(np.max(np.abs(low.net_gas_force(trace, psi, p_cc) - ref))) / scale
    stated = float(np.max(np.abs(lower))) * rod_area / scale
    ref_name = "closed form (p − p_cc) A − (p(ψ − π) − p_cc)(A − π d²/4)"
    note = f"2-stroke, bore {bore:g} m, rod {rod_d:g} m, IMEP 8 bar, 20000 angles"
    return [timing.row(SUITE, "double-acting cylinder", "full", None,
                       f"piston rod d = {rod_d:g} m", e_full, "max rel force", ref_name,
                       bound=1e-12, note=note),
            timing.row(SUITE, "double-acting cylinder", "low", ("full", "rod area"),
                       "rod area 0 (lower fidelity)", e_low, "max rel force", ref_name,
                       bound=1.001 * stated,
                       note=note + "; bound: max |p(ψ − π) − p_cc| π d²/4 / max |F|")]


def _stodola_rows(quick, timer):
    from crankbench.predict.lateral.approx import MassShaft, lumped_exact, stodola

    s = MassShaft(length=2.0, youngs_modulus=2.1e11, area_moment=np.pi * 0.05 ** 4 / 64,
                  mass_per_length=15.0, masses=[40.0, 25.0, 60.0], positions=[0.5, 1.1, 1.6])
    ref = lumped_exact(s).omega
    t_ref = timer(lambda: lumped_exact(s))
    rows = []
    for k in range(1, 4 if quick else 5):
        res = stodola(s, iterations=k)
        t = timer(lambda k=k: stodola(s, iterations=k))
        rows.append(Row(SUITE, "stodola", f"iterations={k}", abs(res.omega - ref) / ref,
                        "rel", "dense eigen-solve of the same lumped model", t, "lumped_exact",
                        t / t_ref, bound=max(res.error_estimate * 2, 1e-15),
                        note="bound: the Collatz bracket width of that iterate"))
    return rows


def _shaft_rows(quick, timer):
    from crankbench.predict.torsion.elements import ShaftLine
    from crankbench.predict.torsion.throws import lumping_error, uniform_shaft_frequencies

    g, rho, length, d = 80e9, 7850.0, 2.0, 0.1
    exact = uniform_shaft_frequencies(length=length, shear_modulus=g, density=rho)
    c = np.sqrt(g / rho)
    rows = []
    base = None
    for n in (4, 8, 16) if quick else (4, 8, 16, 32):
        line = ShaftLine("shaft")
        line.add_mass("a", 1e-12)
        line.add_mass("b", 1e-12)
        line.add_shaft("a", "b", length=length, diameter=d, density=rho, shear_modulus=g,
                       elements=n)
        system = line.build()
        w = system.natural_frequencies("rad/s")[1:4]
        err = float(np.max(np.abs(w - exact) / exact))
        t = timer(lambda s=system: s.replace().natural_frequencies())
        base = base or t
        bound = 1.05 * float(np.max(lumping_error(exact, length=length, wave_velocity=c,
                                                  elements=n)))
        rows.append(Row(SUITE, "heavy shaft (distributed inertia)", f"elements={n}", err,
                        "max rel (modes 1-3)", "exact uniform shaft mπc/L", t,
                        "elements=4", t / base, bound=bound))
    return rows


def _resonance_row(timer):
    import crankbench.predict.torsion as pt
    from crankbench.predict.torsion.resonance import resonance_amplitudes

    root = Path(__file__).resolve().parents[2]
    s = pt.from_toml(root / "sample_data/shaftlines/marine_6l.toml")
    tab = resonance_amplitudes(s, speed_range_rpm=(200, 800), min_vector_sum=0.2)
    m3 = tab[tab["mode"] == 3]
    t = timer(lambda: resonance_amplitudes(s, orders=[4.5], speed_range_rpm=(700, 800)))
    return Row(SUITE, "energy-balance resonance amplitude", "single mode, damper ring still",
               float(m3.method_error.abs().max()), "max rel (mode 3)",
               "exact damped harmonic solve", t, note="6L32 sample with viscous damper; the "
               "exact value is the headline")


def _friction_rows(quick, timer):
    from crankbench.predict.torsion import chain
    from crankbench.predict.torsion.friction import friction_damper_response, time_domain_sdof

    jh, k, c, jr, ts, t = 1.0, 1e5, 5.0, 0.25, 30.0, 60.0
    s = chain([jh], [k]).replace(cylinder_nodes=[0], firing_angles_deg=[0.0], node_damping=[c])
    ratios = [0.9, 1.0] if quick else [0.9, 1.0, 1.05]
    rpm = np.array(ratios) * np.sqrt(k / jh) * 30 / np.pi
    hb = friction_damper_response(s, 0, ring_inertia=jr, slip_torque=ts, speed_rpm=rpm,
                                  order=1.0, torque=t)
    ref = np.array([time_domain_sdof(inertia=jh, stiffness=k, damping=c, ring_inertia=jr,
                                     slip_torque=ts, omega=w, torque=t, cycles=100,
                                     steps_per_cycle=240) for w in rpm * np.pi / 30])
    err = float(np.max(np.abs(hb.hub_amplitude / ref - 1)))
    t_hb = timer(lambda: friction_damper_response(s, 0, ring_inertia=jr, slip_torque=ts,
                                                  speed_rpm=rpm[:1], order=1.0, torque=t))
    t_ti = median_time(lambda: time_domain_sdof(inertia=jh, stiffness=k, damping=c,
                                                ring_inertia=jr, slip_torque=ts,
                                                omega=rpm[0] * np.pi / 30, torque=t,
                                                cycles=100, steps_per_cycle=240), repeats=1)
    return [Row(SUITE, "friction damper", "harmonic balance (first harmonic)", err, "max rel",
                "time integration of the non-linear system", t_hb, "time integration",
                t_hb / t_ti, bound=0.05, note=f"{len(rpm)} speeds across the resonance")]


def _throw_inertia_rows(timer):
    from crankbench.predict.engine import Engine
    from crankbench.predict.torsion.elements import crank_throw_inertia

    rows = []
    for lam in (0.25, 0.4):
        e = Engine(crank_angles_deg=[0], crank_radius=0.1, rod_length=0.1 / lam,
                   reciprocating_mass=10.0)
        exact = crank_throw_inertia(e, 1)
        short = crank_throw_inertia(e, 1, exact=False)
        t_x = timer(lambda: crank_throw_inertia(e, 1))
        t_s = timer(lambda: crank_throw_inertia(e, 1, exact=False))
        rows.append(Row(SUITE, "crank-throw equivalent inertia", f"1/2 + λ²/8, λ = {lam:g}",
                        abs(short / exact - 1), "rel", "exact energy mean (720-point rule)",
                        t_s, "exact mean", t_s / t_x,
                        bound=1.2 * (lam ** 4 / 16 + 5 * lam ** 6 / 128)
                        / (0.5 + lam ** 2 / 8), note="reciprocating part only"))
    return rows


def _journal_rows(timer):
    from crankbench.predict.lateral.journal import JournalBearing

    kw = dict(diameter=0.1, radial_clearance=5e-5, viscosity=0.02)
    fin = JournalBearing(length=0.05, **kw)
    sho = JournalBearing(length=0.05, model="short", **kw)
    load = (0.0, -2000.0)
    ef = fin.coefficients(load=load, omega=300.0).eccentricity
    es = sho.coefficients(load=load, omega=300.0).eccentricity
    t_f = timer(lambda: fin.forces(2e-5, -1e-5, omega=300.0))
    t_s = timer(lambda: sho.forces(2e-5, -1e-5, omega=300.0))
    rb = JournalBearing(length=0.1, **kw)
    s, _ = rb.sommerfeld_at(0.6)
    return [Row(SUITE, "journal bearing", "short bearing (Ocvirk), L/D = 0.5", abs(es / ef - 1),
                "rel eccentricity", "finite-length Reynolds solution", t_s, "finite-length",
                t_s / t_f, note="one force evaluation"),
            Row(SUITE, "journal bearing", "finite-length Reynolds 96×12, L/D = 1", abs(s / 0.121
                                                                                        - 1),
                "rel Sommerfeld number", "Raimondi & Boyd (1958), ε = 0.6", t_f, bound=0.015)]


def run(quick: bool = False) -> list[Row]:
    timer = _time(quick)
    rows = _piston_rows(quick, timer)
    rows.append(_rod_row(timer))
    rows += _double_acting_rows(quick)
    rows += _stodola_rows(quick, timer)
    rows += _shaft_rows(quick, timer)
    rows.append(_resonance_row(timer))
    rows += _friction_rows(quick, timer)
    rows += _throw_inertia_rows(timer)
    rows += _journal_rows(timer)
    return rows
