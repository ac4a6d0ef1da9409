"""``crankbench synth SCENE.toml -o run.h5 [--overwrite] [--json]``: synthesize a record.

Reads the scene (engine, shaft line, mounts, operating profile, sensors, imperfections; see
:mod:`measure.synth.scene`), synthesizes the record with :func:`measure.synth.synthesize` and
writes it atomically with its ground truth (HDF5 group ``truth``; the truth is kept only by
``.h5``/``.hdf5``/``.nc`` outputs). Prints one row per channel, the critical speeds the run
crosses and the fidelity used. An existing output is not replaced without ``--overwrite``.
"""

from __future__ import annotations

HELP = "synthesize a test-bench record with its ground truth from a scene TOML"


def configure(parser) -> None:
    parser.add_argument("scene", metavar="SCENE.toml", help="scene file (sample_data/scenes/)")
    parser.add_argument("-o", "--output", required=True, metavar="FILE",
                        help="record to write (.h5 keeps the ground truth; any record format)")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing output")
    parser.add_argument("--method", choices=("split", "full"), default="split",
                        help="torsional integration: modes through/below the swept band in "
                             "time, others quasi-static (split, default) or all in time (full)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of tables")


def _written_sidecars(out):
    """Files written beside the record (the WAV sidecar)."""
    from crankbench.measure.readers import module_for
    from pathlib import Path

    try:
        return [Path(str(out) + s) for s in getattr(module_for(out), "SIDECARS", ())]
    except Exception:  # noqa: BLE001 - an unknown extension is reported by the writer
        return []


def run(args) -> int:
    from pathlib import Path

    from crankbench.measure._atomic import check_overwrite

    from crankbench.analysis.commands._files import check_outputs, model_inputs

    out = Path(args.output)
    check_outputs([(out, f"-o {out}")] + [(p, f"the sidecar of -o {out} ({p})")
                                            for p in _written_sidecars(out)],
                  model_inputs(args.scene, "the scene"))
    check_overwrite(out, args.overwrite, option="--overwrite")   # before any heavy work

    import json

    import numpy as np
    import pandas as pd

    from crankbench.analysis._output import print_json, print_table
    from crankbench.measure.io import write
    from crankbench.measure.synth import synthesize

    result = synthesize(args.scene, method=args.method)
    keeps_truth = out.suffix.lower() in (".h5", ".hdf5", ".nc")
    write(result.record, out, truth=result.truth if keeps_truth else None,
          overwrite=args.overwrite)
    table = result.to_frame()
    truth = result.truth
    crit = pd.DataFrame()
    if "critical_speed_rpm" in truth:
        crit = pd.DataFrame({"mode": truth["critical_mode"].values,
                             "order": truth["critical_order"].values,
                             "speed_rpm": truth["critical_speed_rpm"].values,
                             "frequency_hz": truth["critical_frequency_hz"].values,
                             "damping_ratio": truth["critical_damping_ratio"].values,
                             "major": truth["critical_major"].values})
    summary = {
        "scene": result.scene.name, "output": str(out), "truth_written": keeps_truth,
        "duration_s": result.scene.profile.duration, "elapsed_s": result.elapsed_s,
        "channels": table, "critical_speeds": crit, "fidelity": result.fidelity,
    }
    if args.json:
        print_json(summary)
        return 0
    print(f"scene       {result.scene.name}  ({args.scene})")
    print(f"output      {out}" + ("" if keeps_truth else "  (no truth: use .h5 to keep it)"))
    print(f"duration    {result.scene.profile.duration:g} s, synthesized in "
          f"{result.elapsed_s:.2f} s")
    print()
    print_table(table, title="channels")
    if len(crit):
        major = crit[crit["major"]]
        print()
        print_table(major if len(major) else crit,
                    title="critical speeds crossed (major orders)" if len(major)
                    else "critical speeds crossed")
    print()
    print("fidelity    " + json.dumps({k: (round(v, 6) if isinstance(v, float) and
                                            np.isfinite(v) else v)
                                        for k, v in result.fidelity.items()}))
    return 0
