"""Scene text of the synthetic I4 bench with cylinder pressure, for the pressure tests.

The I4 of sample_data on its shaft line with a pulley torsiograph, a 60-2 wheel and a
once-per-revolution TDC mark on cylinder 1's throw, and cylinder-1 pressure; the profile, the
load, the seed and further sensors are the caller's.
"""

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
ENGINE = ROOT / "sample_data/engines/i4.toml"
MODEL = ROOT / "sample_data/shaftlines/i4.toml"


def bench_scene(*, name, seed, profile, load="imep = 1.0e6", torsiograph_rate=3000.0,
                pressure_rate=20000.0, extra=""):
    """TOML text of the scene (``profile``/``load``: the bodies of those tables)."""
    return f"""
[scene]
name = "{name}"
engine = "{ENGINE}"
shaftline = "{MODEL}"
seed = {seed}
max_order = 6.0

[profile]
{profile}

[load]
{load}

[[sensor]]
kind = "torsiograph"
name = "tv_pulley"
node = "pulley hub"
quantity = "angle"
sample_rate = {torsiograph_rate}

[[sensor]]
kind = "tacho"
name = "wheel"
node = "cyl 1"
pulses_per_rev = 60
missing_teeth = 2
tdc_offset_deg = 84.0

[[sensor]]
kind = "tacho"
name = "tdc"
node = "cyl 1"
pulses_per_rev = 1

[[sensor]]
kind = "pressure"
name = "p_cyl1"
cylinder = 1
sample_rate = {pressure_rate}
noise_rms = 2.0e3
{extra}"""
