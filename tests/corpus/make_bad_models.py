"""Generate the bad-model corpus: engine, shaft-line, rotor and scene TOML files, each wrong once.

Every case starts from a small valid model (``ENGINE``, ``SHAFTLINE``, ``ROTOR``, ``SCENE``) and
changes one thing: a negative mass or inertia, a rod shorter than the crank, a firing order
that is not a permutation, a misspelt key, a wrong type, a missing required key, a per-cylinder
list of the wrong length, a disconnected shaft graph, a gear ratio of 0, a reference to a
missing engine file, an unknown element type... ``CASES`` lists them with the words the
loader's error message must contain (the file, the dotted key and what was expected);
``tests/reliability/test_bad_models.py`` loads every file and checks the message.

Regenerate (the files are committed; the test checks they match this script)::

    python tests/corpus/make_bad_models.py            # writes tests/corpus/bad/models/*.toml
    python tests/corpus/make_bad_models.py --check    # exit 1 if the folder is out of date
"""

from __future__ import annotations

import argparse
import re
import sys
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Case", "CASES", "ENGINE", "SHAFTLINE", "ROTOR", "SCENE", "OUT", "render", "write_corpus"]

OUT = Path(__file__).resolve().parent / "bad" / "models"

# A valid in-line four (the values of a 2-litre car engine); each engine case changes one line.
ENGINE = """\
[engine]
name = "corpus I4"
crank_angles_deg = [0, 180, 180, 0]
crank_radius = 0.043
rod_length = 0.145
reciprocating_mass = 0.55
rotating_mass = 0.8
cylinder_spacing = 0.09
firing_order = [1, 3, 4, 2]
bore = 0.086
"""

# A valid shaft line with an in-line [engine]: damper, four throws, flywheel, gearbox, vehicle.
SHAFTLINE = ENGINE + """
[shaftline]
name = "corpus I4 driveline"
speed_range_rpm = [800, 6000]

[[shaftline.mass]]
name = "pulley"
inertia = 0.0025

[[shaftline.mass]]
name = "cyl 1"
cylinder = 1
throw_inertia = 0.0022

[[shaftline.mass]]
name = "cyl 2"
cylinder = 2
throw_inertia = 0.0022

[[shaftline.mass]]
name = "cyl 3"
cylinder = 3
throw_inertia = 0.0022

[[shaftline.mass]]
name = "cyl 4"
cylinder = 4
throw_inertia = 0.0022

[[shaftline.mass]]
name = "flywheel"
inertia = 0.12

[[shaftline.mass]]
name = "output gear"
inertia = 0.01
ratio = 0.25

[[shaftline.mass]]
name = "vehicle"
inertia = 95.0
ratio = 0.25

[[shaftline.shaft]]
from = "pulley"
to = "cyl 1"
stiffness = 2.5e5

[[shaftline.shaft]]
from = "cyl 1"
to = "cyl 2"
stiffness = 3.2e5

[[shaftline.shaft]]
from = "cyl 2"
to = "cyl 3"
stiffness = 3.2e5

[[shaftline.shaft]]
from = "cyl 3"
to = "cyl 4"
stiffness = 3.2e5

[[shaftline.shaft]]
from = "cyl 4"
to = "flywheel"
stiffness = 4.0e5
diameter = 0.055

[[shaftline.gear]]
driver = "flywheel"
driven = "output gear"
ratio = 0.25

[[shaftline.shaft]]
from = "output gear"
to = "vehicle"
stiffness = 1.8e4
"""

# A valid two-disk rotor on two bearings.
ROTOR = """\
[rotor]
name = "corpus rotor"
theory = "timoshenko"
max_element_length = 0.25

[rotor.material]
youngs_modulus = 211.0e9
density = 7810.0
shear_modulus = 81.2e9

[[rotor.shaft]]
length = 1.5
outer_diameter = 0.05

[[rotor.disks]]
position = 0.5
mass = 32.6
diametral_inertia = 0.18
polar_inertia = 0.33

[[rotor.bearings]]
position = 0.0
kxx = 1.0e6
kyy = 0.8e6

[[rotor.bearings]]
position = 1.5
kxx = 1.0e6
kyy = 0.8e6
"""

# A valid scene (measure.synth) on the sample I4 engine and driveline: steady 1500 rpm, 1 s,
# a 60-2 tacho on the flywheel and a speed channel. Model paths are relative to the corpus
# folder (tests/corpus/bad/models -> sample_data).
SCENE = """\
[scene]
name = "corpus scene"
engine = "../../../../sample_data/engines/i4.toml"
shaftline = "../../../../sample_data/shaftlines/i4.toml"
seed = 1

[profile]
kind = "steady"
speed_rpm = 1500.0
duration = 1.0

[[sensor]]
kind = "tacho"
name = "tacho"
node = "flywheel"
pulses_per_rev = 60
missing_teeth = 2

[[sensor]]
kind = "speed"
name = "speed"
sample_rate = 100.0
"""


@dataclass(frozen=True)
class Case:
    """One bad model file.

    Attributes
    ----------
    name : str
        File stem (``<kind>_<what>``); the file is ``OUT / f"{name}.toml"``.
    kind : str
        Loader: ``"engine"`` (``Engine.from_toml``), ``"shaftline"``
        (``predict.torsion.from_toml``), ``"rotor"`` (``predict.lateral.load_rotor``) or
        ``"scene"`` (``measure.synth.Scene.from_toml``).
    text : str or bytes
        File content.
    match : tuple of str
        Regular expressions the error message must all contain (the file name is checked
        separately for every case).
    error : str
        Expected exception class name (``"ModelError"`` unless stated); empty for a file that
        loads but must warn (``warning``).
    fault : str
        Empty for a case the loader handles; else the fault found (the test is a strict xfail
        until the loader is fixed).
    file : str
        File name the message must contain when it is not the case's own file (an error in a
        referenced engine file names that file).
    warning : str
        Expected warning class name (``"PlausibilityWarning"``: a likely unit slip); ``match``
        then applies to the warning's message.
    """

    name: str
    kind: str
    text: str | bytes
    match: tuple[str, ...]
    error: str = "ModelError"
    fault: str = ""
    file: str = ""
    warning: str = ""


def _set(base: str, key: str, value: str | None, *, nth: int = 0) -> str:
    """Replace (``value`` given) or delete (``None``) the ``nth`` line ``key = ...`` of ``base``."""
    lines = base.splitlines(keepends=True)
    hits = [i for i, line in enumerate(lines) if re.match(rf"{re.escape(key)}\s*=", line)]
    if len(hits) <= nth:
        raise KeyError(f"{key!r} occurs {len(hits)} times in the base text, need #{nth}")
    i = hits[nth]
    if value is None:
        del lines[i]
    else:
        lines[i] = f"{key} = {value}\n"
    return "".join(lines)


def _add_after(base: str, anchor: str, text: str) -> str:
    """Insert ``text`` after the first line equal to ``anchor``."""
    lines = base.splitlines(keepends=True)
    i = next(i for i, line in enumerate(lines) if line.rstrip("\n") == anchor)
    return "".join(lines[: i + 1] + [text if text.endswith("\n") else text + "\n"] + lines[i + 1:])


def _engine_cases() -> list[Case]:
    e = ENGINE
    return [
        Case("engine_negative_reciprocating_mass", "engine",
             _set(e, "reciprocating_mass", "-0.55"),
             (r"engine\.reciprocating_mass", r"-0\.55", r"must be >= 0")),
        Case("engine_negative_mass_in_list", "engine",
             _set(e, "rotating_mass", "[0.8, 0.8, -0.1, 0.8]"),
             (r"engine\.rotating_mass\[2\]", r"-0\.1", r"must be >= 0")),
        Case("engine_zero_crank_radius", "engine", _set(e, "crank_radius", "0.0"),
             (r"engine\.crank_radius", r"must be > 0")),
        Case("engine_nan_crank_radius", "engine", _set(e, "crank_radius", "nan"),
             (r"engine\.crank_radius", r"must be finite")),
        Case("engine_inf_mass", "engine", _set(e, "reciprocating_mass", "inf"),
             (r"engine\.reciprocating_mass", r"must be finite")),
        Case("engine_rod_shorter_than_crank", "engine", _set(e, "rod_length", "0.03"),
             (r"\[engine\]", r"rod_length=0\.03", r"must exceed crank_radius")),
        Case("engine_rod_equal_to_crank", "engine", _set(e, "rod_length", "0.043"),
             (r"rod_length=0\.043", r"must exceed crank_radius")),
        Case("engine_firing_order_repeated_cylinder", "engine",
             _set(e, "firing_order", "[1, 3, 3, 2]"),
             (r"firing_order=\[1, 3, 3, 2\]", r"each cylinder")),
        Case("engine_firing_order_cylinder_out_of_range", "engine",
             _set(e, "firing_order", "[1, 3, 5, 2]"),
             (r"firing_order", r"\[1, 3, 5, 2\]", r"each cylinder|1\.\.4|cylinder number")),
        Case("engine_firing_order_too_short", "engine", _set(e, "firing_order", "[1, 3, 4]"),
             (r"firing_order", r"\[1, 3, 4\]", r"each cylinder|4")),
        Case("engine_firing_order_string", "engine", _set(e, "firing_order", '"1-3-4-2"'),
             (r"engine\.firing_order", r"must be an array of cylinder numbers")),
        Case("engine_firing_order_floats", "engine",
             _set(e, "firing_order", "[1.0, 3.0, 4.0, 2.0]"),
             (r"engine\.firing_order", r"must be an array of cylinder numbers")),
        Case("engine_unknown_key_typo", "engine", _set(e, "bore", None) + "bor = 0.086\n",
             (r"engine\.bor\b", r"not a known key", r"did you mean 'bore'")),
        Case("engine_unknown_key_typo_of_required", "engine",
             _set(e, "rod_length", None) + "rod_lenght = 0.145\n",
             (r"engine\.rod_length", r"missing", r"rod_lenght"),),
        # issue 19: a quantity string with its unit is read ("43 mm"); one without a unit, of
        # the wrong dimension or with an unknown unit is refused naming the expected unit
        Case("engine_wrong_type_string_number", "engine", _set(e, "crank_radius", '"43"'),
             (r"engine\.crank_radius", r"'43' has no unit", r"plain number \(in m\)")),
        Case("engine_unit_wrong_dimension", "engine", _set(e, "crank_radius", '"43 kg"'),
             (r"engine\.crank_radius", r"'43 kg' has the wrong dimension",
              r"expected a quantity in m")),
        Case("engine_unit_unknown", "engine", _set(e, "crank_radius", '"43 mmm"'),
             (r"engine\.crank_radius", r"'43 mmm': unknown unit", r"expected a quantity in m")),
        Case("engine_bore_in_mm_slip", "engine", _set(e, "bore", "86"),
             (r"engine\.bore = 86 m: did you mean 86 mm\?",), error="",
             warning="PlausibilityWarning"),
        Case("engine_wrong_type_bool_number", "engine", _set(e, "bore", "true"),
             (r"engine\.bore", r"True", r"must be a number")),
        Case("engine_wrong_type_angles_strings", "engine",
             _set(e, "crank_angles_deg", '["0", "180", "180", "0"]'),
             (r"engine\.crank_angles_deg\[0\]", r"'0' has no unit", r"in deg")),
        Case("engine_wrong_type_cycle_float", "engine", e + "cycle = 4.0\n",
             (r"engine\.cycle", r"4\.0", r"must be an integer")),
        Case("engine_wrong_type_name_number", "engine", _set(e, "name", "4"),
             (r"engine\.name", r"must be a string")),
        Case("engine_missing_crank_angles", "engine", _set(e, "crank_angles_deg", None),
             (r"engine\.crank_angles_deg", r"is missing \(required\)")),
        Case("engine_missing_reciprocating_mass", "engine", _set(e, "reciprocating_mass", None),
             (r"engine\.reciprocating_mass", r"is missing \(required\)")),
        Case("engine_missing_crank_radius_and_stroke", "engine", _set(e, "crank_radius", None),
             (r"engine\.crank_radius", r"is missing \(required\)")),
        Case("engine_empty_crank_angles", "engine", _set(e, "crank_angles_deg", "[]"),
             (r"engine\.crank_angles_deg", r"at least one cylinder")),
        Case("engine_bank_angles_wrong_length", "engine",
             e + "bank_angles_deg = [45, -45]\n",
             (r"engine\.bank_angles_deg", r"has 2 values, expected 4")),
        Case("engine_positions_wrong_length", "engine",
             _set(e, "cylinder_spacing", None) + "cylinder_positions = [0.0, 0.09, 0.18]\n",
             (r"engine\.cylinder_positions", r"has 3 values, expected 4")),
        Case("engine_masses_wrong_length", "engine",
             _set(e, "reciprocating_mass", "[0.55, 0.55]"),
             (r"engine\.reciprocating_mass", r"has 2 values, expected 4")),
        Case("engine_cycle_three", "engine", e + "cycle = 3\n",
             (r"\[engine\]", r"cycle=3", r"must be 2 or 4")),
        Case("engine_stroke_and_crank_radius", "engine", e + "stroke = 0.086\n",
             (r"engine\.stroke", r"either stroke or crank_radius")),
        Case("engine_compression_ratio_below_one", "engine", e + "compression_ratio = 0.9\n",
             (r"engine\.compression_ratio", r"0\.9", r"must be > 1")),
        Case("engine_articulated_master_out_of_range", "engine",
             e + "\n[[engine.articulated]]\ncylinder = 2\nmaster = 9\nlink_radius = 0.05\n"
                 "link_angle_deg = 60.0\nrod_length = 0.1\n",
             (r"engine\.articulated\[0\]\.master", r"must be <= 4")),
        Case("engine_no_engine_table", "engine", e.replace("[engine]", "[engin]"),
             (r"no \[engine\] table",)),
        Case("engine_engine_not_a_table", "engine", 'engine = "i4"\n',
             (r"engine", r"must be a table")),
        Case("engine_invalid_toml_syntax", "engine", e.replace("[1, 3, 4, 2]", "[1, 3, 4, 2"),
             (r"not valid TOML",)),
        Case("engine_duplicate_key", "engine", e + "bore = 0.09\n",
             (r"not valid TOML",)),
        Case("engine_not_utf8", "engine", b"[engine]\nname = \"\xff\xfe\xfa\"\n",
             (r"not (valid TOML|a UTF-8 text file)",)),
        Case("engine_empty_file", "engine", "",
             (r"no \[engine\] table",)),
    ]


def _shaftline_cases() -> list[Case]:
    s = SHAFTLINE
    fly = 'name = "flywheel"'
    return [
        Case("shaftline_negative_inertia", "shaftline", _set(s, "inertia", "-0.12", nth=1),
             (r"shaftline\.mass\[5\]\.inertia", r"-0\.12", r"must be > 0")),
        Case("shaftline_zero_inertia", "shaftline", _set(s, "inertia", "0.0", nth=0),
             (r"shaftline\.mass\[0\]\.inertia", r"must be > 0")),
        Case("shaftline_negative_throw_inertia", "shaftline",
             _set(s, "throw_inertia", "-0.0022", nth=2),
             (r"shaftline\.mass\[3\]\.throw_inertia", r"must be >= 0")),
        Case("shaftline_negative_stiffness", "shaftline", _set(s, "stiffness", "-3.2e5", nth=1),
             (r"shaftline\.shaft\[1\]\.stiffness", r"must be > 0")),
        Case("shaftline_gear_ratio_zero", "shaftline", _set(s, "ratio", "0.0", nth=2),
             (r"shaftline\.gear\[0\]\.ratio", r"must be > 0")),
        Case("shaftline_mass_ratio_zero", "shaftline", _set(s, "ratio", "0", nth=0),
             (r"shaftline\.mass\[6\]", r"ratio", r"non-zero")),
        Case("shaftline_gear_ratio_mismatch", "shaftline", _set(s, "ratio", "0.5", nth=2),
             (r"shaftline\.gear\[0\]", r"driven node ratio 0\.25", r"gear ratio 0\.5")),
        Case("shaftline_disconnected_graph", "shaftline",
             s.replace('[[shaftline.shaft]]\nfrom = "cyl 2"\nto = "cyl 3"\nstiffness = 3.2e5\n\n',
                       ""),
             (r"disconnected|not connected", r"cyl 2", r"cyl 3"),),
        Case("shaftline_isolated_mass", "shaftline",
             s + '\n[[shaftline.mass]]\nname = "spare"\ninertia = 0.5\n',
             (r"disconnected|not connected", r"spare"),),
        Case("shaftline_missing_engine_file", "shaftline",
             s[len(ENGINE):].replace('name = "corpus I4 driveline"',
                                     'name = "corpus I4 driveline"\n'
                                     'engine = "no_such_engine.toml"'),
             (r"shaftline\.engine", r"no_such_engine\.toml", r"does not exist")),
        Case("shaftline_bad_referenced_engine", "shaftline",
             s[len(ENGINE):].replace('name = "corpus I4 driveline"',
                                     'name = "corpus I4 driveline"\n'
                                     'engine = "engine_rod_shorter_than_crank.toml"'),
             (r"rod_length=0\.03", r"must exceed crank_radius"),
             file="engine_rod_shorter_than_crank.toml"),
        Case("shaftline_unknown_element_type", "shaftline",
             s + '\n[[shaftline.spring]]\nfrom = "flywheel"\nto = "vehicle"\nstiffness = 1e3\n',
             (r"shaftline\.spring", r"not a known key", r"expected one of")),
        Case("shaftline_unknown_damper_type", "shaftline",
             s + '\n[[shaftline.damper]]\ntype = "visous"\nnode = "pulley"\n'
                 "ring_inertia = 0.006\ndamping = 10.0\n",
             (r"shaftline\.damper\[0\]\.type", r"'visous'", r"did you mean 'viscous'")),
        Case("shaftline_unknown_key_in_element", "shaftline",
             _add_after(s, fly, "inertia_kgm2 = 0.1"),
             (r"shaftline\.mass\[5\]\.inertia_kgm2", r"not a known key")),
        Case("shaftline_unknown_node", "shaftline", s.replace('to = "flywheel"',
                                                             'to = "flywheeel"'),
             (r"shaftline\.shaft\[4\]", r"unknown node 'flywheeel'", r"did you mean 'flywheel'")),
        Case("shaftline_node_defined_twice", "shaftline",
             s + '\n[[shaftline.mass]]\nname = "flywheel"\ninertia = 0.2\n',
             (r"shaftline\.mass\[8\]", r"'flywheel' defined twice")),
        Case("shaftline_shaft_without_stiffness", "shaftline",
             _set(s, "stiffness", None, nth=0),
             (r"shaftline\.shaft\[0\]", r"give stiffness, length\+diameter or segments")),
        Case("shaftline_missing_node_name", "shaftline", _set(s, "name", None, nth=2),
             (r"shaftline\.mass\[0\]\.name", r"is missing \(required\)")),
        Case("shaftline_cylinder_not_in_engine", "shaftline",
             _set(s, "cylinder", "7", nth=3),
             (r"shaftline\.mass\[4\]", r"cylinder=7", r"must be in 1\.\.4")),
        Case("shaftline_segments_malformed", "shaftline",
             _set(s, "stiffness", "[[1.0]]", nth=4).replace(
                 "stiffness = [[1.0]]", "segments = [[1.0]]"),
             (r"shaftline\.shaft\[4\]\.segments", r"\[length, diameter\]")),
        Case("shaftline_speed_range_wrong_length", "shaftline",
             _set(s, "speed_range_rpm", "[800, 3000, 6000]"),
             (r"shaftline\.speed_range_rpm", r"has 3 values, expected 2")),
        Case("shaftline_mass_not_array_of_tables", "shaftline",
             s[len(ENGINE):].split("[[shaftline.mass]]")[0] + "mass = 5\n",
             (r"shaftline\.mass", r"must be an array of tables")),
        Case("shaftline_limits_wrong_length", "shaftline",
             s + "\n[limits]\nspeed_rpm = [0, 7000]\ncontinuous_mpa = [60.0]\n"
                 "transient_mpa = [140.0, 140.0]\n",
             (r"limits\.continuous_mpa", r"has 1 values, expected 2")),
        Case("shaftline_no_shaftline_table", "shaftline", ENGINE,
             (r"no \[shaftline\] table",)),
        # issue 19: unit slips load but warn with the likely unit
        Case("shaftline_shear_modulus_in_gpa_slip", "shaftline",
             _add_after(s, "speed_range_rpm = [800, 6000]", "shear_modulus = 81"),
             (r"shaftline\.shear_modulus = 81 Pa: did you mean 81 GPa\?",
              r"plain numbers are in Pa"), error="", warning="PlausibilityWarning"),
        Case("shaftline_diameter_in_mm_slip", "shaftline", _set(s, "diameter", "55"),
             (r"shaftline\.shaft\[4\]\.diameter = 55 m: did you mean 55 mm\?",), error="",
             warning="PlausibilityWarning"),
        Case("shaftline_stiffness_wrong_unit", "shaftline",
             _set(s, "stiffness", '"2.5e5 N*m"'),
             (r"shaftline\.shaft\[0\]\.stiffness", r"wrong dimension", r"N·m/rad")),
    ]


def _rotor_cases() -> list[Case]:
    r = ROTOR
    return [
        Case("rotor_negative_disk_mass", "rotor", _set(r, "mass", "-32.6"),
             (r"rotor\.disks\[0\]\.mass", r"-32\.6")),
        Case("rotor_zero_shaft_length", "rotor", _set(r, "length", "0.0"),
             (r"rotor\.shaft\[0\]\.length", r"must be > 0")),
        Case("rotor_unknown_theory", "rotor", _set(r, "theory", '"timoshenk"'),
             (r"rotor\.theory", r"'timoshenk'", r"did you mean 'timoshenko'")),
        Case("rotor_unknown_key_typo", "rotor", _add_after(r, "density = 7810.0", "densty = 1.0"),
             (r"rotor\.material\.densty", r"not a known key", r"did you mean 'density'")),
        Case("rotor_disk_outside_shaft", "rotor", _set(r, "position", "2.5", nth=0),
             (r"disks\[0\]\.position=2\.5", r"beyond the shaft end")),
        Case("rotor_missing_shaft", "rotor",
             r.replace("[[rotor.shaft]]\nlength = 1.5\nouter_diameter = 0.05\n", ""),
             (r"rotor\.shaft", r"missing|at least one")),
        Case("rotor_negative_bearing_stiffness", "rotor", _set(r, "kxx", "-1.0e6"),
             (r"rotor\.bearings\[0\]\.kxx", r"-1000000|-1e\+?0?6", r">= 0")),
        # issue 19: a mesh of 15 million elements is refused before any allocation
        Case("rotor_max_element_length_tiny", "rotor", _set(r, "max_element_length", "1e-7"),
             (r"rotor", r"max_element_length=1e-07 m", r"15000000 elements \(60000004 degrees of freedom",
              r"would need 205 PiB", r"use longer elements")),
        Case("rotor_youngs_modulus_slip", "rotor", _set(r, "youngs_modulus", "211"),
             (r"rotor\.material\.youngs_modulus = 211 Pa: did you mean 211 GPa\?",), error="",
             warning="PlausibilityWarning"),
    ]


def _scene_cases() -> list[Case]:
    c = SCENE
    return [
        Case("scene_unknown_key_typo", "scene",
             _add_after(_set(c, "seed", None), 'name = "corpus scene"', "sead = 1"),
             (r"scene\.sead", r"not a known key", r"did you mean 'seed'"), error="ConfigError"),
        Case("scene_missing_profile", "scene", c.split("[profile]")[0] + "[[sensor]]" +
             c.split("[[sensor]]", 1)[1],
             (r"no \[profile\] table",), error="ConfigError"),
        Case("scene_profile_kind_typo", "scene", _set(c, "kind", '"stedy"'),
             (r"profile\.kind", r"'stedy'", r"did you mean 'steady'"), error="ConfigError"),
        Case("scene_negative_speed", "scene", _set(c, "speed_rpm", "-1500.0"),
             (r"profile\.speed_rpm", r"-1500\.0", r"must be > 0"), error="ConfigError"),
        Case("scene_zero_duration", "scene", _set(c, "duration", "0.0"),
             (r"profile\.duration", r"must be > 0"), error="ConfigError"),
        Case("scene_runup_end_below_start", "scene",
             c.replace('kind = "steady"\nspeed_rpm = 1500.0',
                       'kind = "runup"\nstart_rpm = 3000.0\nend_rpm = 1000.0'),
             (r"profile\.end_rpm", r"must be above start_rpm"), error="ConfigError"),
        Case("scene_missing_engine_file", "scene",
             _set(c, "engine", '"no_such_engine.toml"'),
             (r"scene\.engine", r"no_such_engine\.toml", r"does not exist"),
             error="FileNotFoundError"),
        Case("scene_bad_engine_file", "scene",
             _set(c, "engine", '"engine_rod_shorter_than_crank.toml"'),
             (r"rod_length=0\.03", r"must exceed crank_radius"), error="ModelError",
             file="engine_rod_shorter_than_crank.toml"),
        Case("scene_sensor_kind_typo", "scene", _set(c, "kind", '"tahco"', nth=1),
             (r"sensor\[0\]\.kind", r"is not one of", r"did you mean 'tacho'"),
             error="ConfigError"),
        Case("scene_sensor_name_with_space", "scene", _set(c, "name", '"tacho 1"', nth=1),
             (r"sensor\[0\]\.name", r"'tacho 1'", r"letters, digits and underscores"),
             error="ConfigError"),
        Case("scene_sensor_names_repeated", "scene", _set(c, "name", '"tacho"', nth=2),
             (r"sensor names must be unique", r"tacho"), error="ConfigError"),
        Case("scene_too_many_missing_teeth", "scene", _set(c, "missing_teeth", "59"),
             (r"sensor\[0\]\.missing_teeth", r"= 59 must be less than pulses_per_rev - 1"),
             error="ConfigError"),
        Case("scene_sensor_node_unknown", "scene", _set(c, "node", '"flywheeel"'),
             (r"sensor 'tacho' node='flywheeel' is not a shaft-line node",
              r"did you mean 'flywheel'"), error="ConfigError"),
        Case("scene_no_sensors", "scene", c.split("[[sensor]]")[0],
             (r"no sensors", r"\[\[sensor\]\]"), error="ConfigError"),
        Case("scene_negative_sample_rate", "scene", _set(c, "sample_rate", "-100.0"),
             (r"sensor\[1\]\.sample_rate", r"must be > 0"), error="ConfigError"),
        Case("scene_negative_seed", "scene", _set(c, "seed", "-1"),
             (r"scene\.seed", r"= -1 must be >= 0"), error="ConfigError"),
        # issue 19: a scene at 1e12 Hz is refused before anything is synthesized
        Case("scene_sample_rate_1e12", "scene", _set(c, "sample_rate", "1e12"),
             (r"sensor 'speed' sample_rate = 1e\+12 Hz over 1 s", r"would need 29\.1 TiB",
              r"lower the sample rate"), error="ConfigError"),
        Case("scene_speed_unit_string", "scene", _set(c, "speed_rpm", '"1500 m/s"'),
             (r"profile\.speed_rpm", r"wrong dimension", r"in rpm"), error="ConfigError"),
    ]


def _all_cases() -> list[Case]:
    cases = _engine_cases() + _shaftline_cases() + _rotor_cases() + _scene_cases()
    names = [c.name for c in cases]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        raise RuntimeError(f"duplicate case names: {sorted(dup)}")
    return cases


CASES: list[Case] = _all_cases()


def render(case: Case) -> bytes:
    """File content of ``case`` with a one-line header comment saying what is wrong."""
    body = case.text if isinstance(case.text, bytes) else case.text.encode()
    if not body:
        return body  # the empty-file case stays empty
    header = f"# crankbench bad-model corpus: {case.name} (generated by make_bad_models.py)\n"
    return header.encode() + body


def write_corpus(out: Path = OUT, *, check: bool = False) -> list[Path]:
    """Write every case into ``out`` (or, with ``check``, list the files that differ)."""
    out.mkdir(parents=True, exist_ok=True)
    stale = []
    for case in CASES:
        path = out / f"{case.name}.toml"
        data = render(case)
        if path.exists() and path.read_bytes() == data:
            continue
        stale.append(path)
        if not check:
            path.write_bytes(data)
    wanted = {f"{c.name}.toml" for c in CASES}
    extra = [p for p in out.glob("*.toml") if p.name not in wanted]
    return stale + extra


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true",
                        help="do not write; exit 1 if the corpus differs from this script")
    parser.add_argument("-o", "--out", type=Path, default=OUT)
    args = parser.parse_args(argv)
    changed = write_corpus(args.out, check=args.check)
    for p in changed:
        print(("stale: " if args.check else "wrote: ") + str(p))
    print(f"{len(CASES)} bad models in {args.out}")
    return 1 if (args.check and changed) else 0


if __name__ == "__main__":
    sys.exit(main())
