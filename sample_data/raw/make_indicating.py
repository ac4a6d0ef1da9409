"""Regenerate ``indicating_ca.csv``: an indicating system's crank-angle-domain export
(deterministic; run from the repository root).

What an AVL/Kistler-style system writes after a measurement on the synthetic bench's I4 at
2000 rpm (``sample_data/scenes/steady_i4_pressure.toml``, 0.25 s): German headers, semicolons,
decimal commas, the long layout (``Zyklus;KW [°KW];Zylinderdruck Zyl1 [bar];Drehzahl
[1/min]``), cycles 101.. on a 0..719 °KW axis at 1 °KW with the firing TDC at 360 °KW, and the
transducer's unknown level (0.6 bar low). The pressure is the time-domain indicator analysis's
cycles of the bench record (``analysis.pressure.indicator_analysis``), so the angle-domain
analysis of this file can be held against it::

    python sample_data/raw/make_indicating.py
    crankbench pressure sample_data/raw/indicating_ca.csv --model sample_data/engines/i4.toml
"""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

OUT = HERE / "indicating_ca.csv"


def source():
    """The time-domain indicator analysis (1-deg grid) of the 0.25 s bench record."""
    import tempfile

    from crankbench.analysis.pressure import indicator_analysis
    from crankbench.measure.synth.run import synthesize

    scenes = ROOT / "sample_data/scenes"
    source = (scenes / "steady_i4_pressure.toml").read_text(encoding="utf-8")
    source = source.replace('"../', f'"{scenes.parent.as_posix()}/').replace(
        "duration = 3.0", "duration = 0.25")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "scene.toml"
        path.write_text(source, encoding="utf-8")
        run = synthesize(path)
    return indicator_analysis(run.record, run.scene.engine, resolution_deg=1.0)


def text(r=None):
    """The file's text (from :func:`source`)."""
    import numpy as np

    r = source() if r is None else r
    rows = ["Zyklus;KW [°KW];Zylinderdruck Zyl1 [bar];Drehzahl [1/min]"]
    deg = np.rad2deg(r.crank_angle) + 360.0
    for k in range(r.n_cycles):
        p = r.pressure[k] / 1e5 - 0.6
        for a, v in zip(deg, p):
            rows.append(f"{101 + k};{a:.0f};{v:.4f};{r.speed_rpm[k]:.1f}".replace(".", ","))
    return "\n".join(rows) + "\n"


if __name__ == "__main__":
    OUT.write_text(text(), encoding="utf-8")
    print(f"wrote {OUT}")
