"""Assemble the test report from a :class:`analysis.pipeline.PipelineResult`.

Sections, each added by ``Report.add_*`` calls (other steps add theirs the same way): the
verdict (every check pass / fail / inconclusive with its rule and data); test metadata;
provenance (file hashes, model, version, parameters); analysis settings; order map and
torsional Campbell diagram (speed on x, frequency on y, order rays, natural frequencies,
measured crossings); order tracks with the predicted resonance curves; mode shapes along the
shaft line in model order; the one critical-speed table; the limit checks with their rules and
clauses.
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
    ax.set_xlabel("order")
    ax.set_ylabel("engine speed (rpm)")
    return fig


def _campbell_figure(result):
    """Torsional Campbell diagram: speed on x, frequency on y, the tracked orders' rays, the
    model's natural frequencies, the measured crossings, the measured spectrum underneath."""
    from ..orders import campbell_map
    from ..plots import plot_campbell
    from ..speedref import speed_reference

    rec = result.record
    var = rec[result.channel]
    fs = float(var.attrs["sample_rate"])
    rpm = speed_reference(rec, result.channel, speed_channel=result.speed_channel)
    x = np.nan_to_num(np.asarray(var.values, float))
    nat = result.comparison.natural_frequencies
    orders = sorted(set(float(o) for o in result.track["order"].values))
    lo, hi = result.speed_range_rpm
    f_top = float(max(max(orders) * hi / 60.0 * 1.05,
                      nat["frequency_hz_predicted"].max() * 1.1 if len(nat) else 0.0))
    nperseg = int(2 ** np.ceil(np.log2(fs * 1.0)))  # ≈ 1 Hz resolution
    c = campbell_map(x, fs=fs, speed_rpm=np.nan_to_num(rpm, nan=float(np.nanmedian(rpm))),
                     nperseg=nperseg, max_frequency=min(f_top, fs / 2.5), speed_bins_rpm=120,
                     orders=orders)
    c.name = f"Campbell diagram, {result.channel}"
    labels = {f"mode {int(r['mode'])}: {r.frequency_hz_predicted:.1f} Hz":
              float(r.frequency_hz_predicted) for _, r in nat.iterrows()}
    mt = result.comparison.matched
    crossings = None
    if len(mt):
        import pandas as pd

        crossings = pd.DataFrame({"speed_rpm": mt["speed_rpm_measured"],
                                  "frequency_hz": mt["frequency_hz_measured"]})
    return plot_campbell(c, critical_frequencies_hz=labels, speed_range_rpm=(0.0, hi * 1.02),
                         frequency_max_hz=f_top, crossings=crossings)


def _tracks_figure(result):
    """Measured order tracks with the predicted resonance curves (dashed)."""
    import matplotlib.pyplot as plt

    track = result.track
    orders = [float(o) for o in track["order"].values]
    n = len(orders)
    cols = 2 if n > 1 else 1
    rows = int(np.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(8.0, 2.1 * rows), squeeze=False,
                             layout="constrained")
    resp = result.response
    scale = 1.0
    units = result.units
    if units == "rad":
        scale, units = np.rad2deg(1.0) * 1e3, "mdeg"
    for k, q in enumerate(orders):
        ax = axes[k // cols][k % cols]
        a = track["amplitude"].sel(order=q).values
        # every sample: Report.add_figure decimates to the pixel grid keeping each peak (a
        # stride here could step over the resonance peak the figure is there to show)
        ax.plot(track["rpm"].values, a * scale, lw=0.9, label="measured")
        if q in resp["order"].values:
            p = resp.sel(order=q)
            ax.plot(p["rpm"].values, p.values * scale, "--", lw=1.1, label="predicted")
        for r in result.resonances:
            if r.order == q:
                ax.axvline(r.speed_rpm, color="c", lw=0.7, ls=":")
        ax.set_title(f"order {q:g}", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.set_ylabel(f"amplitude ({units})", fontsize=7)
        if k == 0:
            ax.legend(fontsize=7)
    for k in range(n, rows * cols):
        axes[k // cols][k % cols].axis("off")
    for ax in axes[-1]:
        ax.set_xlabel("engine speed (rpm)", fontsize=7)
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
    meta = {"engine": rec.attrs.get("engine_id", "—"), "test": rec.attrs.get("test_id", "—"),
            "start time": rec.attrs.get("start_time", "—"), "record": result.source,
            "channel": f"{result.channel} ({result.quantity}, {result.units}) at {result.node}",
            "speed range (rpm)": f"{result.speed_range_rpm[0]:.1f} – "
                                 f"{result.speed_range_rpm[1]:.1f}",
            "measured": f"{len(result.resonances)} resonances found; "
                        f"{len(result.comparison.matched)} matched to predicted criticals",
            "synthetic record": "yes" if rec.attrs.get("synthetic") else "no"}
    read = "; ".join(str(rec.attrs[k]) for k in ("read_notes", "units_from_names")
                     if rec.attrs.get(k))
    if read:   # what reading the export changed or assumed: a signer must see it
        meta["as read"] = read
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
    settings = {k: _setting(v) for k, v in result.settings.items() if k != "resonance finder"}
    settings["resonance finder"] = ", ".join(f"{k}={_setting(v)}" for k, v in
                                             result.settings.get("resonance finder", {}).items())
    settings["timings (s)"] = ", ".join(f"{k} {v:.2f}" for k, v in result.timings.items())
    rep.add_settings(settings)

    sec = "Measurement and prediction"
    if figures:
        for maker, name, caption in (
                (_order_map_figure, "Order map",
                 "Computed order tracking (8-revolution blocks), dB re max. Circles: predicted "
                 "critical speeds (red: significant); crosses: measured resonances."),
                (_campbell_figure, "Campbell diagram",
                 "Engine speed against frequency. Blue rays: engine orders tracked (labelled "
                 "by order); dashed red lines: the model's natural frequencies; circles: "
                 "measured crossings (resonances); grey: the measured short-time spectrum."),
                (_tracks_figure, "Order tracks against prediction",
                 "Measured order amplitude (solid) and the model's steady-state resonance "
                 "curve at the same node (dashed); dotted: identified critical speeds.")):
            try:
                rep.add_figure(maker(result), title=name, caption=caption, section=sec)
            except Exception as exc:  # a figure must never sink the report
                log.warning("figure %r skipped: %s", name, exc)
                rep.add_text(f"Figure '{name}' could not be drawn: {exc}", section=sec)
        try:
            from ..plots import plot_mode_shapes

            modes = result.system.mode_shapes()
            rep.add_figure(plot_mode_shapes(result.system), title="Mode shapes (model)",
                           caption=f"Relative mode shapes along the shaft line in model order, "
                                   f"{modes.method}; relative error bound "
                                   f"{modes.relative_error_bound:.1e}. Nodes outside the "
                                   "undamped problem (a viscous damper's seismic ring) are not "
                                   "drawn.", section=sec)
        except Exception as exc:
            log.warning("mode-shape figure skipped: %s", exc)
    steady = getattr(result, "steady_orders", None)
    if steady is not None:
        # a constant-speed record: the steady-state orders, not a sweep and its resonances
        rep.add_steady_orders(steady, section="Steady-state orders")
    else:
        # the identified resonances are drawn on the order-track figure (in display units)
        rep.add_resonances(result.resonances, section="Measured resonances", figure=False)
    lo, hi = result.speed_range_rpm
    rep.add_comparison(result.comparison, figure=figures, amplitude_units=result.units,
                       verdict=result.verdicts[0])
    for v in result.verdicts[1 + len(result.limits):]:
        rep.add_verdict(v)
    if getattr(result, "vibrograph", None) is not None:
        from ..vibrograph_report import add_vibrograph

        add_vibrograph(rep, result.vibrograph, figures=figures)
    rep.add_limit_checks(result.limits, figures=figures)
    if getattr(result, "pressure", None) is not None:
        from crankbench.analysis.excitation_compare import add_pressure_section

        add_pressure_section(rep, result.pressure, result=result, figures=figures)
    return rep


def _setting(value):
    """A setting for the table: floats to 4 significant digits."""
    if isinstance(value, float):
        return f"{value:.4g}"
    return value
