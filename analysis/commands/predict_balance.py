"""``crankbench predict balance ENGINE.toml``: the balance residual table of an engine — shaking
force and moment per order before and after counterweights and balance shafts — and, when the
file has a ``[mounts]`` table, the rigid-body modes on the mounts and the forces transmitted to
the foundation by each residual order."""

from __future__ import annotations

HELP = "balance residuals per order (forces, moments, counterweights, balance shafts, mounts)"


def configure(parser) -> None:
    from crankbench.analysis.commands._args import add_list, integer, number

    parser.add_argument("model", help="engine TOML ([engine] table, optional [mounts])")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")
    parser.add_argument("--speed-rpm", type=number(low=0.0, strict_low=True, unit="rpm"),
                        default=None,
                        help="crank speed, rpm (default: the engine's rated_speed_rpm)")
    add_list(parser, "--orders", item=integer(low=1, high=100), metavar="N",
             default=[1, 2, 4, 6, 8], help="engine orders to list (default 1,2,4,6,8)")
    parser.add_argument("--balance-factor", type=number(low=0.0, high=1.0), default=None,
                        help="fit per-throw counterweights balancing all the rotating mass and "
                             "this fraction (0..1) of the reciprocating mass")
    add_list(parser, "--shafts", item=integer(low=1, high=100), metavar="N", default=[],
             help="orders to cancel with Lanchester balance shafts (e.g. 1,2)")
    parser.add_argument("--shaft-planes", type=number(unit="m"), nargs=2, default=None,
                        metavar=("Z_A", "Z_B"),
                        help="two axial planes (m) for the shafts, to cancel moments as well")


def run(args) -> int:
    import numpy as np

    from crankbench.analysis._output import print_json, print_table
    from crankbench.predict.balance import balance_residuals
    from crankbench.predict.engine import Engine
    from crankbench.predict.errors import ConfigError

    engine = Engine.from_toml(args.model)
    rpm = args.speed_rpm or engine.rated_speed_rpm
    if rpm is None:
        raise ConfigError(f"{args.model}: [engine] has no rated_speed_rpm; give --speed-rpm N")
    if rpm <= 0:
        raise ConfigError(f"--speed-rpm={rpm!r} must be > 0")
    omega = rpm * np.pi / 30
    res = balance_residuals(engine, omega=omega, orders=args.orders,
                            balance_factor=args.balance_factor, shaft_orders=args.shafts,
                            shaft_positions=args.shaft_planes)
    table = res.to_frame()
    out = {"model": str(args.model), "engine": engine.name, "speed_rpm": rpm,
           "reference_position_m": engine.reference_position, "measures": list(res.measures),
           "residuals": table}
    mounts_out = _mounts(args.model, engine, omega, res)
    if mounts_out is not None:
        out.update(mounts_out)
    if args.json:
        print_json(out)
        return 0
    print(f"{engine.name} at {rpm:g} rpm — moments about x = {engine.reference_position:g} m")
    print("measures: " + "; ".join(res.measures))
    cols = ["order", "force_unbalanced_n", "force_n", "force_forward_n", "force_backward_n",
            "moment_unbalanced_nm", "moment_nm", "moment_forward_nm", "moment_backward_nm"]
    print_table(table[cols], title="balance residuals (peak over a revolution)")
    if mounts_out is not None:
        print()
        print_table(mounts_out["mount_modes"], title="rigid-body modes on the mounts")
        print()
        print_table(mounts_out["transmitted"],
                    title="force on the foundation per residual order (peak, N)")
    return 0


def _mounts(path, engine, omega, res):
    """Modes on the mounts and transmitted forces of each residual order, if [mounts] exists."""
    import tomllib

    import numpy as np
    import pandas as pd

    from crankbench.predict.balance import unbalance
    from crankbench.predict.mounts import MountedEngine, excitation_from_unbalance

    with open(path, "rb") as fh:
        if "mounts" not in tomllib.load(fh):
            return None
    mounted = MountedEngine.from_toml(path)
    modes = mounted.modes()
    ds = unbalance(engine, omega=omega, orders=res.orders, counterweights=res.counterweights,
                   shafts=res.shafts)
    rows = []
    for order in res.orders:
        ex = excitation_from_unbalance(ds, int(order))
        r = mounted.response(ex["force"], ex["moment"], ex["freq_hz"], point=ex["point"])
        tot = np.abs(r.transmitted[0])
        rows.append({"order": int(order), "freq_hz": ex["freq_hz"], "force_x_n": tot[0],
                     "force_y_n": tot[1], "force_z_n": tot[2],
                     "largest_mount_n": float(np.abs(r.mount_forces[0]).max())})
    return {"mount_modes": modes.to_frame()[["mode", "frequency_hz", "dominant"]],
            "transmitted": pd.DataFrame(rows)}
