"""``crankbench import SRC --map MAP.toml -o OUT.h5``: a test-bench file into a Record.

Reads any supported file — delimited text of any common dialect, ``.xlsx`` workbooks, and the
record formats — through an optional channel map (:mod:`measure.channelmap`: columns, units,
linear calibrations, sensor metadata, raw wheel and TDC signals decoded to pulse trains) and
writes the Record atomically (``.h5`` recommended). The Record keeps its provenance (the source
file's name and SHA-256, the map's text). Prints one row per channel and, for every decoded
pulse channel, what was found: edges per revolution, revolutions, mean speed, runt or lost
teeth. An existing output is not replaced without ``--overwrite``; the output may not be the
source or the map.
"""

from __future__ import annotations

HELP = "import a test-bench file (text, spreadsheet, any record format) through a channel map"


def configure(parser) -> None:
    parser.add_argument("source", metavar="SRC",
                        help="file to import (.csv .txt .tsv .dat .xlsx .h5 .mf4 .tdms ...)")
    parser.add_argument("--map", metavar="MAP.toml", default=None,
                        help="channel map: columns, units, calibration, pulse roles "
                             "(default: the file's own headers)")
    parser.add_argument("-o", "--output", required=True, metavar="OUT.h5",
                        help="record to write (.h5 recommended; any writable record format)")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing output")
    parser.add_argument("--allow-nonfinite", action="store_true",
                        help="keep empty/NaN samples (masked and listed) instead of refusing")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")


def pulse_summary(record) -> list[dict]:
    """One row per pulse channel: role, layout, edges, revolutions, edges/rev, mean speed.

    Revolutions come from the pitch count (:func:`measure.tacho.count_pitches`), so the mean
    speed (crankshaft, rpm, over the span of the edges) is exact; edges per revolution is the
    median count over the complete revolutions of the wheel.

    Examples
    --------
    >>> import numpy as np
    >>> from crankbench.measure.record import make_record
    >>> rec = make_record({"tdc": dict(data=np.arange(50) * 0.04, units="s",
    ...                                quantity="pulse_times", pulses_per_rev=1)})
    >>> row = pulse_summary(rec)[0]
    >>> row["edges"], round(row["mean_speed_rpm"], 6)
    (50, 1500.0)
    """
    import warnings

    import numpy as np

    from crankbench.measure.tacho import count_pitches
    from crankbench.measure.wheel import edges_per_rev
    from crankbench.predict.errors import CrankbenchError

    rows = []
    for name, var in record.data_vars.items():
        if var.attrs.get("quantity") != "pulse_times":
            continue
        edges = np.asarray(var.values, float)
        ppr = int(var.attrs.get("pulses_per_rev", 1))
        ratio = float(var.attrs.get("speed_ratio", 1.0))
        row = {"channel": str(name), "role": var.attrs.get("role", ""), "pulses_per_rev": ppr,
               "missing_teeth": int(var.attrs.get("missing_teeth", 0)), "edges": int(edges.size),
               "runt_teeth": ", ".join(map(str, var.attrs.get("runt_teeth", []))),
               "lost_teeth": ", ".join(map(str, var.attrs.get("lost_teeth", [])))}
        try:
            with warnings.catch_warnings():       # the decoding warned already
                warnings.simplefilter("ignore")
                pc = count_pitches(edges, pulses_per_rev=ppr,
                                   missing_teeth=var.attrs.get("missing_teeth", 0))
            wheel_turns = float(pc.pitch[-1] - pc.pitch[0]) / ppr
            span = float(pc.edge_times[-1] - pc.edge_times[0])
            row.update(revolutions=wheel_turns / ratio,          # crankshaft revolutions
                       edges_per_rev=edges_per_rev(pc.pitch, ppr) if ppr > 1 else 1.0,
                       mean_speed_rpm=60.0 * wheel_turns / ratio / span)
        except CrankbenchError as exc:
            row.update(revolutions=float("nan"), edges_per_rev=float("nan"),
                       mean_speed_rpm=float("nan"), note=str(exc))
        rows.append(row)
    return rows


def run(args) -> int:
    import warnings
    from pathlib import Path

    import pandas as pd

    from crankbench.analysis._output import print_json, print_table
    from crankbench.analysis.commands.info import summary
    from crankbench.measure import io
    from crankbench.measure._atomic import check_overwrite
    from crankbench.measure.provenance import STAT_ATTR, source_sha256
    from crankbench.predict.errors import ConfigError

    out = Path(args.output)
    inputs = [Path(args.source)] + ([Path(args.map)] if args.map else [])
    for p in inputs:
        if p.exists() and out.resolve() == p.resolve():
            raise ConfigError(f"-o {args.output}: is the input {p}; an import never writes over "
                              "its inputs")
    if out.suffix.lower() in (".xlsx", ".xlsm"):
        raise ConfigError(f"-o {args.output}: crankbench does not write spreadsheets; use .h5")
    check_overwrite(out, args.overwrite, option="--overwrite")   # before any work
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        record = io.read(args.source, map=args.map, allow_nonfinite=args.allow_nonfinite)
    notes = list(dict.fromkeys(str(w.message) for w in caught))
    import logging

    log = logging.getLogger("crankbench")
    for note in notes:
        log.warning("warning: %s", note)
    io.write(record, out, overwrite=args.overwrite)
    info = summary(record)
    info["attrs"].pop(STAT_ATTR, None)  # the source's provenance, hashed here (not at the read)
    info["attrs"]["sha256"] = source_sha256(record, missing="")
    pulses = pulse_summary(record)
    if args.json:
        print_json({"source": str(args.source), "map": args.map, "output": str(out),
                    "warnings": notes, **info, "pulses": pulses})
        return 0
    attrs = info["attrs"]
    print(f"source      {args.source}  (sha256 {attrs.get('raw_sha256', attrs.get('sha256'))})")
    if args.map:
        print(f"map         {args.map}  (sha256 {attrs.get('channel_map_sha256', '')})")
    print(f"output      {out}")
    print(f"duration    {info['duration_s']:.6g} s")
    print()
    frame = pd.DataFrame(info["channels"])
    cols = [c for c in ("name", "quantity", "units", "sample_rate", "n", "duration_s",
                        "location") if c in frame.columns]
    print_table(frame[cols].astype(object).where(frame[cols].notna(), ""), title="channels")
    if pulses:
        print()
        table = pd.DataFrame(pulses)
        cols = [c for c in ("channel", "role", "pulses_per_rev", "missing_teeth", "edges",
                            "revolutions", "edges_per_rev", "mean_speed_rpm", "runt_teeth",
                            "lost_teeth") if c in table.columns]
        print_table(table[cols], title="pulse channels (decoded edges)")
    return 0
