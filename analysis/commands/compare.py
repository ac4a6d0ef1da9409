"""``crankbench compare RECORD MODEL.toml [--channel NAME] [--json]``: measurement vs model.

With a shaft-line model: the chain of :mod:`analysis.pipeline` — order tracking of the
torsional channel, resonance identification, the model's critical speeds and resonance curves
at the measured node, their assignment — and prints the matched critical speeds with
deviations (rpm, %) and amplitude ratios, the natural frequencies per mode collected across
orders, what stayed unmatched, the limit checks, and the block/mount vibration of any
vibrograph channel when the engine has ``[mounts]``. With an engine model (``[engine]`` and
``[mounts]``, no shaft line): the vibrograph comparison alone
(:func:`analysis.vibrograph.compare_vibrograph`) — predicted against measured vibration per
(sensor, order), and the residual shaking forces and moments when enough sensors.
``--strict`` exits with status 1 when anything disagrees.
"""

from __future__ import annotations

HELP = ("compare a record with a shaft-line model (critical speeds) or an engine model on "
        "its mounts (block/mount vibration per order)")


def configure(parser) -> None:
    from crankbench.analysis.commands._pipeline_cli import add_common_arguments

    parser.add_argument("record", metavar="RECORD", help="record file (any supported format)")
    parser.add_argument("model", metavar="MODEL.toml",
                        help="shaft-line model, or an engine model with [mounts] (TOML)")
    add_common_arguments(parser)
    parser.add_argument("--strict", action="store_true",
                        help="exit with status 1 unless the overall verdict is a pass (a "
                             "failed or inconclusive check)")
    parser.add_argument("--store", metavar="FILE.duckdb", default=None,
                        help="also write the results into this campaign store (created if "
                             "missing; the same record and settings replace their rows)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")


def run(args) -> int:
    import logging
    from pathlib import Path

    from crankbench.analysis._output import print_json, print_table
    from crankbench.analysis.commands._pipeline_cli import options_from_args, progress_bar
    from crankbench.analysis.pipeline import analyse
    from crankbench.analysis.commands._files import (check_outputs, map_inputs, model_inputs,
                                                     record_inputs)
    from crankbench.analysis.commands._pipeline_cli import check_common
    from crankbench.analysis.vibrograph import model_kind
    from crankbench.analysis.vibrograph_report import print_vibrograph, vibrograph_json
    from crankbench.predict.errors import ConfigError

    log = logging.getLogger("crankbench")
    quiet = args.json or log.getEffectiveLevel() > logging.INFO
    if args.store:
        check_outputs([(Path(args.store), f"--store {args.store}")],
                      record_inputs(args.record) + model_inputs(args.model) + map_inputs(args))
    check_common(args, records=[args.record], model=args.model)   # before any work
    if model_kind(args.model) == "engine":
        if args.store:
            raise ConfigError("--store keeps shaft-line runs; an engine model's vibrograph "
                              "comparison is not stored (use --json)")
        return _run_engine(args, quiet)
    bar, progress = progress_bar(desc="compare", disable=quiet)
    options = options_from_args(args, args.record)
    try:
        result = analyse(args.record, args.model, progress=progress, **options)
    finally:
        bar.close()
    if args.store:
        from crankbench.analysis.campaign.documents import store_result

        run_id = store_result(args.store, result, record_path=args.record,
                              model_path=args.model, settings=options,
                              elapsed_s=float(sum(result.timings.values())))
        log.info("stored as run %s in %s", run_id, args.store)
    vib = result.vibrograph
    comp = result.comparison
    limits = [c.as_dict() for c in result.limits]
    if args.json:
        print_json({"summary": result.summary(), "matched": comp.matched,
                    "natural_frequencies": comp.natural_frequencies,
                    "unmatched_measured": comp.unmatched_measured,
                    "unmatched_predicted": comp.unmatched_predicted,
                    "resonances": result.resonances.to_frame(), "limits": limits,
                    "verdict": result.verdict.as_dict(),
                    "checks": [v.as_dict() for v in result.verdicts],
                    "flags": list(comp.flags), "settings": result.settings,
                    "vibrograph": None if vib is None else vibrograph_json(vib),
                    "measured_excitation": None if result.pressure is None
                    else result.pressure.summary()})
    else:
        print(f"record   {result.source}  channel {result.channel} at {result.node}")
        print(f"model    {result.model_path}")
        print(f"speed    {result.speed_range_rpm[0]:.0f}–{result.speed_range_rpm[1]:.0f} rpm, "
              f"sweep {result.sweep_rate_rpm_per_s:.3g} rpm/s")
        print()
        cols = ["mode", "order", "speed_rpm_predicted", "speed_rpm_measured", "deviation_rpm",
                "deviation_pct", "amplitude_ratio", "confidence", "significant"]
        matched = comp.matched[cols].copy()
        if len(matched) and not matched["significant"].all():
            from crankbench.analysis.compare import not_judged_reason

            matched["judged"] = ["yes" if r["significant"] else "no: " + not_judged_reason(
                result.predicted, r["mode"], r["order"]) for _, r in matched.iterrows()]
        print_table(matched, title="matched critical speeds")
        print()
        print_table(comp.natural_frequencies, title="natural frequencies by mode")
        sig = comp.unmatched_predicted
        if len(sig):
            sig = sig[sig["significant"]]
        if len(sig):
            print()
            print_table(sig[[c for c in ("mode", "order", "speed_rpm", "amplitude", "status")
                             if c in sig]], title="predicted criticals not found")
        listed = comp.unmatched_predicted
        if len(listed):
            listed = listed[~listed["significant"]]
        if len(listed):          # in the range but not judged: say so, and why
            why = listed["not_judged"].fillna("") if "not_judged" in listed else \
                listed["mode"].map(lambda _: "")
            uncovered = listed[why != ""].assign(why=why[why != ""])
            if len(uncovered):
                print()
                print_table(uncovered[["mode", "order", "speed_rpm", "why"]],
                            title="predicted criticals listed, not judged")
            weak = int((why == "").sum())
            if weak:
                print(f"  ({weak} weaker predicted critical(s) in the range, below the "
                      "significance threshold: listed in the report and --json, not judged)")
        if len(comp.unmatched_measured):
            print()
            print_table(comp.unmatched_measured, title="measured resonances without a critical")
        print()
        if result.pressure is not None:
            print_table(result.pressure.table, title="measured response against the model's "
                        "prediction and the prediction from measured cylinder pressure")
            print(f"  ({result.pressure.note})")
            print()
        if comp.flags:
            print("disagreements:")
            for f in comp.flags:
                print(f"  - {f}")
            print()
        if vib is not None:
            print_vibrograph(vib, header=False)
            print()
        for c in result.verdicts:
            print(f"{c.status.upper():<12} {c.name}: {c.reason or c.basis}"
                  + ("" if c.required else "  (for information)"))
        v = result.verdict
        print(f"verdict: {v.status.upper()}" + (f" — {v.reason}" if v.status != "pass" else
                                                "  (every required check passed)"))
    if args.strict and not result.passed:
        return 1
    return 0


def _run_engine(args, quiet) -> int:
    """An engine model on its mounts: the vibrograph comparison alone."""
    from crankbench.analysis._output import print_json
    from crankbench.analysis.commands._pipeline_cli import (options_from_args, progress_bar,
                                                            vibrograph_options)
    from crankbench.analysis.vibrograph import compare_vibrograph
    from crankbench.analysis.vibrograph_report import print_vibrograph, vibrograph_json

    bar, progress = progress_bar(3, desc="compare", disable=quiet)
    try:
        result = compare_vibrograph(args.record, args.model, progress=progress,
                                    **vibrograph_options(options_from_args(args, args.record)))
    finally:
        bar.close()
    if args.json:
        print_json(vibrograph_json(result))
    else:
        print_vibrograph(result)
    if args.strict and not result.passed:
        return 1
    return 0

