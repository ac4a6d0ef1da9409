"""Regenerate the raw rig export in this folder (deterministic; run from the repository root).

``genset_60-2.txt``: what a genset bench's logger wrote — tab-separated, no header, decimal
point, 20 kHz: column 1 the 0–5 V pick-up of a 60-2 crank wheel whose tooth before the gap is a
runt (11 % of the swing), column 2 a TDC mark two samples wide on a drifting baseline, column 3
a cylinder pressure transducer's output in V. The speed rises from 1200 to 1500 rpm in 0.5 s.
``genset_60-2_map.toml`` reads it (see :mod:`crankbench.measure.channelmap`)::

    python sample_data/raw/make_raw.py
    crankbench import sample_data/raw/genset_60-2.txt --map sample_data/raw/genset_60-2_map.toml -o genset.h5
"""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

MAP = """# Channel map of genset_60-2.txt (crankbench import ... --map this file).
description = "genset bench: 60-2 crank wheel, TDC mark, cylinder 1 pressure; 20 kHz, no header"

[source]
sample_rate = 20000.0         # Hz: the file has no time column
delimiter = "tab"
decimal = "."
engine_id = "G1 genset"
test_id = "run-up 1200-1500 rpm"

[channel.crank]               # the crank wheel pick-up, 0-5 V
column = 1
role = "wheel"
pulses_per_rev = 60
missing_teeth = 2
keep_raw = true               # also keep the voltage as crank_raw

[channel.tdc]                 # a TDC mark once per revolution, two samples wide
column = 2
role = "tdc"

[channel.pressure]            # transducer: V = 5 (0.00385 p + 0.115), p in kPa
column = 3
units = "kPa"
quantity = "pressure"
scale = 51.94805194805195     # kPa per V: 1 / (5 x 0.00385)
offset = -29.87012987012987   # kPa: -0.115 / 0.00385
location = "cylinder 1"
"""


def make(folder: Path = HERE) -> list[Path]:
    """Write the export and its map into ``folder``; return their paths."""
    from crankbench.measure.synth.rawrig import raw_rig

    rig = raw_rig(folder, name="genset_60-2", dialect="tab_headerless", fs=20_000.0,
                  duration=0.5, speed_rpm=(1200.0, 1500.0), seed=14, digits=5)
    rig.map_path.write_text(MAP, encoding="utf-8")
    return [rig.path, rig.map_path]


if __name__ == "__main__":
    for p in make():
        print(f"wrote {p} ({p.stat().st_size / 1e3:.0f} kB)")
