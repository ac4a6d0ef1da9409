"""Report figures of the demo: rendering time with pixel-grid decimation against plain matplotlib.

The record is the demo's (``crankbench demo``: the 6L32 run-up of
``sample_data/scenes/marine_6l_runup.toml`` analysed against
``sample_data/shaftlines/marine_6l.toml``), synthesized and analysed once. Its report is then
built by :func:`analysis.report.build.build_report` in interleaved rounds after a warm-up, two
ways: as it ships (every long trace decimated to the output's pixel grid,
:func:`analysis.report.figures.decimate_figure`) and with the decimation switched off (the same
figures drawn by plain matplotlib, every sample). Process CPU time under the suite's BLAS
thread limit, both sides alike.

Rows:

* ``report figure: <title>`` — one per figure: the time of :meth:`Report.add_figure`
  (decimation + SVG rendering) per round, paired with the same figure undecimated in the same
  round. ``error`` counts the decimated lines whose drawn envelope is not the data's
  (per pixel column for time/speed traces: the kept samples' minimum and maximum equal the
  data's; for other lines the overall minimum and maximum), bound 0; ``extra`` holds the
  points and SVG bytes of both sides.
* ``report figures, total`` — the sum over figures, paired per round; error = decimated
  lines with a wrong envelope in all figures, bound 0. The demo's traces are short (an order
  track of 16 000 points), so its figure time is matplotlib's per-artist work (ticks, text,
  layout passes) and the ratio is about 1: decimation there buys size, not time.
* ``report figure: time trace, 210 000 samples`` — a 42 s trace at 5 kHz in one axes with a
  legend, decimated against every sample; a speed *target* of ratio <= 0.75 (0.54 measured
  idle; ``extra`` holds both SVG sizes).
* ``build_report, demo`` — the whole report (figures, tables, verdicts), paired with the
  same build undecimated.
* ``report figures, 2-process pool`` — rendering the figures of one report in a 2-process
  fork pool (pool start-up and pickling of the figures included) against rendering them one
  after another in this process, by *wall* time (what parallel rendering is for);
  informational: this is the measurement behind rendering in series (POSIX only; full run
  only, not ``--quick``).
"""

from __future__ import annotations

import time
from contextlib import contextmanager

import numpy as np

from . import Row, compare

SUITE = "report"


def _demo_result():
    import matplotlib

    matplotlib.use("Agg")
    from crankbench.analysis.commands.demo import MODEL, SCENE, sample_data_dir
    from crankbench.analysis.pipeline import LoadCase, analyse
    from crankbench.measure.synth import Scene, synthesize

    data = sample_data_dir()
    scene = Scene.from_toml(data / SCENE)
    run_ = synthesize(scene)
    return analyse(run_.record, data / MODEL, load=LoadCase.from_any(scene.load, scene.engine))


def _envelope_violations(xs, ys, keep_x, keep_y, dpi_columns, limits) -> int:
    """1 if the kept samples' envelope is not the data's, else 0 (independent of the
    decimator: pandas group-by per column for monotonic x, overall extremes otherwise)."""
    import pandas as pd

    finite = np.isfinite(ys)
    if not finite.any():
        return 0
    step = np.diff(xs)
    if ((step >= 0).all() or (step <= 0).all()) and limits[1] > limits[0]:
        def extremes(x, y):
            # the same grid as the decimator's, to the last rounding at a column's edge
            col = np.clip(np.floor((x - limits[0]) * (dpi_columns / (limits[1] - limits[0]))),
                          -1, dpi_columns)
            return pd.Series(y).groupby(col).agg(["min", "max"])

        a, b = extremes(xs, ys), extremes(keep_x, keep_y)
        return int(not a.reindex(b.index).equals(b) or len(a) != len(b))
    return int(np.nanmin(ys) != np.nanmin(keep_y) or np.nanmax(ys) != np.nanmax(keep_y))


@contextmanager
def _recording(log: dict, *, decimate: bool, check: dict | None = None):
    """Build reports with ``decimate`` on or off, adding each figure's add_figure CPU time to
    ``log[title]`` (and, with ``check``, counting in ``check[title]`` the decimated lines whose
    envelope is wrong)."""
    from crankbench.analysis.report import figures as figmod
    from crankbench.analysis.report import report as repmod

    original = repmod.Report.add_figure
    decimate_figure = figmod.decimate_figure
    current = {"title": ""}

    def checked_decimate(fig, *, dpi, **kw):
        lines = [(ln, np.asarray(ln.get_xdata(orig=False), float),
                  np.asarray(ln.get_ydata(orig=False), float)) for ax in fig.axes
                 for ln in ax.get_lines()]
        out = decimate_figure(fig, dpi=dpi, **kw)
        for ln, xs, ys in lines:
            kx = np.asarray(ln.get_xdata(orig=False), float)
            if kx.size < xs.size:
                ax = ln.axes
                scale = ax.xaxis.get_transform()
                from crankbench.analysis.report.figures import _width_bound

                cols = int(np.ceil(fig.get_figwidth() * dpi * _width_bound(ax)))
                title = current["title"]
                check[title] = check.get(title, 0) + _envelope_violations(
                    scale.transform(xs), ys, scale.transform(kx),
                    np.asarray(ln.get_ydata(orig=False), float), cols,
                    scale.transform(np.asarray(ax.get_xlim(), float)))
        return out

    def timed(self, fig, **kw):
        kw["decimate"] = decimate
        title = current["title"] = kw.get("title", "")
        c0 = time.process_time()
        original(self, fig, **kw)
        log[title] = log.get(title, 0.0) + time.process_time() - c0
        log.setdefault("_svg", {})[title] = len(self._sections[-1].items[-1].payload.get(
            "svg", ""))

    repmod.Report.add_figure = timed
    if check is not None:
        figmod.decimate_figure = checked_decimate
    try:
        yield
    finally:
        repmod.Report.add_figure = original
        figmod.decimate_figure = decimate_figure


def _trace_row(quick: bool) -> Row:
    """A long time trace (42 s at 5 kHz: 210 000 samples, a resonance burst, noise) in one
    axes with a legend, added to a report with and without decimation."""
    import matplotlib.pyplot as plt

    from crankbench.analysis.report import Report

    t = np.arange(0.0, 42.0, 1 / 5000.0)
    y = (np.sin(2 * np.pi * (3 + 0.5 * t) * t) * (1 + 3 * np.exp(-((t - 30) / 2) ** 2))
         + 0.1 * np.random.default_rng(0).standard_normal(t.size))
    sizes = {}

    def add(decimate):
        def run():
            fig, ax = plt.subplots(figsize=(7.5, 3.5), layout="constrained")
            ax.plot(t, y, lw=0.6, label="angular vibration")
            ax.legend()
            ax.set_xlabel("time (s)")
            rep = Report("bench")
            rep.add_figure(fig, title="trace", decimate=decimate)
            sizes[decimate] = len(rep._sections[0].items[0].payload["svg"])
        return run

    timing = compare({"dec": add(True), "full": add(False)}, rounds=3 if quick else 7,
                     min_time=0.0)
    return timing.row(SUITE, "report figure: time trace, 210 000 samples", "dec",
                      ("full", "the same figure, every sample"), "42 s at 5 kHz, SVG at 150 dpi",
                      timing.ratio("dec", "full")[0], "paired time ratio",
                      "target <= 0.75 (measured 0.54 on an idle 2-core machine)", bound=0.75,
                      target=True, extra={"svg_bytes": sizes[True],
                                          "svg_bytes_undecimated": sizes[False]})


def _pool_rows(result, quick: bool) -> list[Row]:
    import multiprocessing as mp
    import pickle

    from crankbench.analysis.report import report as repmod
    from crankbench.analysis.report.build import build_report
    from crankbench.analysis.report.figures import decimate_figure

    try:
        ctx = mp.get_context("fork")
    except ValueError:  # pragma: no cover - no fork (Windows)
        return []
    blobs = []
    original = repmod.Report.add_figure

    def grab(self, fig, **kw):
        decimate_figure(fig, dpi=kw.get("dpi", 150))
        blobs.append(pickle.dumps(fig))
        import matplotlib.pyplot as plt

        plt.close(fig)

    repmod.Report.add_figure = grab
    try:
        build_report(result)
    finally:
        repmod.Report.add_figure = original
    wall = {"pool": [], "serial": []}
    rounds = 2 if quick else 4

    def serial():
        return [_render(b) for b in blobs]

    def pooled():
        with ctx.Pool(2) as pool:
            return pool.map(_render, blobs, chunksize=1)

    serial()
    for r in range(rounds):
        for name, f in (("pool", pooled), ("serial", serial))[::1 if r % 2 else -1]:
            w0 = time.perf_counter()
            f()
            wall[name].append(time.perf_counter() - w0)
    ratios = np.asarray(wall["pool"]) / np.asarray(wall["serial"])
    return [Row(SUITE, "report figures, 2-process pool", f"{len(blobs)} figures of the demo",
                0.0, "-", "same SVGs", float(np.median(wall["pool"])),
                "the same figures rendered in series (wall)", float(np.median(ratios)),
                note="wall time, pool start-up and pickling included; the report renders "
                     "in series", ratio_lo=float(np.percentile(ratios, 25)),
                ratio_hi=float(np.percentile(ratios, 75)), paired=True, clock="wall",
                rounds=rounds, extra={"pickled_bytes": sum(map(len, blobs)),
                                      "serial_wall_s": float(np.median(wall["serial"]))})]


def _render(blob: bytes) -> int:
    import io
    import pickle

    import matplotlib
    import matplotlib.pyplot as plt

    fig = pickle.loads(blob)
    buf = io.StringIO()
    with matplotlib.rc_context({"svg.fonttype": "none", "svg.hashsalt": "crankbench"}):
        fig.savefig(buf, format="svg", bbox_inches="tight", dpi=150)
    plt.close(fig)
    return len(buf.getvalue())


def run(quick: bool) -> list[Row]:
    """Rows described in the module docstring (quick: 2 rounds and no pool row; the demo's
    synthesis and analysis, about 15 s, come first either way)."""
    from crankbench.analysis.report.build import build_report

    result = _demo_result()
    rounds = 2 if quick else 7
    per = {"dec": [], "full": []}
    checks: dict = {}
    # warm-up (fonts, caches; the decimated side checked against the data), then
    # interleaved rounds, the order alternating
    with _recording({}, decimate=True, check=checks):
        build_report(result)
    with _recording({}, decimate=False):
        build_report(result)
    totals = {"dec": np.empty(rounds), "full": np.empty(rounds)}
    for r in range(rounds):
        for name in (("dec", "full") if r % 2 == 0 else ("full", "dec")):
            log: dict = {}
            with _recording(log, decimate=name == "dec"):
                c0 = time.process_time()
                build_report(result)
                totals[name][r] = time.process_time() - c0
            per[name].append(log)
    titles = [t for t in per["dec"][0] if t != "_svg"]
    rows = []
    fig_sum = {k: np.array([sum(v for t, v in log.items() if t != "_svg") for log in per[k]])
               for k in per}
    violations = int(sum(checks.values()))
    for title in titles:
        dec = np.array([log[title] for log in per["dec"]])
        full = np.array([log[title] for log in per["full"]])
        ratio = dec / full
        rows.append(Row(SUITE, f"report figure: {title}", "demo record, SVG at 150 dpi",
                        float(checks.get(title, 0)), "lines whose drawn envelope differs from the data's",
                        "per pixel column min/max of the samples (pandas group-by)",
                        float(np.median(dec)), "same figure, every sample (plain matplotlib)",
                        float(np.median(ratio)), bound=0.0,
                        ratio_lo=float(np.percentile(ratio, 25)),
                        ratio_hi=float(np.percentile(ratio, 75)), paired=True, rounds=rounds,
                        extra={"svg_bytes": per["dec"][0]["_svg"][title],
                               "svg_bytes_undecimated": per["full"][0]["_svg"][title]}))
    ratio = fig_sum["dec"] / fig_sum["full"]
    rows.append(Row(SUITE, "report figures, total", f"{len(titles)} figures of the demo",
                    float(violations), "decimated lines with a wrong envelope",
                    "per pixel column min/max of the samples", float(np.median(
                        fig_sum["dec"])), "the same figures, every sample",
                    float(np.median(ratio)), bound=0.0,
                    note="the demo's traces are short (<= 16 000 samples): its figure time is "
                         "matplotlib's per-artist work (ticks, text, layout), not samples",
                    ratio_lo=float(np.percentile(ratio, 25)),
                    ratio_hi=float(np.percentile(ratio, 75)), paired=True, rounds=rounds,
                    extra={"svg_bytes": sum(per["dec"][0]["_svg"].values()),
                           "svg_bytes_undecimated": sum(per["full"][0]["_svg"].values())}))
    ratio = totals["dec"] / totals["full"]
    rows.append(Row(SUITE, "build_report, demo", "figures, tables, verdicts",
                    float(violations), "decimated lines with a wrong envelope",
                    "per pixel column min/max of the samples", float(np.median(totals["dec"])),
                    "the same report, every sample", float(np.median(ratio)), bound=0.0,
                    ratio_lo=float(np.percentile(ratio, 25)),
                    ratio_hi=float(np.percentile(ratio, 75)), paired=True, rounds=rounds,
                    extra={"figure_share": float(np.median(fig_sum["dec"] / totals["dec"]))}))
    rows.append(_trace_row(quick))
    if not quick:  # 20-40 s more: the measurement behind rendering in series
        rows.extend(_pool_rows(result, quick))
    return rows
