"""Bad command lines: every case of issue 19 (and its class) with the message it must give.

Each :class:`Case` is a ``crankbench`` command line over a small workspace of copies
(:func:`build_workspace`: sample records, models, balancing runs and a few generated models),
the exit status it must end with and the regular expressions its standard error must
contain. ``tests/reliability/test_bad_commands.py`` runs them all and also checks that no
input changed and no file appeared (a refused command writes nothing).

Placeholders in ``argv`` (``{csv}``, ``{model}``...) are the workspace's paths; ``env`` sets
environment variables for the case (``CRANKBENCH_MEMORY_LIMIT`` makes a size check
reproducible on any machine).

List the cases with::

    python tests/corpus/bad_commands.py
"""

from __future__ import annotations

import os
import shutil
import socket
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["Case", "CASES", "build_workspace"]

ROOT = Path(__file__).resolve().parents[2]
SAMPLE = ROOT / "sample_data"


@dataclass(frozen=True)
class Case:
    """One bad command line.

    Attributes
    ----------
    name : str
    argv : tuple of str
        Arguments after ``crankbench`` (placeholders filled from the workspace).
    status : int
        Expected exit status (2: refused with our one-line error or argparse's usage error;
        0: runs, with a warning).
    match : tuple of str
        Regular expressions standard error must contain.
    issue : str
        What the issue reported for this case before the fix.
    env : dict
        Environment variables set for the run.
    """

    name: str
    argv: tuple
    status: int
    match: tuple
    issue: str = ""
    env: dict = field(default_factory=dict)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def build_workspace(folder: Path) -> dict:
    """Fill ``folder`` with the inputs the cases use; return the placeholder values."""
    folder = Path(folder)
    rec = folder / "records"
    rec.mkdir(parents=True)
    for ext in (".h5", ".csv", ".wav", ".wav.json"):
        shutil.copy(SAMPLE / "records" / f"i4_runup{ext}", rec / f"i4_runup{ext}")
    os.symlink(rec / "i4_runup.csv", rec / "link.csv")
    os.link(rec / "i4_runup.csv", rec / "hard.csv")
    os.symlink(rec / "i4_runup.h5", rec / "report.html")     # outputs that are links to
    os.symlink(rec / "i4_runup.h5", rec / "both.pdf")        # the record
    models = folder / "models"
    shutil.copytree(SAMPLE / "engines", models / "engines")
    shutil.copytree(SAMPLE / "shaftlines", models / "shaftlines")
    shutil.copytree(SAMPLE / "balance", models / "balance", ignore=shutil.ignore_patterns(
        "records", "*.py"))
    trial = models / "balance" / "trial_plane1.toml"
    trial.write_text(trial.read_text().replace("speed_rpm = 2400.0", "speed_rpm = 2880.0"))
    # a rotor meshed at 0.1 µm: 15 million elements
    (models / "rotor_fine.toml").write_text(
        '[rotor]\nname = "fine"\nmax_element_length = 1e-7\n\n[[rotor.shaft]]\nlength = 1.5\n'
        'outer_diameter = 0.05\n\n[[rotor.bearings]]\nposition = 0.0\nkxx = 1.0e6\n\n'
        '[[rotor.bearings]]\nposition = 1.5\nkxx = 1.0e6\n')
    # a scene sampling its speed channel at 1e12 Hz
    (models / "scene_1e12.toml").write_text(
        '[scene]\nname = "fast"\nengine = "engines/i4.toml"\nshaftline = "shaftlines/i4.toml"\n'
        '\n[profile]\nkind = "steady"\nspeed_rpm = 1500.0\nduration = 1.0\n\n[[sensor]]\n'
        'kind = "speed"\nname = "speed"\nsample_rate = 1e12\n')
    # a 3000-mass chain (its dense mode shapes: 137 MiB)
    lines = ['[shaftline]', 'name = "long chain"', 'speed_range_rpm = [100, 1000]']
    for i in range(3000):
        lines += ['[[shaftline.mass]]', f'name = "m{i}"', 'inertia = 1.0']
    for i in range(2999):
        lines += ['[[shaftline.shaft]]', f'from = "m{i}"', f'to = "m{i + 1}"',
                  'stiffness = 1e6']
    (models / "chain3000.toml").write_text("\n".join(lines) + "\n")
    # the i4 shaft line with its shear modulus written in GPa but without the unit
    line = (models / "shaftlines" / "i4.toml").read_text()
    (models / "shaftlines" / "i4_g81.toml").write_text(
        line.replace("speed_range_rpm = [800, 6500]",
                     "speed_range_rpm = [800, 6500]\nshear_modulus = 81", 1))
    reports = folder / "reports"
    reports.mkdir()
    (reports / "i4_runup.html").write_text("an earlier report")
    return {
        "h5": str(rec / "i4_runup.h5"), "csv": str(rec / "i4_runup.csv"),
        "wav": str(rec / "i4_runup.wav"), "link": str(rec / "link.csv"),
        "hard": str(rec / "hard.csv"), "model": str(models / "shaftlines" / "i4.toml"),
        "report_link": str(rec / "report.html"), "both": str(rec / "both.html"),
        "engine": str(models / "engines" / "i4.toml"),
        "g81": str(models / "shaftlines" / "i4_g81.toml"),
        "scene_1e12": str(models / "scene_1e12.toml"),
        "rotor_fine": str(models / "rotor_fine.toml"),
        "chain": str(models / "chain3000.toml"),
        "initial": str(models / "balance" / "initial.toml"),
        "trial1": str(models / "balance" / "trial_plane1.toml"),
        "trial2": str(models / "balance" / "trial_plane2.toml"),
        "out": str(folder / "out"), "reports": str(reports),
        "records_glob": str(rec / "*.h5"),
        "port": str(_free_port()),
    }


_ONE_LINE = r"whatever --overwrite says"
_LIMIT = {"CRANKBENCH_MEMORY_LIMIT": "64 MiB"}

CASES = [
    # -- no output may resolve to an input --------------------------------------------------
    Case("batch_output_is_the_record",
         ("batch", "{csv}", "--model", "{model}", "-o", "{csv}", "--overwrite"), 2,
         (r"-o \S+i4_runup\.csv is one of the inputs \(the record \S+i4_runup\.csv\)", _ONE_LINE),
         "replaced the record with a 448-byte summary"),
    Case("batch_output_is_the_wav_sidecar",
         ("batch", "{wav}", "--model", "{model}", "-o", "{wav}.json", "--overwrite"), 2,
         (r"is one of the inputs \(the sidecar of the record \S+i4_runup\.wav\)", _ONE_LINE),
         "destroyed the WAV record's sidecar"),
    Case("batch_output_is_a_symlink_to_the_record",
         ("batch", "{csv}", "--model", "{model}", "-o", "{link}", "--overwrite"), 2,
         (r"-o \S+link\.csv resolves to \(is a link to\) one of the inputs", _ONE_LINE)),
    Case("batch_output_is_a_hard_link_to_the_record",
         ("batch", "{csv}", "--model", "{model}", "-o", "{hard}", "--overwrite"), 2,
         (r"-o \S+hard\.csv resolves to \(is a link to\) one of the inputs", _ONE_LINE)),
    Case("report_output_is_a_symlink_to_the_record",
         ("report", "{h5}", "{model}", "-o", "{report_link}", "--overwrite"), 2,
         (r"-o \S+report\.html resolves to \(is a link to\) one of the inputs \(the record "
          r"\S+i4_runup\.h5\)", _ONE_LINE)),
    Case("report_pdf_beside_is_a_symlink_to_the_record",
         ("report", "{h5}", "{model}", "-o", "{both}", "--pdf", "--overwrite"), 2,
         (r"the PDF beside it \(\S+both\.pdf\) resolves to \(is a link to\) one of the inputs",
          _ONE_LINE)),
    Case("synth_output_is_the_scenes_engine",
         ("synth", "{scene_1e12}", "-o", "{engine}", "--overwrite"), 2,
         (r"is one of the inputs \(a file named by scene_1e12\.toml: \S+engines/i4\.toml\)",
          _ONE_LINE)),
    Case("batch_existing_report_refused_before_work",
         ("batch", "{h5}", "--model", "{model}", "-o", "{out}/s.csv", "--reports", "{reports}",
          "--no-cache"), 2,
         (r"1 report\(s\) exist \(\S+reports/i4_runup\.html\); pass --overwrite",),
         "a good record was marked failed when its report existed"),
    # -- one list grammar -------------------------------------------------------------------
    Case("analyse_orders_repeated_item",
         ("analyse", "{h5}", "--channel", "acc_block_z", "--orders", "2,2"), 2,
         (r"argument --orders: 2 is given twice; list each value once",), "IndexError"),
    Case("analyse_orders_repeated_option",
         ("analyse", "{h5}", "--channel", "acc_block_z", "--orders", "2", "--orders", "2"), 2,
         (r"argument --orders: 2 is given twice",)),
    Case("analyse_orders_space_inside_one_argument",
         ("analyse", "{h5}", "--channel", "acc_block_z", "--orders", "2 4"), 2,
         (r"argument --orders: '2 4': items are separated by commas \(--orders 2,4\)",),
         "read silently as order 24"),
    Case("analyse_orders_empty_item",
         ("analyse", "{h5}", "--channel", "acc_block_z", "--orders", "2,,4"), 2,
         (r"argument --orders: '2,,4' has an empty item",), "read silently as 2,4"),
    Case("analyse_orders_as_two_arguments",
         ("analyse", "{h5}", "--channel", "acc_block_z", "--orders", "2", "4"), 2,
         (r"unrecognized arguments: 4; --orders takes one comma-separated list: write "
          r"--orders 2,4 \(or repeat --orders 2 --orders 4\)",)),
    Case("compare_orders_as_two_arguments",
         ("compare", "{h5}", "{model}", "--orders", "2", "4"), 2,
         (r"unrecognized arguments: 4; --orders takes one comma-separated list",)),
    Case("analyse_orders_not_finite",
         ("analyse", "{h5}", "--channel", "acc_block_z", "--orders", "2,nan"), 2,
         (r"argument --orders: 'nan' is not a finite number",)),
    Case("analyse_orders_zero",
         ("analyse", "{h5}", "--channel", "acc_block_z", "--orders", "0"), 2,
         (r"argument --orders: 0 must be > 0",)),
    Case("info_channels_as_two_arguments",
         ("info", "{h5}", "--channels", "acc_block_z", "speed"), 2,
         (r"--channels takes one comma-separated list: write --channels acc_block_z,speed",)),
    # -- every argument checked before the work ----------------------------------------------
    Case("compare_reference_rpm_zero",
         ("compare", "{h5}", "{model}", "--load-law", "propeller", "--reference-rpm", "0"), 2,
         (r"argument --reference-rpm: 0 must be > 0",), "failed after 140 s"),
    Case("compare_reference_rpm_without_propeller_law",
         ("compare", "{h5}", "{model}", "--reference-rpm", "720"), 2,
         (r"--reference-rpm applies to --load-law propeller only",)),
    Case("compare_tolerance_above_gate",
         ("compare", "{h5}", "{model}", "--tolerance", "0.2"), 2,
         (r"--tolerance 0\.2 must not exceed --gate 0\.15",)),
    Case("compare_channel_typo",
         ("compare", "{h5}", "{model}", "--channel", "acc_blok_z"), 2,
         (r"--channel 'acc_blok_z': record has no channel 'acc_blok_z' \(did you mean "
          r"'acc_block_z'\?\)",)),
    Case("compare_order_not_of_the_engine",
         ("compare", "{h5}", "{model}", "--orders", "0.25"), 2,
         (r"--orders 0\.25: not an order of this 4-stroke engine",)),
    Case("analyse_order_above_samples_per_rev",
         ("analyse", "{h5}", "--channel", "acc_block_z", "--orders", "30",
          "--samples-per-rev", "64"), 2,
         (r"--orders 30 exceeds --samples-per-rev/4 = 16 .*use --samples-per-rev 128",),
         "named the Python parameter samples_per_rev"),
    Case("analyse_speed_channel_typo",
         ("analyse", "{h5}", "--channel", "acc_block_z", "--orders", "2", "--speed-channel",
          "sped"), 2,
         (r"--speed-channel 'sped': no such channel \(did you mean 'speed'\?\)",)),
    Case("batch_workers_zero",
         ("batch", "{h5}", "--model", "{model}", "-o", "{out}/s.csv", "--workers", "0"), 2,
         (r"argument --workers: 0 must be >= 1",)),
    Case("predict_flywheel_speed_zero",
         ("predict", "flywheel", "{engine}", "--speed-rpm", "0"), 2,
         (r"argument --speed-rpm: 0 must be > 0",)),
    Case("predict_torsion_speed_range_reversed",
         ("predict", "torsion", "{model}", "--speed-range", "6000", "800"), 2,
         (r"--speed-range 6000 800: LOW must be below HIGH",)),
    Case("balance_iso_check_incomplete",
         ("balance", "{initial}", "{trial2}", "--radius", "0.1"), 2,
         (r"the ISO check needs all of --radius, --rotor-mass, --max-speed",)),
    # -- distributed batch ------------------------------------------------------------------
    Case("batch_scheduler_unreachable",
         ("batch", "{h5}", "--model", "{model}", "-o", "{out}/s.csv", "--scheduler",
          "tcp://127.0.0.1:{port}"), 2,
         (r"--scheduler 'tcp://127\.0\.0\.1:\d+': no dask scheduler answers there",),
         "waited 30 s then printed three raw tracebacks"),
    Case("batch_scheduler_malformed",
         ("batch", "{h5}", "--model", "{model}", "-o", "{out}/s.csv", "--scheduler",
          "localhost"), 2,
         (r"--scheduler 'localhost': expected tcp://HOST:PORT",)),
    # -- inconsistent inputs ----------------------------------------------------------------
    Case("balance_trial_run_at_another_speed",
         ("balance", "{initial}", "{trial1}", "{trial2}"), 2,
         (r"balance runs at different speeds: 'trial plane 1' at 2880 rpm \(\+20\.0 %\) "
          r"against 'initial' at 2400 rpm, beyond --speed-tolerance 0\.02",),
         "balance accepted trial runs taken at a different speed"),
    # -- sizes checked before allocation -----------------------------------------------------
    Case("predict_lateral_mesh_of_15_million_elements",
         ("predict", "lateral", "{rotor_fine}"), 2,
         (r"max_element_length=1e-07 m\) would need 205 PiB",),
         "asked for 25.6 PiB"),
    Case("synth_scene_at_1e12_hz",
         ("synth", "{scene_1e12}", "-o", "{out}/fast.h5"), 2,
         (r"sensor 'speed' sample_rate = 1e\+12 Hz over 1 s \(1e\+12 samples\) would need "
          r"29\.1 TiB",), "asked for 153 TiB"),
    Case("predict_torsion_chain_beyond_the_memory_limit",
         ("predict", "torsion", "{chain}", "--no-forced"), 2,
         (r"long chain: 3000 masses, dense mode shapes would need 137 MiB, more than the "
          r"64 MiB of memory available \(CRANKBENCH_MEMORY_LIMIT\)",),
         "a 100 000-mass chain: 6.5 min, then 'Unable to allocate 74.5 GiB'", env=_LIMIT),
    Case("predict_torsion_forced_response_beyond_the_memory_limit",
         ("predict", "torsion", "{model}", "--speeds", "1000000"), 2,
         (r"--speeds 1000000 × 24 orders × \d+ masses \(forced response\) would need",),
         env=_LIMIT),
    # -- unit slips -------------------------------------------------------------------------
    Case("predict_torsion_shear_modulus_in_gpa_without_unit",
         ("predict", "torsion", "{g81}", "--no-forced"), 0,
         (r"shaftline\.shear_modulus = 81 Pa: did you mean 81 GPa\?",),
         "modes at 0.00025 Hz, no warning"),
]


if __name__ == "__main__":
    for c in CASES:
        print(f"{c.name:55s} exit {c.status}  {' '.join(c.argv)}")
    print(f"{len(CASES)} bad command lines")
