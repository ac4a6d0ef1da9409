"""``crankbench predict lateral MODEL.toml``: lateral natural frequencies, critical speeds with
whirl direction, Campbell diagram and unbalance response of a rotor model ([rotor] table)."""

from __future__ import annotations

HELP = "lateral vibration of a rotor: critical speeds, whirl, Campbell diagram, unbalance response"


def configure(parser) -> None:
    from crankbench.analysis.commands._args import add_list, integer, positive_order

    parser.add_argument("model", help="rotor model TOML ([rotor] table, see sample_data/rotors)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")
    parser.add_argument("--speed-range", nargs="+", metavar=("LOW", "HIGH"),
                        help="spin speed range, rpm: LOW HIGH or LOW,HIGH (default: the "
                             "model's speed_range_rpm)")
    add_list(parser, "--orders", item=positive_order, metavar="Q",
             help="excitation orders, e.g. 1,2 (default: the model's orders)")
    parser.add_argument("--modes", type=integer(low=1, high=1000), default=None,
                        help="modes / critical speeds per order (default: the model's n_modes)")
    parser.add_argument("--speeds", type=integer(low=2, high=10**5), default=None,
                        help="speeds in the Campbell diagram and response (default: n_speeds)")
    parser.add_argument("--campbell", action="store_true",
                        help="also print the Campbell diagram table")


def run(args) -> int:
    import numpy as np

    from crankbench.analysis._output import print_json, print_table
    from crankbench.predict.errors import ConfigError
    from crankbench.predict.lateral.toml import load_rotor

    from crankbench.analysis.commands._args import check_pair

    given = check_pair(args.speed_range, "--speed-range", low=0.0, unit="rpm")
    model = load_rotor(args.model)
    rotor = model.rotor
    lo, hi = given or model.speed_range_rpm
    orders = tuple(args.orders or model.orders)
    n_modes = args.modes or model.n_modes
    n_speeds = args.speeds or model.n_speeds
    if n_modes < 1 or n_speeds < 2:
        raise ConfigError("--modes must be >= 1 and --speeds >= 2")
    at_rest = rotor.natural_frequencies(0.0, n_modes=2 * n_modes)
    crit = rotor.critical_speeds(orders, n_modes=n_modes, speed_range_rpm=(lo, hi))
    speeds = np.linspace(lo, hi, n_speeds) * np.pi / 30
    out = dict(model=str(args.model), name=rotor.name, theory=rotor.theory,
               n_elements=at_rest.n_elements, total_mass_kg=rotor.mass,
               speed_range_rpm=[lo, hi], orders=list(orders),
               natural_frequencies_at_rest=at_rest.to_frame().drop(columns=["speed_rpm",
                                                                           "theory"]),
               critical_speeds=crit.to_frame())
    if args.campbell or args.json:
        out["campbell"] = rotor.campbell(speeds, n_modes=2 * n_modes, orders=orders).to_frame()
    if model.unbalances:
        probes = sorted({b.position for b in rotor.bearings} | {u[0] for u in model.unbalances})
        resp = rotor.unbalance_response(speeds[speeds > 0], list(model.unbalances),
                                        probes=probes)
        frame = resp.to_frame()
        peaks = frame.loc[frame.groupby("position")["major_axis"].idxmax(),
                          ["position", "speed_rpm", "major_axis"]]
        out["unbalance_peaks"] = peaks.rename(columns={"major_axis": "peak_major_axis_m"})
        if args.json:
            out["unbalance_response"] = frame
    if args.json:
        print_json(out)
        return 0
    print(f"{rotor.name or args.model}: {rotor.theory}, {at_rest.n_elements} elements, "
          f"{rotor.mass:.4g} kg, speeds {lo:g}-{hi:g} rpm")
    print_table(out["natural_frequencies_at_rest"], title="\nnatural frequencies at rest")
    print_table(out["critical_speeds"], title=f"\ncritical speeds (orders {list(orders)})")
    if "campbell" in out:
        print_table(out["campbell"], title="\nCampbell diagram")
    if "unbalance_peaks" in out:
        print_table(out["unbalance_peaks"], title="\npeak unbalance response (orbit semi-major "
                                                  "axis, m)")
    return 0
