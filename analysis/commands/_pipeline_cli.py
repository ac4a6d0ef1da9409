"""Command-line glue shared by ``compare``, ``report``, ``batch`` and ``demo``: the common
arguments, their translation into :func:`analysis.pipeline.analyse` options, a progress bar."""

from __future__ import annotations

import logging

from crankbench.analysis.pipeline import LoadCase, load_from_record_file

__all__ = ["add_common_arguments", "options_from_args", "vibrograph_options", "progress_bar"]

log = logging.getLogger("crankbench")


def add_common_arguments(parser) -> None:
    """Arguments shared by ``compare``, ``report`` and ``batch``."""
    parser.add_argument("--map", metavar="MAP.toml", default=None,
                        help="channel map for the record(s): columns, units, calibration, raw "
                             "pulse roles")
    parser.add_argument("--channel", metavar="NAME", default=None,
                        help="torsional channel (default: the first angle/angular-velocity one)")
    parser.add_argument("--speed-channel", metavar="NAME", default=None,
                        help="speed source (default: found in the record)")
    parser.add_argument("--orders", type=float, nargs="+", metavar="Q", default=None,
                        help="orders to track (default: the strongest predicted ones)")
    parser.add_argument("--method", choices=("vkf", "cot"), default="vkf",
                        help="order tracker: Vold-Kalman (default) or computed order tracking")
    parser.add_argument("--bandwidth-orders", type=float, default=None, metavar="B",
                        help="VKF bandwidth in orders (default: 0.25, wider for fast sweeps)")
    parser.add_argument("--imep", type=float, metavar="BAR", default=None,
                        help="load for the predicted excitation, bar (default: the run's load "
                             "stored with a synthetic record, else the model's imep)")
    parser.add_argument("--load-law", choices=("constant", "propeller"), default=None,
                        help="gas load against speed (propeller: ∝ speed²)")
    parser.add_argument("--reference-rpm", type=float, default=None, metavar="RPM",
                        help="speed at which --imep applies for the propeller law")
    parser.add_argument("--gate", type=float, default=0.15,
                        help="largest relative speed deviation of a match (default 0.15)")
    parser.add_argument("--tolerance", type=float, default=0.03,
                        help="relative speed deviation flagged as disagreement (default 0.03)")
    parser.add_argument("--vibration-standard", choices=("ISO 10816-6", "ISO 10816-1"),
                        default=None,
                        help="vibration-severity zones (default: the model's "
                             "[limits.vibration], else ISO 10816-6 for reciprocating machines)")
    parser.add_argument("--machine-class", default=None,
                        help="class of that standard (ISO 10816-6: 1-7, ISO 10816-1: I-IV; "
                             "default: the model's, else chosen from the engine's power and "
                             "mounting)")
    parser.add_argument("--vibration-tolerance", type=float, default=0.5, metavar="T",
                        help="block/mount vibration against the engine model: measured/"
                             "predicted order amplitude within [1/(1+T), 1+T] (default 0.5)")


def options_from_args(args, record_path=None) -> dict:
    """Keyword arguments of :func:`analyse` from parsed CLI arguments."""
    load = None
    if args.imep is not None or args.load_law is not None:
        load = LoadCase(imep=None if args.imep is None else args.imep * 1e5,
                        law=args.load_law or "constant", reference_rpm=args.reference_rpm)
    elif record_path is not None:
        load = load_from_record_file(record_path)
        if load is not None:
            log.debug("load from the record's scene: %s, imep %s Pa", load.law, load.imep)
    return dict(channel_map=args.map, channel=args.channel, speed_channel=args.speed_channel,
                orders=args.orders,
                method=args.method, bandwidth_orders=args.bandwidth_orders, load=load,
                gate=args.gate, tolerance=args.tolerance,
                machine_class=args.machine_class,
                vibration_standard=getattr(args, "vibration_standard", None),
                vibration_tolerance=getattr(args, "vibration_tolerance", 0.5))


def vibrograph_options(options) -> dict:
    """The options of :func:`analysis.vibrograph.compare_vibrograph` among those of
    :func:`options_from_args` (an engine model: no torsional channel, no criticals)."""
    return dict(load=options.get("load"), speed_channel=options.get("speed_channel"),
                orders=options.get("orders"),
                tolerance=options.get("vibration_tolerance", 0.5))


def progress_bar(total_steps: int = 7, *, desc: str = "", disable: bool = False):
    """A tqdm bar over the pipeline steps and the ``progress(step)`` callback that moves it."""
    from tqdm import tqdm

    bar = tqdm(total=total_steps, desc=desc, unit="step", leave=False, disable=disable)

    def progress(step_name):
        bar.set_postfix_str(step_name)
        bar.update(1)

    return bar, progress
