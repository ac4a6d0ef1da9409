"""``crankbench import`` and ``--map`` on info/analyse, on raw rig exports with known truth."""

import json

import numpy as np
import pytest

from crankbench.analysis.cli import main
from crankbench.measure import io
from crankbench.measure.synth.rawrig import raw_rig


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    return raw_rig(tmp_path_factory.mktemp("rig"), dialect="semicolon_decimal_comma_bom",
                   duration=0.6, speed_rpm=(1200.0, 1500.0))


def test_import_writes_the_record_with_provenance_and_summarises_pulses(rig, tmp_path,
                                                                          capsys):
    out = tmp_path / "genset.h5"
    before = io.sha256_of(rig.path)
    assert main(["import", str(rig.path), "--map", str(rig.map_path), "-o", str(out),
                 "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert io.sha256_of(rig.path) == before                     # input untouched
    pulses = {p["channel"]: p for p in report["pulses"]}
    assert pulses["crank"]["edges_per_rev"] == pytest.approx(58.0, rel=2e-3)
    assert pulses["crank"]["runt_teeth"] == "57"
    assert pulses["crank"]["mean_speed_rpm"] == pytest.approx(1350.0, rel=2e-3)
    assert pulses["tdc"]["edges_per_rev"] == pytest.approx(1.0, rel=2e-3)
    assert any("tooth 57" in w for w in report["warnings"])
    rec = io.read(out)
    assert rec.attrs["raw_sha256"] == before
    assert rec.attrs["channel_map"] == rig.map_path.read_text()
    # refused: existing output without --overwrite, output onto an input
    assert main(["import", str(rig.path), "--map", str(rig.map_path), "-o", str(out)]) == 2
    assert "exists" in capsys.readouterr().err
    assert main(["import", str(rig.path), "--map", str(rig.map_path), "-o",
                 str(rig.map_path), "--overwrite"]) == 2
    assert "is the input" in capsys.readouterr().err


def test_info_and_analyse_read_raw_text_through_the_map(rig, capsys):
    assert main(["info", str(rig.path), "--map", str(rig.map_path), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    names = [c["name"] for c in info["channels"]]
    assert names == ["pressure", "crank_raw", "crank", "tdc"]
    # the order track of the pressure channel uses the decoded wheel as speed source
    assert main(["analyse", str(rig.path), "--map", str(rig.map_path), "--channel", "pressure",
                 "--orders", "0.5,1", "--revolutions", "2", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    speed = np.asarray(res["tracks"]["speed_rpm"])
    assert speed.min() > 1190 and speed.max() < 1510


def test_analyse_streams_through_the_map_too(rig, capsys, monkeypatch):
    from crankbench.analysis.commands import analyse as command

    monkeypatch.setattr(command, "STREAM_BYTES", 0)          # take the streaming path
    assert main(["analyse", str(rig.path), "--map", str(rig.map_path), "--channel", "pressure",
                 "--orders", "1", "--revolutions", "2", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    speed = np.asarray(res["tracks"]["speed_rpm"])
    assert speed.min() > 1190 and speed.max() < 1510


def test_bad_map_is_one_line_naming_map_and_key(rig, tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(rig.map_path.read_text().replace("pulses_per_rev", "pulses_per_revs"))
    assert main(["import", str(rig.path), "--map", str(bad), "-o", str(tmp_path / "x.h5")]) == 2
    err = capsys.readouterr().err
    assert "bad.toml: channel.crank.pulses_per_rev is missing (required); found " \
           "'pulses_per_revs' — a misspelling of 'pulses_per_rev'?" in err
