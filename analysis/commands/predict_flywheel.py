"""``crankbench predict flywheel ENGINE.toml --speed-rpm N``: turning-moment summary, fluctuation
of energy, coefficient of speed fluctuation for a given inertia or the flywheel inertia, mass and
rim stress for a required coefficient."""

from __future__ import annotations

HELP = "turning moment, energy fluctuation and flywheel sizing at one speed"


def configure(parser) -> None:
    from crankbench.analysis.commands._args import number

    parser.add_argument("model", help="engine TOML ([engine] with bore, compression_ratio and "
                                      "[engine.combustion])")
    parser.add_argument("--speed-rpm", type=number(low=0.0, strict_low=True, unit="rpm"),
                        required=True, help="mean crank speed, rpm")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")
    parser.add_argument("--coefficient", type=number(low=0.0, high=1.0, strict_low=True),
                        default=0.01,
                        help="required coefficient of speed fluctuation, (0, 1] (default 0.01)")
    parser.add_argument("--inertia", type=number(low=0.0, strict_low=True, unit="kg*m^2"),
                        default=None,
                        help="existing total inertia, kg m²: report its speed fluctuation")
    parser.add_argument("--radius", type=number(low=0.0, strict_low=True, unit="m"),
                        default=None, help="flywheel rim mean radius, m (default: 2.5 × stroke)")
    parser.add_argument("--density", type=number(low=0.0, strict_low=True, unit="kg/m^3"),
                        default=7200.0,
                        help="flywheel material density, kg/m³ (default cast iron 7200)")
    parser.add_argument("--shape", choices=["rim", "disc"], default="rim")
    parser.add_argument("--imep", type=number(low=0.0, strict_low=True, unit="Pa"), default=None,
                        help="IMEP, Pa (or with its unit: '12 bar'), for the synthetic pressure "
                             "(default: the engine's [engine.combustion])")


def run(args) -> int:
    import numpy as np

    from crankbench.analysis._output import print_json, print_table
    from crankbench.predict.engine import Engine
    from crankbench.predict.errors import ConfigError
    from crankbench.predict.flywheel import design_flywheel, turning_moment
    from crankbench.predict.pressure import synthetic_pressure

    if args.speed_rpm <= 0:
        raise ConfigError(f"--speed-rpm={args.speed_rpm!r} must be > 0")
    engine = Engine.from_toml(args.model)
    pressure = synthetic_pressure(engine, imep=args.imep) if args.imep else synthetic_pressure(
        engine)
    omega = args.speed_rpm * np.pi / 30
    from crankbench.predict.flywheel import load_from_toml

    tm = turning_moment(engine, omega=omega, pressure=pressure)
    load = load_from_toml(args.model)          # optional [load] table: load with harmonics
    if load is not None:
        mean = tm.mean_torque if load.fixed_mean is None else load.fixed_mean
        tm = turning_moment(engine, omega=omega, pressure=pressure,
                            load_torque=lambda a: load(a, mean))
    radius = args.radius or 2.5 * engine.stroke
    design = design_flywheel(tm, coefficient=args.coefficient, outer_radius=radius,
                             density=args.density, shape=args.shape)
    summary = {
        "model": str(args.model), "engine": engine.name, "speed_rpm": args.speed_rpm,
        "imep_pa": pressure.imep(engine), "mean_torque_nm": tm.mean_torque,
        "max_torque_nm": float(tm.torque.max()), "min_torque_nm": float(tm.torque.min()),
        "power_kw": tm.power / 1e3, "fluctuation_of_energy_j": tm.fluctuation_of_energy,
        "fluctuation_error_j": tm.fluctuation_error(),
    }
    if args.inertia:
        summary["inertia_kgm2"] = args.inertia
        summary["coefficient_of_speed_fluctuation"] = tm.speed_fluctuation(args.inertia)
    frame = design.to_frame()
    crossings = tm.crossings()
    if args.json:
        print_json({**summary, "flywheel": frame, "crossings": crossings})
        return 0
    import pandas as pd

    print_table(pd.DataFrame([summary]).drop(columns=["model"]).T.reset_index().rename(
        columns={"index": "quantity", 0: "value"}), title=f"{engine.name}: turning moment")
    print()
    print_table(frame, title=f"flywheel for coefficient {args.coefficient:g}")
    print()
    print_table(crossings, title="crossings of the turning moment with the load")
    return 0
