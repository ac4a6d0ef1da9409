"""``crankbench info FILE [--json]``: what a record holds.

Prints the record attrs (source, start time, engine/test ids, SHA-256 of the file) and one row
per channel: name, quantity, units (SI, as stored after ingest), sample rate (Hz), number of
samples, duration (s), time dim and sensor location/direction. Long records are opened lazily
(:func:`measure.io.open`), so ``info`` on a multi-gigabyte ``.h5`` reads only its header (plus
one pass for the checksum).
"""

from __future__ import annotations

HELP = "show a record's channels, quantities, units, sample rates, duration and start time"


def configure(parser) -> None:
    parser.add_argument("file", metavar="FILE",
                        help="record file (.h5 .hdf5 .nc .csv .mf4 .mdf .tdms .uff .unv .wav)")
    from crankbench.analysis.commands._args import add_list

    add_list(parser, "--channels", metavar="NAME", help="only these channels, e.g. acc,speed")
    parser.add_argument("--map", metavar="MAP.toml", default=None,
                        help="channel map for text/spreadsheet files or raw pulse channels")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")


def summary(record) -> dict:
    """Record summary as a JSON-able dict: ``attrs``, ``duration_s``, ``channels`` (list).

    Examples
    --------
    >>> import numpy as np
    >>> from crankbench.measure.record import make_record
    >>> rec = make_record({"acc": dict(data=np.zeros(200), sample_rate=100.0, units="g")},
    ...                   start_time="2026-01-01T00:00:00+00:00")
    >>> s = summary(rec)
    >>> print(s["duration_s"], s["channels"][0]["units"], s["channels"][0]["sample_rate"])
    2.0 m/s^2 100.0
    """
    import numpy as np

    from crankbench.measure.record import list_channels

    table = list_channels(record)
    extra = []
    for name in table["name"]:
        attrs = record[name].attrs
        extra.append({k: attrs[k] for k in ("location", "direction", "sensitivity",
                                             "sensitivity_units", "pulses_per_rev",
                                             "missing_teeth") if k in attrs})
    channels = []
    for row, more in zip(table.to_dict(orient="records"), extra):
        row.update(more)
        channels.append(row)
    durations = [c["duration_s"] for c in channels if np.isfinite(c["duration_s"])]
    return {"attrs": {str(k): v for k, v in record.attrs.items()},
            "duration_s": max(durations) if durations else float("nan"),
            "channels": channels}


def run(args) -> int:
    import pandas as pd

    from crankbench.analysis._output import print_json, print_table
    from crankbench.measure import io
    from crankbench.measure.provenance import STAT_ATTR, source_sha256

    record = io.open(args.file, channels=args.channels, map=args.map)
    info = summary(record)
    # provenance is written here: hash the file, checked to be the one just opened
    info["attrs"].pop(STAT_ATTR, None)
    info["attrs"]["sha256"] = source_sha256(record, missing="")
    if args.json:
        print_json({"file": str(args.file), **info})
        return 0
    attrs = info["attrs"]
    print(f"record      {args.file}")
    for key in ("start_time", "engine_id", "test_id"):
        if key in attrs:
            print(f"{key:<11} {attrs[key]}")
    print(f"duration    {info['duration_s']:.6g} s")
    print(f"channels    {len(info['channels'])}")
    print(f"sha256      {attrs.get('sha256', '')}")
    others = {k: v for k, v in attrs.items()
              if k not in ("start_time", "engine_id", "test_id", "sha256", "source")}
    for key, value in others.items():
        text = str(value)
        if "\n" in text.strip():  # the channel map's text: its size, not its lines
            text = f"({len(text.strip().splitlines())} lines of TOML; sha256 in " \
                   "channel_map_sha256)"
        print(f"{key:<11} {text}")
    print()
    frame = pd.DataFrame(info["channels"])
    columns = ["name", "quantity", "units", "sample_rate", "n", "duration_s", "dim"]
    columns += [c for c in ("location", "direction", "pulses_per_rev", "missing_teeth")
                if c in frame.columns]
    frame = frame[columns].rename(columns={"sample_rate": "sample_rate_Hz"})
    print_table(frame.astype(object).where(frame.notna(), ""))
    return 0
