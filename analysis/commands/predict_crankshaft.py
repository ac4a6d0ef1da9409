"""``crankbench predict crankshaft ENGINE.toml``: main-bearing loads of the ``[crankshaft]``
beam and, with ``[crankshaft.fillets]``, the UR M53 stress-concentration factors and the
acceptability factor Q = σ_DW/σ_V of every throw at the crank-pin fillet, the journal fillet
and the oil-bore outlet, with a pass / fail / inconclusive verdict per location of the worst
throw (:mod:`predict.crankshaft_m53`)."""

from __future__ import annotations

HELP = "main-bearing loads and the UR M53 crankshaft acceptability (Q >= 1.15 per location)"


def configure(parser) -> None:
    from crankbench.analysis.commands._args import integer, number

    parser.add_argument("model", help="engine TOML with [crankshaft] (bearing_positions) and "
                                      "optionally [crankshaft.fillets]")
    parser.add_argument("--speed-rpm", type=number(low=0.0, strict_low=True, unit="rpm"),
                        default=None, help="crank speed, rpm (default: rated_speed_rpm)")
    parser.add_argument("--points", type=integer(low=8, high=100000), default=720,
                        help="crank angles over the cycle (default 720)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")


def m53_verdicts(assessment) -> list:
    """One :class:`~crankbench.analysis.verdict.Verdict` per location of an
    :class:`~crankbench.predict.crankshaft_m53.M53Assessment`.

    Examples
    --------
    >>> from crankbench.predict.crankshaft_m53 import M53Acceptance, M53Assessment
    >>> a = M53Assessment((M53Acceptance("crank-pin fillet", 2e8, 2.6e8, 1.3, 1.15, True),),
    ...                   basis="cylinder 1")
    >>> [v.status for v in m53_verdicts(a)]
    ['pass']
    """
    from crankbench.analysis.verdict import Verdict

    out = []
    for a in assessment.locations:
        detail = (f"Q = {a.q:.3f} (σ_DW {a.fatigue_strength / 1e6:.1f} MPa / σ_V "
                  f"{a.equivalent_stress / 1e6:.1f} MPa), required {a.required:g}")
        name = f"UR M53 {a.location}"
        if a.passed is None:
            out.append(Verdict.inconclusive(name, rule=a.clause, basis=assessment.basis,
                                            reason=f"{detail}; {a.reason}"))
        else:
            out.append(Verdict.from_bool(name, a.passed, rule=a.clause, basis=assessment.basis,
                                         reason="; ".join(filter(None, [detail, a.reason]))))
    return out


def run(args) -> int:
    import numpy as np
    import pandas as pd

    from crankbench.analysis._output import print_json, print_table
    from crankbench.analysis.verdict import combine
    from crankbench.predict._toml import load_toml
    from crankbench.predict.crankshaft import bearing_loads_from_toml
    from crankbench.predict.engine import Engine
    from crankbench.predict.errors import ConfigError

    engine = Engine.from_toml(args.model)
    rpm = args.speed_rpm or engine.rated_speed_rpm
    if rpm is None:
        raise ConfigError(f"{args.model}: [engine] has no rated_speed_rpm; give --speed-rpm N")
    loads = bearing_loads_from_toml(args.model, omega=rpm * np.pi / 30, points=args.points)
    out = {"model": str(args.model), "engine": engine.name, "speed_rpm": rpm,
           "beam_model": loads.model, "bearings": loads.to_frame()}
    ct = load_toml(args.model).table("crankshaft")
    if "fillets" in ct:
        from crankbench.predict.crankshaft_m53 import m53_from_toml

        res = m53_from_toml(args.model, speed_rpm=rpm, points=args.points)
        worst = res["worst"]
        verdicts = m53_verdicts(worst)
        overall = combine(verdicts, name="UR M53 crankshaft")
        out.update(scf=res["scf"].to_frame(),
                   throws=pd.DataFrame([{"throw": i + 1, "q_min": a.q_min, "status": a.status}
                                        for i, a in enumerate(res["throws"])]),
                   m53=worst.to_frame(), m53_basis=worst.basis,
                   verdicts=[v.as_dict() for v in verdicts], verdict=overall.as_dict())
    if args.json:
        print_json(out)
        return 0
    print(f"{engine.name} at {rpm:g} rpm — main bearings ({loads.model} beam)")
    print_table(out["bearings"], title="main-bearing loads over a cycle")
    if "m53" in out:
        print()
        print_table(out["scf"].drop(columns=["basis"]),
                    title="UR M53 stress-concentration factors")
        print()
        print_table(out["throws"], title="UR M53 smallest acceptability factor per throw")
        print()
        print_table(out["m53"].drop(columns=["reason"]),
                    title=f"UR M53 acceptability, worst throw ({out['m53_basis']})")
        print(f"verdict: {out['verdict']['verdict']} — {out['verdict']['rule']}")
        for v in out["verdicts"]:
            print(f"  {v['check']}: {v['verdict']} ({v['reason']})")
    return 0
