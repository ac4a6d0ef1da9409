"""``crankbench predict lateral`` and ``crankbench balance`` end to end on the sample files."""

import json

import numpy as np
import pytest

from crankbench.analysis.cli import main
from crankbench.predict.lateral.toml import load_rotor


def test_predict_lateral_json_matches_closed_form(sample_data, capsys):
    """The pinned uniform shaft's first critical speed is (π/L)²√(EI/ρA) = 6123.46 rpm."""
    path = sample_data / "rotors" / "pinned_shaft.toml"
    assert main(["predict", "lateral", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    first = out["critical_speeds"][0]
    E, rho, d = 2.11e11, 7810.0, 0.05
    exact = np.pi**2 * np.sqrt(E * d**2 / 16 / rho) * 30 / np.pi
    assert first["speed_rpm"] == pytest.approx(exact, rel=1e-6)  # 20 elements: 4e-7
    assert {"natural_frequencies_at_rest", "campbell"} <= set(out)


def test_predict_lateral_text_and_unbalance(sample_data, capsys):
    assert main(["predict", "lateral", str(sample_data / "rotors" / "two_disk.toml"),
                 "--modes", "2"]) == 0
    text = capsys.readouterr().out
    assert "critical speeds" in text and "peak unbalance response" in text


def test_rotor_model_errors_name_file_and_key(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[rotor]\ntheory = 'timoshenko'\n[[rotor.shaft]]\nlength = 1.0\n"
                   "outer_diameter = -0.05\n", encoding="utf-8")
    assert main(["predict", "lateral", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "bad.toml: rotor.shaft[0].outer_diameter = -0.05 must be > 0" in err
    bad.write_text("[rotor]\n[[rotor.shaft]]\nlength = 1.0\nouter_diameter = 0.05\n"
                   "diameter = 0.05\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"rotor.shaft\[0\].diameter is not a known key "
                                         r"\(did you mean 'outer_diameter'\?\)"):
        load_rotor(bad)


def test_balance_cli_recovers_sample_unbalance(sample_data, capsys):
    """The sample runs were synthesised with 12.4 g at 43° and 8.7 g at 212° (see
    sample_data/balance/generate.py): the corrections are the opposite masses."""
    folder = sample_data / "balance"
    files = [str(folder / f) for f in ("initial.toml", "trial_plane1.toml", "trial_plane2.toml",
                                       "check.toml")]
    assert main(["balance", *files, "--check", "check", "--radius", "0.14", "--rotor-mass",
                 "88.2", "--max-speed", "3000", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    corr = out["corrections"]
    assert corr[0]["mass_kg"] == pytest.approx(0.0124, rel=1e-3)
    assert corr[0]["angle_deg"] == pytest.approx(223.0, abs=0.05)
    assert corr[1]["mass_kg"] == pytest.approx(0.0087, rel=1e-3)
    assert corr[1]["angle_deg"] == pytest.approx(32.0, abs=0.05)
    assert out["iso_21940_11"]["passed"] is True
    assert main(["balance", str(folder / "runs.csv"), "--json"]) == 0
    csv_out = json.loads(capsys.readouterr().out)
    assert csv_out["corrections"][0]["mass_kg"] == pytest.approx(0.0124, rel=1e-3)


def test_balance_cli_errors(sample_data, tmp_path, capsys):
    folder = sample_data / "balance"
    assert main(["balance", str(folder / "initial.toml")]) == 2
    assert "no trial runs" in capsys.readouterr().err
    bad = tmp_path / "runs.csv"
    bad.write_text("run,plane,amplitude\nx,1,2\n", encoding="utf-8")
    assert main(["balance", str(bad)]) == 2
    assert "missing column(s) ['measurement_plane', 'phase_deg']" in capsys.readouterr().err
    assert main(["balance", str(folder / "initial.toml"), str(folder / "trial_plane1.toml"),
                 "--check", "chek"]) == 2
    assert "--check 'chek' names no run" in capsys.readouterr().err
