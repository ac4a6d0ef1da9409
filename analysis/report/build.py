"""Assemble the test report from a :class:`analysis.pipeline.PipelineResult`.

Sections: verdict; test metadata; provenance (file hashes, model, version, parameters);
analysis settings (window, resolution, amplitude convention, tacho pulses/rev, sweep rate and
the estimated peak loss); order map and Campbell diagram with the predicted criticals overlaid;
order tracks with the predicted resonance curves; mode shapes; the comparison tables; the
limit checks.
"""

from __future__ import annotations

import logging

import numpy as np

from .report import Report

__all__ = ["build_report"]

log = logging.getLogger("crankbench")


def _order_map_figure(result):
    import matplotlib.pyplot as plt

    from ..orders import order_map
    from ..plots import plot_order_map

    rec = result.record
    var = rec[result.channel]
    fs = float(var.attrs["sample_rate"])
    from ..speedref import speed_reference

    rpm = speed_reference(rec, result.channel, speed_channel=result.speed_channel)
    x = np.nan_to_num(np.asarray(var.values, float))
    top = float(max(result.predicted["order"].max() if len(result.predicted) else 6.0, 6.0))
    m = order_map(x, fs=fs, speed_rpm=np.nan_to_num(rpm, nan=float(np.nanmedian(rpm))),
                  revolutions=8, samples_per_rev=64, max_order=min(16.0, top + 1.0),
                  speed_bins_rpm=120)
    fig, ax = plt.subplots(figsize=(7.5, 5.0))
    plot_order_map(m, ax=ax)
    p = result.predicted
    sig = p[p.get("significant", True)] if "significant" in p else p
    ax.plot(p["order"], p["speed_rpm"], "o", mfc="none", mec="w", ms=6, label="predicted critical")
    if len(sig):
        ax.plot(sig["order"], sig["speed_rpm"], "o", mfc="none", mec="r", ms=8, mew=1.5,
                label="predicted, significant")
    mt = result.comparison.matched
    if len(mt):
        ax.plot(mt["order"], mt["speed_rpm_measured"], "x", color="c", ms=7, mew=1.5,
                label="measured resonance")
    ax.legend(fontsize=7, loc="upper right")
    ax.set_title(f"order map of {result.channel}", fontsize=9)
    return fig


def _campbell_figure(result):
    import matplotlib.pyplot as plt

    from ..orders import campbell_map
    from ..plots import plot_campbell
    from ..speedref import speed_reference

    rec = result.record
    var = rec[result.channel]
    fs = float(var.attrs["sample_rate"])
    rpm = speed_reference(rec, result.channel, speed_channel=result.speed_channel)
    x = np.nan_to_num(np.asarray(var.values, float))
    nat = result.comparison.natural_frequencies
    f_top = float(max(nat["frequency_hz_predicted"].max() * 1.5 if len(nat) else 80.0, 40.0))
    nperseg = int(2 ** np.ceil(np.log2(fs * 1.0)))  # ≈ 1 Hz resolution
    c = campbell_map(x, fs=fs, speed_rpm=np.nan_to_num(rpm, nan=float(np.nanmedian(rpm))),
                     nperseg=nperseg, max_frequency=min(f_top, fs / 2.5), speed_bins_rpm=120,
                     orders=sorted(set(float(o) for o in result.track["order"].values)))
    fig, ax = plt.subplots(figsize=(7.5, 5.0))
    plot_campbell(c, ax=ax, critical_frequencies_hz=[f for f in nat["frequency_hz_predicted"]
                                                     if f < f_top])
    mt = result.comparison.matched
    if len(mt):
        ax.plot(mt["frequency_hz_measured"] * 1.0, mt["speed_rpm_measured"], "x", color="c",
                ms=7, mew=1.5, label="measured crossings")
        ax.legend(fontsize=7, loc="lower right")
    ax.set_title("Campbell diagram (lines: predicted natural frequencies)", fontsize=9)
    return fig


def _tracks_figure(result):
    """Measured order tracks with the predicted resonance curves (dashed)."""
    import matplotlib.pyplot as plt

    track = result.track
    orders = [float(o) for o in track["order"].values]
    n = len(orders)
    cols = 2 if n > 1 else 1
    rows = int(np.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(8.0, 2.4 * rows), squeeze=False,
                             layout="constrained")
    resp = result.response
    scale = 1.0
    units = result.units
    if units == "rad":
        scale, units = np.rad2deg(1.0) * 1e3, "mdeg"
    for k, q in enumerate(orders):
        ax = axes[k // cols][k % cols]
        a = track["amplitude"].sel(order=q).values
        step = max(1, a.size // 1500)  # plotting more points than pixels only costs time
        ax.plot(track["rpm"].values[::step], a[::step] * scale, lw=0.9, label="measured")
        if q in resp["order"].values:
            p = resp.sel(order=q)
            ax.plot(p["rpm"].values, p.values * scale, "--", lw=1.1, label="predicted")
        for r in result.resonances:
            if r.order == q:
                ax.axvline(r.speed_rpm, color="c", lw=0.7, ls=":")
        ax.set_title(f"order {q:g}", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.set_ylabel(units, fontsize=7)
        if k == 0:
            ax.legend(fontsize=7)
    for k in range(n, rows * cols):
        axes[k // cols][k % cols].axis("off")
    for ax in axes[-1]:
        ax.set_xlabel("speed (rpm)", fontsize=7)
    return fig


def build_report(result, *, title=None, parameters=None, record_path=None, model_path=None,
                 figures=True) -> Report:
    """The test report of one pipeline run.

    Parameters
    ----------
    result : PipelineResult
    title : str, optional
    parameters : dict, optional
        Command parameters for the provenance table.
    record_path, model_path : path-like, optional
        Files to hash (default: the result's source and model when they are files).
    figures : bool
        Include figures (order map, Campbell, tracks, mode shapes, comparison, limits).

    Returns
    -------
    Report

    Examples
    --------
    >>> from crankbench.analysis.pipeline import analyse                    # doctest: +SKIP
    >>> rep = build_report(analyse("run.h5", "shaftline.toml"))  # doctest: +SKIP
    >>> rep.save("report.html")                                  # doctest: +SKIP
    """
    from pathlib import Path

    rec = result.record
    title = title or f"Torsional vibration test report — {rec.attrs.get('test_id', result.source)}"
    rep = Report(title, subtitle=f"{rec.attrs.get('engine_id', '')} · record {result.source} · "
                                 f"model {Path(result.model_path).name}")
    rep.add_summary("measurement analysed", None,
                    f"{len(result.resonances)} resonances found in {result.channel} at "
                    f"{result.node}; {len(result.comparison.matched)} matched to predicted "
                    "criticals")
    meta = {"engine": rec.attrs.get("engine_id", "—"), "test": rec.attrs.get("test_id", "—"),
            "start time": rec.attrs.get("start_time", "—"), "record": result.source,
            "channel": f"{result.channel} ({result.quantity}, {result.units}) at {result.node}",
            "speed range (rpm)": f"{result.speed_range_rpm[0]:.1f} – "
                                 f"{result.speed_range_rpm[1]:.1f}",
            "synthetic record": "yes" if rec.attrs.get("synthetic") else "no"}
    rep.add_metadata(meta)
    files = []
    rp = Path(record_path or result.source)
    if rp.is_file():
        files.append(rp)
    mp = Path(model_path or result.model_path)
    params = dict(parameters or {})
    if result.record_sha256:
        params.setdefault("record sha256 (from the reader)", result.record_sha256)
    rep.add_provenance(files=files, model=mp if mp.is_file() else None, parameters=params)
    settings = {k: v for k, v in result.settings.items() if k != "resonance finder"}
    settings["resonance finder"] = ", ".join(f"{k}={v}" for k, v in
                                             result.settings.get("resonance finder", {}).items())
    settings["timings (s)"] = ", ".join(f"{k} {v:.2f}" for k, v in result.timings.items())
    rep.add_settings(settings)

    if figures:
        for maker, name, caption in (
                (_order_map_figure, "Order map",
                 "Computed order tracking (8-revolution blocks), dB re max. Circles: predicted "
                 "critical speeds (red: significant); crosses: measured resonances."),
                (_campbell_figure, "Campbell diagram",
                 "Short-time spectra against speed; dashed rays: tracked orders; vertical "
                 "lines: predicted natural frequencies; crosses: measured crossings."),
                (_tracks_figure, "Order tracks against prediction",
                 "Measured order amplitude (solid) and the model's steady-state resonance "
                 "curve at the same node (dashed); dotted: identified critical speeds.")):
            try:
                rep.add_figure(maker(result), title=name, caption=caption,
                               section="Measurement and prediction")
            except Exception as exc:  # a figure must never sink the report
                log.warning("figure %r skipped: %s", name, exc)
                rep.add_text(f"Figure '{name}' could not be drawn: {exc}",
                             section="Measurement and prediction")
        try:
            modes = result.system.mode_shapes()
            rep.add_figure(modes.plot(), title="Mode shapes (model)",
                           caption=f"Relative mode shapes, {modes.method}; relative error bound "
                                   f"{modes.relative_error_bound:.1e}.",
                           section="Measurement and prediction")
        except Exception as exc:
            log.warning("mode-shape figure skipped: %s", exc)
    rep.add_resonances(result.resonances, section="Measured resonances",
                       figure=figures)
    rep.add_comparison(result.comparison, figure=figures)
    pred = result.predicted
    cols = [c for c in ("mode", "order", "speed_rpm", "speed_rpm_undamped", "frequency_hz",
                        "amplitude", "damping_ratio", "vector_sum", "major", "significant")
            if c in pred]
    rep.add_table(pred[cols], title="Predicted critical speeds in the measured range",
                  section="Measurement against prediction",
                  caption="speed_rpm: the model's resonance identified like the measurement "
                          "(SDOF fit of the predicted response at the measured node); "
                          "speed_rpm_undamped: 60 f_n / order of the undamped model.")
    if getattr(result, "vibrograph", None) is not None:
        from ..vibrograph_report import add_vibrograph

        add_vibrograph(rep, result.vibrograph, figures=figures)
    if result.limits:
        rep.add_limit_checks(result.limits, figures=figures)
    return rep
