"""``crankbench analyse RECORD --channel NAME --orders 0.5,1,1.5``: order analysis of a record.

Reads the record (``measure.read``), takes the shaft speed (and the encoder angle) from its speed
channel, pulse train, encoder angle or IAS channel (``analysis.speedref``), tracks the requested
orders (by default with settings chosen from the record, ``analysis.autotrack``; or COT or
Vold–Kalman) and prints, per order, the largest amplitude, the speed where it occurs and the mean
amplitude, then the settings chosen and why (sweep rate or 'steady', the channel's trend, the
phase reference, the largest uncertainty per order); a constant-speed record also gets its
steady-state order table (amplitude and phase ± 1 σ). ``--json`` prints the
same plus the parameters used and the tracks (at most ``--json-points`` points per order).
``--plot DIR`` writes ``order_map.png``, ``campbell.png`` and ``order_tracks.png`` atomically;
existing files are kept unless ``--overwrite``. ``--store FILE.duckdb`` also writes the order
amplitudes at reference speeds (and a steady run's order table) into a campaign store
(:mod:`analysis.campaign`), verdict 'inconclusive' since nothing is compared.

Records larger than 256 MB are opened lazily (``measure.open``) and tracked segment by segment
(``analysis.stream``) with bounded memory; the output has the same form.
"""

from __future__ import annotations

import logging

import numpy as np

HELP = "order analysis of a record channel (order tracks, order map, Campbell diagram)"

log = logging.getLogger("crankbench")

PLOTS = ("order_map.png", "campbell.png", "order_tracks.png")

#: record files larger than this (bytes) are opened lazily and order-tracked segment by segment
STREAM_BYTES = 256 * 1024 * 1024


def configure(parser) -> None:
    from crankbench.analysis.commands._args import add_list, integer, number, positive_order

    parser.add_argument("record", metavar="RECORD",
                        help="record file (any format measure.read knows)")
    parser.add_argument("--map", metavar="MAP.toml", default=None,
                        help="channel map: columns, units, calibration, raw pulse roles")
    parser.add_argument("--channel", default=None,
                        help="channel to analyse (default: the record's only sampled channel "
                             "that is not a speed source)")
    parser.add_argument("--allow-nonfinite", action="store_true",
                        help="keep empty/NaN samples (dropouts): the trackers mask them and "
                             "report the masked spans, instead of refusing the record")
    add_list(parser, "--orders", item=positive_order, metavar="Q", required=True,
             help="orders to track, e.g. 0.5,1,1.5")
    parser.add_argument("--method", choices=("auto", "cot", "vkf"), default="auto",
                        help="auto (default: settings chosen from the record, printed), computed "
                             "order tracking or Vold-Kalman filter")
    parser.add_argument("--amplitude", choices=("peak", "rms", "peak-to-peak"), default="peak",
                        help="amplitude convention (default peak)")
    parser.add_argument("--speed-channel", default=None,
                        help="speed source (rotational_speed channel or pulse train); "
                             "default: found in the record")
    parser.add_argument("--revolutions", type=integer(low=1, high=4096), default=None,
                        help="COT/map block length in revolutions, 1..4096 (order resolution "
                             "1/N); default: chosen from the sweep rate and the order spacing "
                             "(COT), 16 (map)")
    parser.add_argument("--samples-per-rev", type=integer(low=8, high=MAX_SAMPLES_PER_REV),
                        default=None,
                        help=f"angle samples per revolution, 8..{MAX_SAMPLES_PER_REV} (orders "
                             "up to N/4; default 64, more for orders above 16)")
    parser.add_argument("--bandwidth-hz", type=number(low=0.0, strict_low=True), default=None,
                        help="VKF -3 dB bandwidth, Hz")
    parser.add_argument("--bandwidth-orders", type=number(low=0.0, high=2.0, strict_low=True),
                        default=None, help="VKF bandwidth in orders, (0, 2] (follows the speed)")
    parser.add_argument("--filter-order", type=int, choices=(1, 2), default=2,
                        help="VKF filter order")
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.add_argument("--json-points", type=integer(low=1, high=10**7), default=500,
                        help="largest number of track points per order in the JSON output")
    parser.add_argument("--plot", metavar="DIR", default=None,
                        help="write order_map.png, campbell.png, order_tracks.png to DIR")
    parser.add_argument("--overwrite", action="store_true", help="replace existing plot files")
    parser.add_argument("--store", metavar="FILE.duckdb", default=None,
                        help="also write the order amplitudes (and a steady run's order table) "
                             "into this campaign store (created if missing; verdict "
                             "'inconclusive': nothing is compared)")


#: largest --samples-per-rev (the angle-domain signal grows with it)
MAX_SAMPLES_PER_REV = 2**14


def check_args(args) -> None:
    """Cross-checks of the arguments, naming the flags (before the record is read).

    Raises
    ------
    ConfigError
    """
    from crankbench.predict.errors import ConfigError

    top = max(args.orders)
    spr = args.samples_per_rev        # None: chosen for the orders (64, more above order 16)
    if spr is not None and (args.method != "vkf" or args.plot):
        if top > spr / 4:
            need = 1 << int(np.ceil(np.log2(4 * top)))
            raise ConfigError(f"--orders {top:g} exceeds --samples-per-rev/4 = "
                              f"{spr / 4:g} (the anti-alias pass band); use "
                              f"--samples-per-rev {max(need, 8)} or more")
    if args.method == "cot":
        used = [f for f, v in (("--bandwidth-hz", args.bandwidth_hz),
                               ("--bandwidth-orders", args.bandwidth_orders)) if v is not None]
        if used:
            raise ConfigError(f"{' and '.join(used)} appl{'y' if len(used) > 1 else 'ies'} to "
                              "--method vkf only")
    elif args.bandwidth_hz is not None and args.bandwidth_orders is not None:
        raise ConfigError("give --bandwidth-hz or --bandwidth-orders, not both")
    if len(args.orders) > 64:
        raise ConfigError(f"--orders lists {len(args.orders)} orders; at most 64 are tracked "
                          "at once")


def check_size(args, record, channel) -> None:
    """Refuse a request whose order tracks cannot fit in memory (naming the flags)."""
    from crankbench.predict._memory import check_allocation
    from crankbench.predict.errors import ConfigError

    n = float(record[channel].shape[0])
    k = len(args.orders)
    if args.method in ("vkf", "auto"):
        # the joint Vold-Kalman solve holds a banded system of about 2·filter order + 1
        # bands per order pair: ~ n (2 k)^2 (2 p + 1) float64
        nbytes = 8.0 * n * (2 * k) ** 2 * (2 * args.filter_order + 1) + 48.0 * n * k
        what = f"--method vkf on {n:.3g} samples with {k} orders"
        hint = "track fewer --orders at once, or use --method cot"
    else:
        fs = float(record[channel].attrs.get("sample_rate") or 1.0)
        spr = args.samples_per_rev or max(64, 1 << int(np.ceil(np.log2(4 * max(args.orders)))))
        # the angle-domain signal: at most as many samples per revolution as asked, over the
        # record's revolutions; bounded above by the record length times the upsampling
        revs_bound = n / fs * 2e5 / 60.0              # never above 200 000 rpm
        angle = min(revs_bound * spr, max(n, 1.0) * spr)
        nbytes = 8.0 * angle * 4 + 48.0 * n
        what = f"--samples-per-rev {spr} on {n:.3g} samples"
        hint = "lower --samples-per-rev"
    check_allocation(nbytes, what=what, hint=hint, error=ConfigError)


def _settings_text(tracks, rpm) -> list:
    """What was chosen and why: the tracker's settings, the sweep rate (or 'steady'), the
    channel's trend and the phase reference, one line each."""
    import numpy as np

    from crankbench.analysis.autotrack import steady_speed, sweep_rate

    lines = []
    if rpm is not None:
        fs = float(rpm.attrs.get("sample_rate", 0) or 0) or (
            1.0 / float(np.median(np.diff(rpm[rpm.dims[0]].values))) if rpm.size > 1 else 1.0)
        lines.append("speed: steady (no sweep)" if steady_speed(rpm.values, fs) else
                     f"sweep rate: {sweep_rate(rpm.values, fs):.4g} rpm/s (median)")
    for key in ("auto_settings", "trend", "phase_reference"):
        if tracks.attrs.get(key):
            lines.append(f"{key.replace('_', ' ')}: {tracks.attrs[key]}")
    if "amplitude_uncertainty" in tracks:
        vals = tracks["amplitude_uncertainty"].values
        unc = np.array([np.nanmax(v) if np.isfinite(v).any() else np.nan for v in vals])
        lines.append("largest 1-sigma uncertainty (noise and smearing): " + ", ".join(
            f"order {o:g}: {u:.3g}" for o, u in zip(tracks["order"].values, unc)))
    return lines


def _steady_table(channel, rpm, args):
    """The steady-state order table of a constant-speed record, else None."""
    import numpy as np

    from crankbench.analysis.autotrack import steady_speed
    from crankbench.analysis.steady import steady_orders
    from crankbench.predict.errors import AnalysisError

    fs = float(channel.attrs["sample_rate"])
    if not steady_speed(np.asarray(rpm.values, float), fs):
        return None
    try:
        return steady_orders(channel, speed_rpm=rpm, orders=args.orders,
                             amplitude=args.amplitude)
    except AnalysisError as exc:
        log.info("no steady-state table: %s", exc)
        return None


def _map_spr(args) -> int:
    """Angle samples per revolution of the order map: as given, else 64 or the power of two
    that keeps every requested order below a quarter of it (as the trackers choose)."""
    if args.samples_per_rev:
        return int(args.samples_per_rev)
    return max(64, 1 << int(np.ceil(np.log2(4 * max(args.orders)))))


def _summary(tracks):
    import numpy as np
    import pandas as pd

    rows = []
    for o in tracks["order"].values:
        amp = tracks["amplitude"].sel(order=o).values
        if not np.isfinite(amp).any():       # (results NaN where the filter is unsettled)
            rows.append({"order": float(o), "max_amplitude": float("nan"),
                         "speed_rpm_at_max": float("nan"), "time_s_at_max": float("nan"),
                         "mean_amplitude": float("nan")})
            continue
        i = int(np.nanargmax(amp))
        rows.append({"order": float(o), "max_amplitude": float(amp[i]),
                     "speed_rpm_at_max": float(tracks["rpm"].values[i]),
                     "time_s_at_max": float(tracks["time"].values[i]),
                     "mean_amplitude": float(np.nanmean(amp))})
    return pd.DataFrame(rows)


def run(args) -> int:
    from pathlib import Path

    from crankbench import measure
    from crankbench.analysis._output import print_json, print_table
    from crankbench.analysis.orders import campbell_map, order_map, order_track
    from crankbench.analysis.speedref import speed_reference
    from crankbench.predict._validate import suggest
    from crankbench.predict.errors import ConfigError, RecordError

    check_args(args)
    if args.store:
        from crankbench.analysis.commands._files import check_outputs, map_inputs, record_inputs

        check_outputs([(Path(args.store), f"--store {args.store}")],
                      record_inputs(args.record) + map_inputs(args))
    targets = []
    if args.plot:
        from crankbench.analysis.commands._files import check_outputs, map_inputs, record_inputs
        from crankbench.measure._atomic import check_overwrite

        out_dir = Path(args.plot)
        if out_dir.exists() and not out_dir.is_dir():
            raise ConfigError(f"--plot {out_dir}: exists and is not a directory")
        targets = [out_dir / name for name in PLOTS]
        check_outputs([(p, f"--plot {out_dir} ({p.name})") for p in targets],
                      record_inputs(args.record) + map_inputs(args))
        for path in targets:           # refuse before any work, never half a set of plots
            check_overwrite(path, args.overwrite, option="--overwrite")
    import os

    size = os.path.getsize(args.record)
    streaming = size > STREAM_BYTES
    if streaming and args.allow_nonfinite:
        raise RecordError(
            f"--allow-nonfinite: {args.record} is {size / 1e6:.4g} MB, above the "
            f"{STREAM_BYTES / 1e6:.4g} MB read whole, and the streamed trackers do not mask "
            "NaN/inf runs (they refuse them); order-track the spans around the dropouts in "
            "Python (measure.open(path, allow_nonfinite=True), .isel(time=slice(a, b)), "
            "analysis.order_track), or trim the file")
    if streaming:
        log.info("%s: %.3g MB > %.3g MB, streaming it segment by segment (measure.open + "
                 "analysis.stream)", args.record, os.path.getsize(args.record) / 1e6,
                 STREAM_BYTES / 1e6)
        record = measure.open(args.record, map=args.map)
    else:
        record = measure.read(args.record, map=args.map, allow_nonfinite=args.allow_nonfinite)
    names = [str(n) for n in record.data_vars]
    if args.channel is None:
        args.channel = _only_signal(record, names, args.record)
    if args.channel not in names:
        raise RecordError(f"{args.record}: --channel {args.channel!r}: no such channel"
                          f"{suggest(args.channel, names)}; channels: {', '.join(names)}")
    channel = record[args.channel]
    if channel.attrs.get("sample_rate") is None:
        raise RecordError(f"{args.record}: channel {args.channel!r} is not a sampled channel "
                          "(no sample_rate); choose a signal channel")
    if args.speed_channel is not None and args.speed_channel not in names:
        raise RecordError(f"{args.record}: --speed-channel {args.speed_channel!r}: no such "
                          f"channel{suggest(args.speed_channel, names)}; channels: "
                          f"{', '.join(names)}")
    check_size(args, record, args.channel)
    kwargs = dict(orders=args.orders, amplitude=args.amplitude, method=args.method,
                  samples_per_rev=args.samples_per_rev, revolutions=args.revolutions)
    if args.method in ("vkf", "auto"):
        kwargs.update(bandwidth_hz=args.bandwidth_hz, bandwidth_orders=args.bandwidth_orders,
                      filter_order=args.filter_order)
    if streaming:
        from crankbench.analysis.stream import order_track_stream

        rpm = None
        tracks = order_track_stream(record, args.channel, speed_channel=args.speed_channel,
                                    **kwargs)
    else:
        rpm = speed_reference(record, args.channel, speed_channel=args.speed_channel)
        channel = channel.load() if hasattr(channel, "load") else channel
        tracks = order_track(channel, speed_rpm=rpm, **kwargs)
    summary = _summary(tracks)
    units = tracks["amplitude"].attrs.get("units", "")
    steady = _steady_table(channel, rpm, args) if rpm is not None else None
    if args.json:
        step = max(1, int(np.ceil(tracks.sizes["time"] / max(1, args.json_points))))
        sub = tracks.isel(time=slice(None, None, step))
        print_json({
            "record": str(args.record), "channel": args.channel, "units": units,
            "amplitude_convention": args.amplitude,
            "parameters": {k: v for k, v in tracks.attrs.items()},
            "summary": summary,
            "settings": _settings_text(tracks, rpm),
            "steady_orders": steady,
            "tracks": {"time_s": sub["time"].values, "speed_rpm": sub["rpm"].values,
                       "orders": {f"{o:g}": {"amplitude": sub["amplitude"].sel(order=o).values,
                                             "phase_rad": sub["phase"].sel(order=o).values}
                                  for o in sub["order"].values},
                       "every_nth_point": step},
        })
    else:
        print_table(summary, title=f"{args.channel} [{units}], {args.amplitude} amplitude, "
                                   f"method {args.method} ({tracks.attrs.get('method', '')})")
        for line in _settings_text(tracks, rpm):
            print(line)
        if steady is not None:
            print_table(steady, title=f"{args.channel}: steady-state orders (constant speed, "
                                      f"±1 sigma), phases from "
                                      f"{steady.attrs.get('phase_reference', '')}")
    if args.store:
        from crankbench.analysis.campaign.documents import store_tracks

        settings = {k: getattr(args, k) for k in (
            "channel", "orders", "method", "amplitude", "speed_channel", "revolutions",
            "samples_per_rev", "bandwidth_hz", "bandwidth_orders", "filter_order", "map")}
        run_id = store_tracks(args.store, tracks, record_path=args.record, settings=settings,
                              steady_table=steady, attrs=dict(record.attrs))
        log.info("stored as run %s in %s", run_id, args.store)
    if targets:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from crankbench.measure._atomic import atomic_path
        from crankbench.analysis.plots import plot_campbell, plot_order_map, plot_order_tracks

        fs = float(channel.attrs["sample_rate"])
        if streaming:
            from crankbench.analysis.stream import order_map_stream

            omap = order_map_stream(record, args.channel, speed_channel=args.speed_channel,
                                    samples_per_rev=_map_spr(args),
                                    revolutions=args.revolutions or 16, amplitude=args.amplitude)
            # the Campbell map needs the channel in memory: low-passed and decimated, streamed
            from crankbench.analysis.stream import decimate_stream

            top = max(args.orders) * float(tracks["rpm"].max()) / 60.0 * 1.5
            channel, rpm = decimate_stream(record, args.channel, max_frequency=min(top, fs / 3),
                                           speed_channel=args.speed_channel)
            fs = float(channel.attrs["sample_rate"])
            log.info("Campbell map of the streamed record at %.6g Hz (decimated by %d)", fs,
                     channel.attrs["decimation"])
        else:
            omap = order_map(channel, speed_rpm=rpm, samples_per_rev=_map_spr(args),
                             revolutions=args.revolutions or 16, amplitude=args.amplitude)
        nperseg = int(2 ** np.clip(np.round(np.log2(fs)), 8, 16))
        top = max(args.orders) * float(np.max(rpm)) / 60.0 * 1.5
        camp = campbell_map(channel, speed_rpm=rpm, nperseg=min(nperseg, channel.shape[0]),
                            orders=args.orders, max_frequency=min(top, fs / 2),
                            amplitude=args.amplitude)
        figures = [plot_order_map(omap), plot_campbell(camp), plot_order_tracks(tracks)]
        for fig, path in zip(figures, targets):
            with atomic_path(path, overwrite=args.overwrite, option="--overwrite") as tmp:
                fig.savefig(tmp, format="png", dpi=110)
            plt.close(fig)
            log.info("wrote %s", path)
    return 0


def _only_signal(record, names, path) -> str:
    """The one sampled channel of a record that is not a speed source, or a clear error."""
    from crankbench.analysis.speedref import _is_pulses
    from crankbench.predict.errors import ConfigError

    speed_like = ("rotational_speed", "pulse_times")
    candidates = [n for n in names if record[n].attrs.get("sample_rate") is not None
                  and record[n].attrs.get("quantity") not in speed_like
                  and not _is_pulses(record[n])]
    if len(candidates) == 1:
        log.info("%s: analysing channel %r (the only signal channel)", path, candidates[0])
        return candidates[0]
    raise ConfigError(f"{path}: give --channel: the record has {len(candidates)} signal "
                      f"channels ({', '.join(candidates) or 'none'}); all channels: "
                      f"{', '.join(names)}")
