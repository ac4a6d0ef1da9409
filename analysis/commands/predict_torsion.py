"""``crankbench predict torsion MODEL.toml``: natural frequencies, mode table, critical speeds,
resonance amplitudes (energy balance vs exact) and worst vibratory stresses of a shaft line;
with a non-linear friction damper in the model, its harmonic-balance response per order
instead of the linear resonance table."""

from __future__ import annotations

HELP = "torsional vibration of a shaft line: frequencies, critical speeds, stresses"


def configure(parser) -> None:
    from crankbench.analysis.commands._args import integer, number

    parser.add_argument("model", help="shaft-line TOML ([shaftline] table)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")
    parser.add_argument("--speed-range", nargs="+", metavar=("LOW", "HIGH"),
                        help="crankshaft speed range, rpm: LOW HIGH or LOW,HIGH (default: the "
                             "model's speed_range_rpm)")
    parser.add_argument("--max-order", type=number(low=0.0, high=200.0, strict_low=True),
                        default=12.0, help="highest excitation order (default 12)")
    parser.add_argument("--modes", type=integer(low=1, high=10000), default=8,
                        help="elastic modes to list (default 8)")
    parser.add_argument("--imep", type=number(low=0.0, strict_low=True, unit="Pa"), default=None,
                        help="mean indicated pressure, Pa (or with its unit: '22 bar'), for the "
                             "excitation")
    parser.add_argument("--speeds", type=integer(low=2, high=10**6), default=400,
                        help="number of speeds for the forced response (default 400)")
    parser.add_argument("--min-vector-sum", type=number(low=0.0), default=0.2,
                        help="list criticals with relative vector sum >= this (default 0.2)")
    parser.add_argument("--no-forced", action="store_true",
                        help="skip forced response, resonance amplitudes and stresses")


def run(args) -> int:
    import numpy as np
    import pandas as pd

    from crankbench.analysis._output import print_json, print_table
    from crankbench.predict.torsion import from_toml
    from crankbench.predict.torsion.resonance import resonance_amplitudes
    from crankbench.predict.torsion.stress import check_stress

    from crankbench.analysis.commands._args import check_pair

    given = check_pair(args.speed_range, "--speed-range", low=0.0, unit="rpm")
    system = from_toml(args.model)
    rng = given or system.operating.get("speed_range_rpm")
    if rng is None:
        rated = getattr(system.engine, "rated_speed_rpm", None)
        rng = (0.25 * rated, 1.1 * rated) if rated else None
    if rng is None:
        from crankbench.predict.errors import ConfigError

        raise ConfigError(f"{args.model}: no [shaftline] speed_range_rpm and no engine "
                          "rated_speed_rpm; give --speed-range LOW HIGH (rpm)")
    lo, hi = float(rng[0]), float(rng[1])
    if not args.no_forced:
        from crankbench.predict._memory import check_allocation
        from crankbench.predict.errors import ConfigError

        n_orders = len(system.default_orders(args.max_order))
        # forced response: complex angle and torque per (speed, order, node/section), a few
        # copies while superposing
        check_allocation(16.0 * 4 * args.speeds * n_orders * 2 * system.n_nodes,
                         what=f"--speeds {args.speeds} × {n_orders} orders × {system.n_nodes} "
                              "masses (forced response)",
                         hint="lower --speeds or --max-order, or use --no-forced",
                         error=ConfigError)
    modes = system.mode_shapes()
    freqs = modes.frequencies_hz
    elastic = np.flatnonzero(modes.mode_numbers > 0)[: args.modes]
    rel = modes.relative()
    mode_table = pd.DataFrame({
        "mode": modes.mode_numbers[elastic],
        "frequency_hz": freqs[elastic],
        "frequency_cpm": freqs[elastic] * 60.0,
        "max_amplitude_node": [system.node_names[int(np.argmax(np.abs(rel[:, i])))]
                               for i in elastic],
    })
    orders = system.default_orders(args.max_order)
    crit = system.critical_speeds(orders, (lo, hi))
    crit_shown = crit[(crit["vector_sum"].isna()) | (crit["vector_sum"] >= args.min_vector_sum)]
    out = dict(model=str(args.model), name=system.name, nodes=list(system.node_names),
               eigen_method=modes.method, relative_error_bound=modes.relative_error_bound,
               speed_range_rpm=[lo, hi], modes=mode_table, critical_speeds=crit_shown)
    forced_ok = (not args.no_forced and system.engine is not None and system.cylinder_nodes)
    if forced_ok:
        speeds = np.linspace(max(lo, 1.0), hi, args.speeds)
        if system.friction_dampers:
            # non-linear friction ring: harmonic balance per order replaces the linear
            # resonance table (which would leave the ring out)
            from crankbench.predict.torsion.friction_line import friction_forced_response

            fr = friction_forced_response(system, speeds, orders=orders,
                                          imep=args.imep or system.operating.get("imep"))
            resp = fr.forced
            peaks = fr.peaks().sort_values("hub_amplitude_deg", ascending=False)
            out["friction_damper"] = dict(name=fr.damper, node=fr.node,
                                          method=resp.method, peaks=peaks.head(8))
        else:
            out["resonances"] = resonance_amplitudes(
                system, orders=orders, speed_range_rpm=(lo, hi),
                imep=args.imep or system.operating.get("imep"),
                min_vector_sum=args.min_vector_sum)
            resp = system.forced_response(speeds, orders=orders,
                                          imep=args.imep or system.operating.get("imep"))
        frame = resp.to_frame()
        worst = frame.sort_values("max_stress_mpa", ascending=False).head(5)
        out["worst_stresses"] = worst
        if system.limits is not None:
            chk = check_stress(resp, system.limits)
            out["limits"] = dict(source=system.limits.source, passed=chk.passed,
                                 barred_ranges_rpm=chk.barred_ranges_rpm,
                                 transient_exceeded_rpm=chk.transient_exceeded_rpm)
    if args.json:
        print_json(out)
        return 0
    print(f"{system.name}: {system.n_nodes} masses, eigen-solver {modes.method} "
          f"(relative error bound {modes.relative_error_bound:.1e})")
    print_table(mode_table, title="\nNatural frequencies")
    print_table(crit_shown, title=f"\nCritical speeds {lo:g}-{hi:g} rpm "
                                  f"(relative vector sum >= {args.min_vector_sum:g})")
    if forced_ok:
        if "friction_damper" in out:
            fd = out["friction_damper"]
            print_table(fd["peaks"], title=f"\nFriction damper {fd['name']!r} on {fd['node']!r}: "
                                           "largest hub amplitudes (harmonic balance of the "
                                           "stick-slip ring, each order alone)")
        else:
            cols = ["mode", "order", "speed_rpm", "vector_sum", "node", "amplitude_deg",
                    "energy_balance_deg", "method_error", "dynamic_magnifier",
                    "max_stress_mpa", "section"]
            print_table(out["resonances"][cols], title="\nResonance amplitudes (exact damped "
                                                        "solve; classical energy balance "
                                                        "beside)")
        print_table(out["worst_stresses"], title="\nWorst superposed stresses")
        if "limits" in out:
            lim = out["limits"]
            barred = ", ".join(f"{a:.0f}-{b:.0f}" for a, b in lim["barred_ranges_rpm"]) or "none"
            print(f"\nLimits ({lim['source']}): barred speed ranges [rpm]: {barred}; "
                  f"transient limit {'kept' if lim['passed'] else 'EXCEEDED'}")
    elif not args.no_forced:
        print("\n(no engine with cylinders attached: forced response skipped)")
    return 0
