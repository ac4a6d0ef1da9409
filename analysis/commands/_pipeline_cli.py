"""Command-line glue shared by ``compare``, ``report``, ``batch`` and ``demo``: the common
arguments, their check before any work, their translation into
:func:`analysis.pipeline.analyse` options, a progress bar."""

from __future__ import annotations

import logging

from crankbench.analysis.commands._args import add_list, number, positive_order
from crankbench.analysis.pipeline import LoadCase, load_from_record_file

__all__ = ["add_common_arguments", "check_common", "options_from_args", "vibrograph_options",
           "progress_bar"]

log = logging.getLogger("crankbench")

#: highest order the pipeline predicts (analysis.pipeline.analyse max_order)
MAX_ORDER = 12.0


def add_common_arguments(parser) -> None:
    """Arguments shared by ``compare``, ``report`` and ``batch``."""
    parser.add_argument("--map", metavar="MAP.toml", default=None,
                        help="channel map for the record(s): columns, units, calibration, raw "
                             "pulse roles")
    parser.add_argument("--channel", metavar="NAME", default=None,
                        help="torsional channel (default: the first angle/angular-velocity one)")
    parser.add_argument("--speed-channel", metavar="NAME", default=None,
                        help="speed source (default: found in the record)")
    add_list(parser, "--orders", item=positive_order, metavar="Q",
             help="orders to track, e.g. 3,6 (default: the strongest predicted ones)")
    parser.add_argument("--method", choices=("vkf", "cot"), default="vkf",
                        help="order tracker: Vold-Kalman (default) or computed order tracking")
    parser.add_argument("--bandwidth-orders", type=number(low=0.0, high=2.0, strict_low=True),
                        default=None, metavar="B",
                        help="VKF bandwidth in orders, (0, 2] (default: 0.25, wider for fast "
                             "sweeps)")
    parser.add_argument("--imep", type=number(low=0.0, high=1000.0, strict_low=True, unit="bar"),
                        metavar="BAR", default=None,
                        help="load for the predicted excitation, bar (default: the run's load "
                             "stored with a synthetic record, else the model's imep)")
    parser.add_argument("--load-law", choices=("constant", "propeller"), default=None,
                        help="gas load against speed (propeller: ∝ speed²)")
    parser.add_argument("--reference-rpm", type=number(low=0.0, strict_low=True, unit="rpm"),
                        default=None,
                        metavar="RPM",
                        help="speed at which --imep applies for the propeller law, rpm (> 0)")
    parser.add_argument("--gate", type=number(low=0.0, high=1.0, strict_low=True), default=0.15,
                        help="largest relative speed deviation of a match, (0, 1] "
                             "(default 0.15)")
    parser.add_argument("--tolerance", type=number(low=0.0, high=1.0, strict_low=True),
                        default=0.03,
                        help="relative speed deviation flagged as disagreement, (0, --gate] "
                             "(default 0.03)")
    parser.add_argument("--vibration-standard", choices=("ISO 10816-6", "ISO 10816-1"),
                        default=None,
                        help="vibration-severity zones (default: the model's "
                             "[limits.vibration], else ISO 10816-6 for reciprocating machines)")
    parser.add_argument("--machine-class", default=None,
                        help="class of that standard (ISO 10816-6: 1-7, ISO 10816-1: I-IV; "
                             "default: the model's, else chosen from the engine's power and "
                             "mounting)")
    parser.add_argument("--vibration-tolerance", type=number(low=0.0, high=100.0, strict_low=True),
                        default=0.5, metavar="T",
                        help="block/mount vibration against the engine model: measured/"
                             "predicted order amplitude within [1/(1+T), 1+T] (default 0.5)")


def check_common(args, *, records=(), model=None) -> None:
    """Check the common arguments against each other, the model and each record's channels,
    before any work (reading a record's header only).

    Raises
    ------
    ConfigError, ModelError, RecordError
        Naming the flag (``--reference-rpm``, ``--channel``) or file at fault.
    """
    from crankbench.predict.errors import ConfigError, RecordError

    if args.tolerance > args.gate:
        raise ConfigError(f"--tolerance {args.tolerance:g} must not exceed --gate {args.gate:g} "
                          "(a deviation beyond the gate is never matched)")
    if args.reference_rpm is not None and args.load_law != "propeller":
        raise ConfigError("--reference-rpm applies to --load-law propeller only (the speed at "
                          "which --imep holds)")
    if args.bandwidth_orders is not None and args.method != "vkf":
        raise ConfigError("--bandwidth-orders applies to --method vkf only")
    if args.machine_class is not None:
        from crankbench.analysis.limits import zone_boundaries
        from crankbench.predict.errors import CrankbenchError

        standard = getattr(args, "vibration_standard", None) or "ISO 10816-6"
        try:
            zone_boundaries(args.machine_class, standard=standard)
        except CrankbenchError as exc:
            raise ConfigError(f"--machine-class {args.machine_class!r} is not a class of "
                              f"{standard} ({exc})") from None
    engine = None
    if model is not None:   # a bad model fails now, not after the record is tracked
        from crankbench.analysis.vibrograph import model_kind

        if model_kind(model) == "engine":     # vibrograph comparison against the engine
            from crankbench.predict.engine import Engine

            engine = Engine.from_toml(model)
        else:
            from crankbench.predict.torsion import from_toml

            engine = from_toml(model).engine
        if args.load_law == "propeller" and args.reference_rpm is None and getattr(
                engine, "rated_speed_rpm", None) is None:
            raise ConfigError(f"--load-law propeller needs --reference-rpm: the engine of {model} "
                              "has no rated_speed_rpm")
    if args.orders and max(args.orders) > MAX_ORDER:
        raise ConfigError(f"--orders {max(args.orders):g} is above the highest order the "
                          f"prediction covers ({MAX_ORDER:g})")
    if args.orders and engine is not None:
        step = 0.5 if engine.cycle == 4 else 1.0
        odd = [q for q in args.orders if abs(q / step - round(q / step)) > 1e-9]
        if odd:
            raise ConfigError(f"--orders {','.join(f'{q:g}' for q in odd)}: not an order of this "
                              f"{engine.cycle}-stroke engine (multiples of {step:g})")
    for path in records:
        names = _channels(path, getattr(args, "map", None))
        if names is None:
            continue
        from crankbench.predict._validate import suggest

        for flag, name in (("--channel", args.channel), ("--speed-channel", args.speed_channel)):
            if name is not None and name not in names:
                raise RecordError(f"{flag} {name!r}: record has no channel {name!r}"
                                  f"{suggest(name, names)}; channels: {', '.join(names)} "
                                  f"({path})")


def _channels(path, channel_map=None):
    """Channel names of a record from its header (lazy open, through the channel map when
    given), None if it cannot be opened here (the analysis then reports the file's own
    error)."""
    from crankbench.measure import io as mio
    from crankbench.predict.errors import CrankbenchError

    try:
        kwargs = {"map": channel_map} if channel_map else {}
        return [str(n) for n in mio.open(path, **kwargs).data_vars]
    except (CrankbenchError, OSError):
        return None


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


#: options of the shaft-line comparison with their defaults; given with an engine model they
#: have no effect, which is said rather than passed over
_TORSIONAL_ONLY = {"method": "vkf", "bandwidth_orders": None, "gate": 0.15, "tolerance": 0.03}


def vibrograph_options(options) -> dict:
    """The options of :func:`analysis.vibrograph.compare_vibrograph` among those of
    :func:`options_from_args` (an engine model: no torsional channel, no criticals). The
    channel map reads the record; ``--channel`` selects the one vibrograph channel compared;
    an option that only a shaft-line comparison uses is named in a warning, not dropped
    silently."""
    unused = [f"--{key.replace('_', '-')} {options[key]}" for key, default
              in _TORSIONAL_ONLY.items() if options.get(key, default) != default]
    unused += [f"--{key.replace('_', '-')} {options[key]}"
               for key in ("machine_class", "vibration_standard") if options.get(key)]
    if unused:
        log.warning("%s: not used with an engine model (block/mount vibration per order is "
                    "compared with a fixed %d-revolution order track, and no severity zone is "
                    "judged); these apply to a shaft-line model", ", ".join(unused), 8)
    channel = options.get("channel")
    return dict(load=options.get("load"), speed_channel=options.get("speed_channel"),
                orders=options.get("orders"), channel_map=options.get("channel_map"),
                channels=None if channel is None else [channel],
                tolerance=options.get("vibration_tolerance", 0.5))


def progress_bar(total_steps: int | None = None, *, desc: str = "", disable: bool = False):
    """A tqdm bar over the pipeline steps (default: :data:`analysis.pipeline.STEPS`) and the
    ``progress(step)`` callback that moves it."""
    from tqdm import tqdm

    if total_steps is None:
        from crankbench.analysis.pipeline import STEPS

        total_steps = len(STEPS)
    bar = tqdm(total=total_steps, desc=desc, unit="step", leave=False, disable=disable)

    def progress(step_name):
        bar.set_postfix_str(step_name)
        bar.update(1)

    return bar, progress
