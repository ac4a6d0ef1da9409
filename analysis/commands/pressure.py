"""``crankbench pressure REC [--model ENGINE] [--json]``: indicator analysis of cylinder pressure.

For every cylinder-pressure channel of the record (or ``--channel``): crank angle from the
pulse wheel/encoder and the TDC mark, the firing TDC (phase) and how it was found, pegging,
the thermodynamic TDC check, peak pressure and its angle (mean cycle and per cycle), net and
gross IMEP, PMEP, COV of IMEP and the single-zone heat release (:mod:`analysis.pressure`).
The engine model (``--model``: an engine TOML, or a shaft-line TOML naming one) gives the
cylinder geometry; without it only the quantities that need none are given. ``--cycles``
prints the per-cycle table; ``--plot DIR`` writes ``pressure_<channel>.png`` (p–θ, log p–log V,
heat release) and ``--report OUT.html`` a report section (:class:`analysis.report.Report`)
atomically; ``--map`` reads a raw export through a channel map.

A crank-angle-domain export of an indicating system (a table with a crank-angle column and no
time column, :mod:`measure.readers.angle_table`; or a map with ``[source] angle_column``) is
analysed per cycle as exported (:mod:`analysis.pressure_cycles`): ``--firing-tdc-deg`` says
where its axis puts the firing TDC (default: from the pressure), ``--speed-rpm`` the speed
when it has no speed column.
"""

from __future__ import annotations

import logging
from pathlib import Path

HELP = ("indicator analysis of cylinder pressure: peak and angle, IMEP, PMEP, COV, pegging, "
        "TDC check, heat release")

log = logging.getLogger("crankbench")


def configure(parser) -> None:
    from crankbench.analysis.commands._args import integer, number

    parser.add_argument("record", metavar="REC", help="record with a pressure channel and a "
                        "pulse wheel/encoder (.h5 .nc .csv .mf4 .tdms ...)")
    parser.add_argument("--model", default=None, metavar="TOML",
                        help="engine model (bore, stroke, rod, compression ratio) or a shaft "
                             "line naming one; needed for IMEP, PMEP, pegging and heat release")
    parser.add_argument("--channel", default=None, help="pressure channel (default: all)")
    parser.add_argument("--cylinder", type=integer(low=1, high=64), default=None,
                        help="cylinder of --channel (default: from the channel)")
    parser.add_argument("--angle-channel", default=None, help="crank-angle pulses/encoder")
    parser.add_argument("--tdc-channel", default=None, help="TDC mark channel")
    parser.add_argument("--phase-channel", default=None, help="cam/phase mark (one per cycle)")
    parser.add_argument("--tdc-offset-deg", type=number(low=-720.0, high=720.0, unit="deg"),
                        default=None,
                        help="TDC of cylinder 1 after the TDC mark (or the wheel gap), deg")
    parser.add_argument("--tdc-correct", action="store_true",
                        help="apply the thermodynamic TDC correction")
    parser.add_argument("--peg", default="auto", choices=["auto", "bdc", "polytropic", "none"],
                        help="absolute level: BDC pressure, polytropic compression, none "
                             "(default auto)")
    parser.add_argument("--peg-pressure-bar", type=number(low=0.0, high=1000.0, strict_low=True,
                                                          unit="bar"), default=None,
                        help="absolute pressure at intake BDC, bar (selects --peg bdc)")
    parser.add_argument("--gamma", type=number(low=1.0, high=2.0, strict_low=True), default=1.32,
                        help="ratio of specific heats for the heat release (default 1.32)")
    parser.add_argument("--firing-tdc-deg", type=number(low=-720.0, high=720.0, unit="deg"),
                        default=None, help="angle-domain export: angle of its axis at which "
                        "the cylinder fires, deg (default: found from the pressure)")
    parser.add_argument("--speed-rpm", type=number(low=0.0, high=1e5, strict_low=True,
                                                   unit="rpm"), default=None,
                        help="angle-domain export without a speed column: engine speed, rpm "
                             "(only the speed/time columns use it)")
    parser.add_argument("--cycle", type=int, default=4, choices=[2, 4],
                        help="strokes, without --model (default 4)")
    parser.add_argument("--cycles", action="store_true", help="print the per-cycle table")
    parser.add_argument("--plot", default=None, metavar="DIR",
                        help="write pressure_<channel>.png into DIR")
    parser.add_argument("--report", default=None, metavar="OUT.html",
                        help="write an HTML report of the indicator analysis")
    parser.add_argument("--map", default=None, metavar="MAP.toml",
                        help="channel map of a raw export (see crankbench import)")
    parser.add_argument("--overwrite", action="store_true", help="replace existing outputs")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")


def _lines(s):
    def f(v, fmt="{:.4g}"):
        return "n/a (needs --model)" if v is None else fmt.format(v)

    pc, ac = s["peak_pressure_bar_per_cycle"], s["peak_angle_deg_per_cycle"]
    speed = ", speed not given" if s["speed_rpm"] is None else f" at {s['speed_rpm']:.1f} rpm"
    out = [f"channel {s['channel']} (cylinder {s['cylinder']}, {s['cycle']}-stroke): "
           f"{s['cycles']} cycles{speed}",
           f"  peak pressure      {s['peak_pressure_bar']:.3f} bar at "
           f"{s['peak_angle_deg']:.2f} deg after TDC (mean cycle)",
           f"  per cycle          {pc['mean']:.3f} ± {pc['std']:.3f} bar at {ac['mean']:.2f} ± "
           f"{ac['std']:.2f} deg",
           f"  IMEP net / gross   {f(s['imep_net_bar'])} / {f(s['imep_gross_bar'])} bar",
           f"  PMEP               {f(s['pmep_bar'])} bar",
           f"  COV of IMEP        {f(s['cov_imep_net_percent'], '{:.3g}')} %",
           f"  pegging            {s['peg']['method']}: {s['peg']['note']}",
           f"  TDC reference      {s['tdc']['reference']}",
           f"  firing TDC         {s['tdc']['phase']}"]
    chk = s["tdc"]["check"]
    if chk is not None:
        se = chk["standard_error_deg"]
        out.append(f"  TDC check          {chk['offset_deg']:+.2f} deg"
                   + ("" if se != se else f" ± {se:.2f}") + f" ({chk['method']}"
                   + ("" if chk["plausible"] else ", inconclusive") + "); applied "
                   f"{s['tdc']['applied_correction_deg']:+.2f} deg")
    hr = s["heat_release"]
    if hr is not None:
        out.append(f"  heat release       {hr['total_j']:.4g} J (gamma {hr['gamma']:g}); MFB10/"
                   f"50/90 {hr['mfb10_deg']:.1f} / {hr['mfb50_deg']:.1f} / "
                   f"{hr['mfb90_deg']:.1f} deg")
    for w in s["warnings"]:
        out.append(f"  warning: {w}")
    return out


def run(args) -> int:
    from crankbench.analysis._output import print_json, print_table
    from crankbench.analysis.pressure import indicator_analysis, pressure_channels
    from crankbench.measure import io

    if args.plot:
        out_dir = Path(args.plot)
        if out_dir.exists() and not out_dir.is_dir():
            from crankbench.predict.errors import ConfigError

            raise ConfigError(f"--plot {out_dir}: exists and is not a directory")
    record = _read(io, args)
    angle_domain = record.attrs.get("domain") == "crank_angle"
    if angle_domain:
        from crankbench.analysis.pressure_cycles import angle_pressure_channels as pressure_channels
    channels = [args.channel] if args.channel else pressure_channels(record)
    if not channels:
        from crankbench.predict.errors import AnalysisError

        raise AnalysisError(f"{args.record}: no cylinder-pressure channel (quantity "
                            "'pressure'); channels: " + ", ".join(map(str, record.data_vars)))
    options = dict(cylinder=args.cylinder, angle_channel=args.angle_channel,
                   tdc_channel=args.tdc_channel, phase_channel=args.phase_channel,
                   tdc_offset_deg=args.tdc_offset_deg, tdc_correction=args.tdc_correct,
                   peg="bdc" if args.peg_pressure_bar is not None and args.peg == "auto"
                   else args.peg,
                   peg_pressure=None if args.peg_pressure_bar is None
                   else args.peg_pressure_bar * 1e5,
                   gamma=args.gamma, cycle=args.cycle)
    from crankbench.analysis.commands._files import (check_outputs, map_inputs, model_inputs,
                                                     record_inputs)
    from crankbench.measure._atomic import check_overwrite

    outputs = [(Path(args.report), f"--report {args.report}")] if args.report else []
    if args.plot:
        outputs += [(Path(args.plot) / f"pressure_{c}.png", f"--plot {args.plot} "
                     f"(pressure_{c}.png)") for c in channels]
    check_outputs(outputs, record_inputs(args.record) + map_inputs(args)
                  + (model_inputs(args.model) if args.model else []))
    for path, _ in outputs:
        check_overwrite(path, args.overwrite, option="--overwrite")
    if angle_domain:
        from crankbench.analysis.pressure_cycles import indicator_analysis_cycles

        for key in ("angle_channel", "tdc_channel", "phase_channel", "tdc_offset_deg"):
            if options.pop(key) is not None:
                log.warning("--%s does not apply to a crank-angle-domain export (its axis is "
                            "referenced to TDC; use --firing-tdc-deg)", key.replace("_", "-"))
        options["cycle"] = None if args.model else args.cycle
        results = {c: indicator_analysis_cycles(record, args.model, channel=c,
                                                firing_tdc_deg=args.firing_tdc_deg,
                                                speed_rpm=args.speed_rpm, **options)
                   for c in channels}
    else:
        results = {c: indicator_analysis(record, args.model, channel=c, **options)
                   for c in channels}
    if args.json:
        out = {"record": str(args.record), "model": args.model,
               "channels": {c: r.summary() for c, r in results.items()}}
        if args.cycles:
            for c, r in results.items():
                out["channels"][c]["per_cycle"] = r.to_frame().to_dict(orient="list")
        print_json(out)
    else:
        for c, r in results.items():
            print("\n".join(_lines(r.summary())))
            if args.cycles:
                print_table(r.to_frame(), title=f"cycles of {c}")
            print()
    if args.plot:
        _plots(results, Path(args.plot), args.overwrite)
    if args.report:
        from crankbench.analysis.excitation_compare import add_indicator_section
        from crankbench.analysis.report import Report

        rep = Report(f"Cylinder pressure - {record.attrs.get('test_id', args.record)}",
                     subtitle=f"record {args.record} · model {args.model or 'none'}")
        rep.add_metadata({"record": str(args.record), "engine model": str(args.model),
                          "engine": record.attrs.get("engine_id", "—"),
                          "test": record.attrs.get("test_id", "—")})
        add_indicator_section(rep, results, section="Cylinder pressure")
        log.info("wrote %s", rep.save(args.report, overwrite=args.overwrite,
                                      option="--overwrite"))
    return 0


def _read(io, args):
    from crankbench.measure.readers.angle_table import is_angle_table, read_angle_table

    if args.map is None:
        if is_angle_table(args.record):
            return read_angle_table(args.record)
        return io.read(args.record)
    from crankbench.measure.channelmap import load_map

    cmap = load_map(args.map)
    if "angle_column" in cmap.source or is_angle_table(args.record):
        return read_angle_table(args.record, map=cmap)
    import inspect

    if "map" not in inspect.signature(io.read).parameters:
        from crankbench.predict.errors import ConfigError

        raise ConfigError("--map: this build reads no channel maps")
    return io.read(args.record, map=args.map)


def _plots(results, out_dir, overwrite):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from crankbench.measure._atomic import atomic_path

    out_dir.mkdir(parents=True, exist_ok=True)
    for c, r in results.items():
        geo = r.volume is not None
        fig, axes = plt.subplots(1, 3 if geo else 1, figsize=(15 if geo else 7, 4),
                                 squeeze=False)
        r.plot(ax=axes[0, 0])
        if geo:
            r.plot_log_pv(ax=axes[0, 1])
            r.plot_heat_release(ax=axes[0, 2])
        fig.tight_layout()
        path = out_dir / f"pressure_{c}.png"
        with atomic_path(path, overwrite=overwrite, option="--overwrite") as tmp:
            fig.savefig(tmp, format="png", dpi=100)
        plt.close(fig)
        log.info("wrote %s", path)
