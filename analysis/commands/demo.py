"""``crankbench demo [-o DIR] [--overwrite] [--pdf]``: the whole chain on the sample data.

Synthesizes the 6L32 marine run-up of ``sample_data/scenes/marine_6l_runup.toml`` (record and
ground truth written to ``DIR/marine_6l_runup.h5``), analyses its free-end torsiograph
against the shaft-line model ``sample_data/shaftlines/marine_6l.toml``, compares, checks the
limits, and writes ``DIR/report.html`` (and ``report.pdf`` with ``--pdf``). Prints where the
report is. Runs in well under a minute.
"""

from __future__ import annotations

HELP = "run the whole chain on the sample data (synthesize, analyse, compare, report)"

SCENE = "scenes/marine_6l_runup.toml"
MODEL = "shaftlines/marine_6l.toml"


def sample_data_dir():
    """The ``sample_data`` folder: inside the installed package (wheel: models and scenes), or
    the repository's top-level folder (source checkout, editable install)."""
    from pathlib import Path

    import crankbench

    candidates = [Path(crankbench.__file__).resolve().parent / "sample_data",
                  Path(__file__).resolve().parents[2] / "sample_data"]
    for here in candidates:
        if (here / SCENE).is_file():
            return here
    from crankbench.predict.errors import ConfigError

    raise ConfigError(f"the demo's scene {SCENE} is in none of {', '.join(map(str, candidates))}; "
                      "reinstall crankbench (pip install -e . from a clone)")


def configure(parser) -> None:
    parser.add_argument("-o", "--output", default="crankbench-demo", metavar="DIR",
                        help="output folder (default ./crankbench-demo)")
    parser.add_argument("--overwrite", action="store_true",
                        help="replace the record and report from an earlier demo")
    parser.add_argument("--pdf", action="store_true", help="also write report.pdf")
    parser.add_argument("--json", action="store_true", help="print paths and summary as JSON")


def run(args) -> int:
    import logging
    import time
    from pathlib import Path

    from crankbench.analysis._output import print_json
    from crankbench.analysis.commands.report import write_outputs
    from crankbench.analysis.commands._pipeline_cli import progress_bar
    from crankbench.analysis.pipeline import LoadCase, analyse
    from crankbench.measure._atomic import check_overwrite
    from crankbench.measure.io import write
    from crankbench.measure.synth import Scene, synthesize

    log = logging.getLogger("crankbench")
    t0 = time.perf_counter()
    data = sample_data_dir()
    out = Path(args.output)
    record_path = out / "marine_6l_runup.h5"
    report_path = out / "report.html"
    if out.exists() and not out.is_dir():
        from crankbench.predict.errors import ConfigError

        raise ConfigError(f"-o {out}: exists and is not a folder")
    outputs = [record_path, report_path] + ([out / "report.pdf"] if args.pdf else [])
    from crankbench.analysis.commands._files import check_outputs, model_inputs

    check_outputs([(p, f"-o {out} ({p.name})") for p in outputs],
                  model_inputs(data / SCENE, "the demo scene") + model_inputs(data / MODEL))
    for p in outputs:
        check_overwrite(p, args.overwrite, option="--overwrite")
    quiet = args.json or log.getEffectiveLevel() > logging.INFO
    from crankbench.analysis.pipeline import STEPS

    # synthesize and write the record, then the pipeline's own steps
    bar, progress = progress_bar(total_steps=2 + len(STEPS), desc="demo", disable=quiet)
    try:
        progress("synthesize")
        scene = Scene.from_toml(data / SCENE)
        run_ = synthesize(scene)
        progress("write record")
        write(run_.record, record_path, truth=run_.truth, overwrite=args.overwrite)
        load = LoadCase.from_any(scene.load, scene.engine)
        record = run_.record.assign_attrs(source=record_path.name)
        from crankbench.analysis.report import file_sha256

        record = record.assign_attrs(sha256=file_sha256(record_path))
        result = analyse(record, data / MODEL, load=load, progress=progress)
    finally:
        bar.close()
    params = {"scene": str(data / SCENE), "load": f"{load.law}, imep {load.imep} Pa",
              "synthesis time (s)": round(run_.elapsed_s, 2)}
    paths = write_outputs(result, report_path, pdf=args.pdf, overwrite=args.overwrite,
                          title="crankbench demo — 6L32 marine diesel run-up",
                          parameters=params, record_path=record_path, model_path=data / MODEL)
    elapsed = time.perf_counter() - t0
    summary = result.summary()
    if args.json:
        print_json({"record": str(record_path), "written": [str(p) for p in paths],
                    "elapsed_s": elapsed, "summary": summary})
        return 0
    m = result.comparison.matched
    sig = m[m["significant"]] if len(m) else m
    print(f"synthesized  {record_path}  ({scene.profile.duration:g} s run-up "
          f"{result.speed_range_rpm[0]:.0f}–{result.speed_range_rpm[1]:.0f} rpm)")
    print(f"analysed     {result.channel} at {result.node}: {len(result.resonances)} resonances, "
          f"{len(m)} matched to the model's criticals"
          + (f"; the {len(sig)} significant ones within {sig.deviation_pct.abs().max():.2f} %"
             if len(sig) else ""))
    v = result.verdict
    for c in result.verdicts:
        if c.required:
            print(f"check        {c.status.upper():<12} {c.name}"
                  + (f": {c.reason}" if c.status != "pass" else ""))
    print(f"verdict      {v.status.upper()}" + (f" — {v.reason}" if v.status != "pass" else
                                                "  (every required check passed)"))
    for p in paths:
        print(f"report       {p.resolve()}")
    print(f"done in {elapsed:.1f} s — open the report in a browser")
    return 0
