"""Crank-angle-domain indicating exports (measure.readers.angle_table,
analysis.pressure_cycles, ``crankbench pressure`` on them) against the time-domain analysis
of the same cycles and against the synthetic bench's truth.

The bench record (I4, 2000 rpm, 10 bar IMEP varying 2 % rms from cycle to cycle, cylinder 1
at 50 kHz with an unknown offset, drift and 0.02 bar noise; 60-2 wheel and TDC mark on cylinder 1's crank) is analysed in the
time domain; its cycles are then written as an indicating system would export them — long and
wide layouts, English and German dialects, axes -360..359.9 with the firing TDC at 0, 0..720
with it at 360 (closing point included) and 0..719.9 with it at 0, a single averaged cycle —
with the transducer's level lost again (0.5 bar low plus a drift of 0.01 bar per cycle,
0.17 bar/s) and
pressures printed to 0.1 mbar. The angle-domain analysis must give back the time-domain
figures (the same cycles) and the truth within the accuracy table of analysis.pressure.
"""

from pathlib import Path

import numpy as np
import pytest

from crankbench.analysis.cli import main
from crankbench.analysis.pressure import indicator_analysis
from crankbench.analysis.pressure_cycles import indicator_analysis_cycles
from crankbench.measure.readers.angle_table import is_angle_table, read_angle_table
from crankbench.measure.synth.pressure import pressure_truth
from crankbench.measure.synth.run import synthesize
from crankbench.predict.errors import AnalysisError, RecordError

from pressure_scenes import bench_scene

ROOT = Path(__file__).resolve().parents[2]
I4 = ROOT / "sample_data/engines/i4.toml"


def _scene(path):
    path.write_text(bench_scene(
        name="I4 steady, cylinder pressure", seed=5, pressure_rate=50000.0,
        profile='kind = "steady"\nspeed_rpm = 2000.0\nduration = 0.55',
        extra="offset = -0.6e5\ndrift_rate = 1.0e4\ncycle_variation = 0.02\n"))
    return path


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("pca")
    run = synthesize(_scene(tmp / "scene.toml"))
    r = indicator_analysis(run.record, run.scene.engine)
    truth = pressure_truth(run.truth)["p_cyl1"]["cycles"]
    times = np.array([row["time_s"] for row in truth])
    rows = [truth[int(np.argmin(np.abs(times - t)))] for t in r.cycle_time]
    raw = r.pressure / 1e5 - 0.5 + 0.01 * (np.arange(r.n_cycles)[:, None]
                                           + (np.rad2deg(r.crank_angle)[None, :] + 360) / 720)
    return {"tmp": tmp, "engine": run.scene.engine, "time": r, "truth": rows, "raw": raw}


def _fmt(v, comma):
    text = f"{v:.4f}"
    return text.replace(".", ",") if comma else text


def write_long(path, b, *, header="Cycle;CA [deg];P1 [bar];n [rpm]", comma=False,
               firing_at=0.0, closed=False, cycle_col=True, speed=True, tdc_late=0.0):
    """Long layout; the file's angle = ψ + ``firing_at`` − ``tdc_late`` (the file's zero
    ``tdc_late`` deg after the true TDC)."""
    r, raw = b["time"], b["raw"]
    deg = np.rad2deg(r.crank_angle) + firing_at - tdc_late
    lines = [header]
    for k in range(r.n_cycles):
        vals = list(raw[k])
        angles = list(deg)
        if closed:                               # 0..720 inclusive: the next cycle's first
            vals.append(raw[k + 1][0] if k + 1 < r.n_cycles else raw[k][0])
            angles.append(deg[-1] + 0.1)
        for a, v in zip(angles, vals):
            angle = f"{a:.1f}".replace(".", ",") if comma else f"{a:.1f}"
            cells = ([str(k + 1)] if cycle_col else []) + [angle, _fmt(v, comma)]
            if speed:
                cells.append(_fmt(r.speed_rpm[k], comma))
            lines.append(";".join(cells))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def write_wide_tdc_at_start(path, b):
    """Wide layout, 0..719.9 deg with the firing TDC at 0: file cycle j runs from firing TDC
    j - 1 (time-domain cycle j - 1) to the next, so N cycles hold N - 1 whole firing cycles."""
    raw = b["raw"]
    n = raw.shape[1] // 2
    cols = [np.concatenate([raw[k, n:], raw[k + 1, :n]]) for k in range(raw.shape[0] - 1)]
    deg = np.arange(2 * n) * 0.1
    lines = ["CA [deg]," + ",".join(f"cycle {k + 1} [bar]" for k in range(len(cols)))]
    lines += [f"{deg[j]:.1f}," + ",".join(f"{c[j]:.4f}" for c in cols) for j in range(2 * n)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _compare(a, b, *, first=1):
    """The angle-domain result ``a`` against the time-domain one on the same cycles."""
    r = b["time"]
    idx = np.asarray(a.cycle_number) - 1
    assert list(a.cycle_number) == list(range(first, first + a.n_cycles))
    assert np.max(np.abs(a.imep_net / r.imep_net[idx] - 1)) < 1e-4
    assert np.max(np.abs(a.pmep - r.pmep[idx])) < 60.0    # Pa: 6e-5 of IMEP (drift re-pegged)
    assert np.max(np.abs(a.peak_pressure / r.peak_pressure[idx] - 1)) < 1e-4
    assert np.max(np.abs(np.rad2deg(a.peak_angle - r.peak_angle[idx]))) < 0.01
    sub = np.std(r.imep_net[idx], ddof=1) / abs(np.mean(r.imep_net[idx])) * 100
    assert abs(a.cov_imep - sub) < 0.01
    if idx.size == r.n_cycles:
        assert abs(a.heat_release.total / r.heat_release.total - 1) < 1e-3
        assert abs(a.heat_release.mfb_deg[50] - r.heat_release.mfb_deg[50]) < 0.05
    _truth(a, [b["truth"][i] for i in idx])


def _truth(a, rows):
    """Against the bench's truth: the 'noise 0.03 bar' row of analysis.pressure's table
    (mean IMEP 0.03 %, peak 0.03 %, angle 0.06 deg; per cycle IMEP 0.15 %)."""
    imep = np.array([x["imep_net_pa"] for x in rows])
    peak = np.array([x["peak_pressure_pa"] for x in rows])
    angle = np.array([x["peak_angle_deg"] for x in rows])
    assert abs(np.mean(a.imep_net) / np.mean(imep) - 1) < 3e-4
    assert abs(a.mean["peak_pressure"] / np.mean(peak) - 1) < 3e-4
    assert abs(np.rad2deg(a.mean["peak_angle"]) - np.mean(angle)) < 0.06
    assert np.max(np.abs(a.imep_net / imep - 1)) < 1.5e-3
    if imep.size > 2:                          # the bench's cycle-to-cycle variation (~1.5 %)
        cov = 100 * np.std(imep, ddof=1) / np.mean(imep)
        assert cov > 1.0 and abs(a.cov_imep - cov) < 0.05


def test_long_layout_english_matches_time_domain_and_truth(bench):
    path = write_long(bench["tmp"] / "long.csv", bench)
    assert is_angle_table(path)
    ds = read_angle_table(path)
    assert dict(ds.sizes) == {"cycle": bench["time"].n_cycles, "crank_angle": 7200}
    assert ds["P1"].attrs["cylinder"] == 1 and ds.attrs["cycle_deg"] == 720.0
    a = indicator_analysis_cycles(ds, bench["engine"])
    _compare(a, bench)
    assert np.max(np.abs(a.speed_rpm - bench["time"].speed_rpm)) < 0.01
    assert "firing TDC at 0 deg" in a.tdc["phase"]


def test_long_layout_german_0_720_closed_firing_at_360_no_cycle_column_no_speed(bench):
    """Decimal commas, 'KW [°KW]', cycles found where the angle wraps, the closing 720 deg
    point dropped, the firing TDC found at 360 deg; no speed: the result says so."""
    path = write_long(bench["tmp"] / "de.csv", bench, header="KW [°KW];Zylinderdruck Zyl1 [bar]",
                      comma=True, firing_at=360.0, closed=True, cycle_col=False, speed=False)
    ds = read_angle_table(path)
    assert ds.attrs["closing_point_dropped"] == 1 and ds.sizes["crank_angle"] == 7200
    a = indicator_analysis_cycles(ds, bench["engine"])
    _compare(a, bench)
    assert "firing TDC at 360 deg" in a.tdc["phase"]
    assert np.all(np.isnan(a.speed_rpm)) and a.summary()["speed_rpm"] is None


def test_wide_layout_firing_tdc_at_start_gives_one_cycle_less(bench):
    path = write_wide_tdc_at_start(bench["tmp"] / "wide.csv", bench)
    ds = read_angle_table(path)
    assert ds.attrs["layout"] == "wide" and ds.sizes["cycle"] == bench["time"].n_cycles - 1
    a = indicator_analysis_cycles(ds, bench["engine"], speed_rpm=2000.0)
    assert a.n_cycles == bench["time"].n_cycles - 2          # the first half cycle is lost
    _compare(a, bench, first=2)
    assert abs(np.mean(a.speed_rpm) - 2000.0) < 1e-9


def test_averaged_single_cycle(bench):
    """One averaged cycle (what many systems export by default), in kPa, 'Kurbelwinkel', its
    level 0.5 bar low: peak, IMEP and heat release of the mean cycle as the time-domain
    analysis gives them."""
    r = bench["time"]
    mean = (r.mean_pressure / 1e5 - 0.5) * 100.0
    deg = np.rad2deg(r.crank_angle)
    path = bench["tmp"] / "avg.txt"
    path.write_text("Kurbelwinkel [deg]\tp_zyl [kPa]\n" + "".join(
        f"{a:.1f}\t{v:.3f}\n" for a, v in zip(deg, mean)), encoding="utf-8")
    a = indicator_analysis_cycles(path, bench["engine"])
    assert a.n_cycles == 1 and np.isnan(a.cov_imep)
    assert abs(a.imep_net[0] / np.mean(r.imep_net) - 1) < 1e-4
    assert abs(a.mean["peak_pressure"] / r.mean["peak_pressure"] - 1) < 1e-4
    assert abs(np.rad2deg(a.mean["peak_angle"] - r.mean["peak_angle"])) < 0.01
    assert abs(a.heat_release.total / r.heat_release.total - 1) < 1e-3
    _truth(a, [{k: np.mean([x[k] for x in bench["truth"]]) for k in
                ("imep_net_pa", "peak_pressure_pa", "peak_angle_deg")}])


def test_tdc_error_on_the_axis_is_found_and_corrected_as_an_angle_shift(bench):
    """The export's zero 1 deg after the true TDC (the system's TDC offset wrong): net IMEP
    about 4 % low and warned; with tdc_correction the shift (taking the edge samples from the
    neighbouring cycles) brings IMEP back within the table's 0.15 % ('TDC 1 deg,
    tdc_correction') of the truth."""
    path = write_long(bench["tmp"] / "late.csv", bench, tdc_late=1.0)
    ds = read_angle_table(path)
    plain = indicator_analysis_cycles(ds, bench["engine"])
    imep = np.mean([x["imep_net_pa"] for x in bench["truth"]])
    assert -4.5 < 100 * (np.mean(plain.imep_net) / imep - 1) < -3.0
    assert any("thermodynamic TDC lies" in w for w in plain.warnings)
    fixed = indicator_analysis_cycles(ds, bench["engine"], tdc_correction=True)
    assert fixed.n_cycles == bench["time"].n_cycles
    assert abs(100 * (np.mean(fixed.imep_net) / imep - 1)) < 0.15
    assert abs(fixed.tdc["applied_deg"] + 1.0) < 0.15


def test_cli_and_map(bench, capsys):
    path = write_long(bench["tmp"] / "cli.csv", bench)
    assert main(["pressure", str(path), "--model", str(I4)]) == 0
    out = capsys.readouterr().out
    imep = np.mean(bench["time"].imep_net) / 1e5
    assert f"IMEP net / gross   {imep:.4g}" in out and "cycles at 2000.0 rpm" in out
    wide = write_wide_tdc_at_start(bench["tmp"] / "wide_map.csv", bench)
    cmap = bench["tmp"] / "map.toml"
    cmap.write_text('[source]\nangle_column = 1\nlayout = "wide"\nfiring_tdc_deg = 0.0\n'
                    '[channel.p_cyl1]\ncolumn = 2\nunits = "bar"\nlocation = "cylinder 1"\n')
    assert main(["pressure", str(wide), "--model", str(I4), "--map", str(cmap), "--json"]) == 0
    import json

    s = json.loads(capsys.readouterr().out)["channels"]["p_cyl1"]
    assert s["cycles"] == bench["time"].n_cycles - 2 and s["speed_rpm"] is None
    assert "(given)" in s["tdc"]["phase"]
    assert abs(s["imep_net_bar"] / (np.mean(bench["time"].imep_net[1:-1]) / 1e5) - 1) < 1e-4


def test_sample_file_is_its_generators_and_matches_its_time_domain_source():
    """sample_data/raw/indicating_ca.csv is what make_indicating.py writes (3 cycles at 1 deg
    of the sample scene, German dialect, firing TDC at 360, 0.6 bar low), and its analysis
    gives the time-domain analysis's cycles back."""
    import runpy

    gen = runpy.run_path(str(ROOT / "sample_data/raw/make_indicating.py"))
    r = gen["source"]()
    path = ROOT / "sample_data/raw/indicating_ca.csv"
    assert gen["text"](r) == path.read_text(encoding="utf-8")
    ds = read_angle_table(path)
    assert list(ds["cycle"].values) == [101, 102, 103]
    a = indicator_analysis_cycles(ds, I4)
    assert list(a.cycle_number) == [101, 102, 103]
    assert "firing TDC at 360 deg" in a.tdc["phase"]
    assert np.max(np.abs(a.speed_rpm - r.speed_rpm)) < 0.05
    assert np.max(np.abs(a.imep_net / r.imep_net - 1)) < 1e-4
    assert np.max(np.abs(a.peak_pressure / r.peak_pressure - 1)) < 1e-4


# ------------------------------------------------------------------------------ bad inputs
def _table(path, text):
    path.write_text(text, encoding="utf-8")
    return path


def _rows(angles, cycles=(1, 2), value=lambda c, a: 1.0 + c):
    return "".join(f"{c};{a:g};{value(c, a)}\n" for c in cycles for a in angles)


@pytest.mark.parametrize("case, text, match", [
    ("uneven step", "Cycle;CA [deg];P1 [bar]\n" + _rows(
        [a for a in np.arange(-360.0, 360.0, 1.0) if a != 17.0] + [360.0]),
     "uneven crank-angle step at 16 -> 18 deg"),
    ("missing rows", "Cycle;CA [deg];P1 [bar]\n" + _rows(np.arange(-360.0, 360.0, 1.0))
     + _rows(np.arange(-360.0, 300.0, 1.0), cycles=(3,)), "cycle 3 has 660 rows"),
    ("span", "Cycle;CA [deg];P1 [bar]\n" + _rows(np.arange(0.0, 500.0, 1.0)),
     "spans 500 deg; expected one whole cycle"),
    ("not together", "Cycle;CA [deg];P1 [bar]\n" + _rows(np.arange(-360.0, 360.0, 1.0),
                                                          cycles=(1, 2, 1)),
     r"rows of cycle\(s\) \[1\] are not together"),
    ("mixed units", "CA [deg];cycle 1 [bar];cycle 2 [kPa]\n" + "".join(
        f"{a:g};1.0;100.0\n" for a in np.arange(-360.0, 360.0, 1.0)),
     "cycle columns of the wide layout are in different units"),
    ("no pressure", "CA [deg];Temp [degC]\n" + "".join(
        f"{a:g};20\n" for a in np.arange(-360.0, 360.0, 1.0)), "no cylinder-pressure column"),
    ("empty cell", "CA [deg];P1 [bar]\n" + "".join(
        f"{a:g};{'' if a == 5 else 1.0}\n" for a in np.arange(-360.0, 360.0, 1.0)),
     r"P1 \[bar\]'\) is empty or not a number in data row 366"),
])
def test_bad_exports_are_refused_with_what_was_expected(tmp_path, case, text, match):
    path = _table(tmp_path / "bad.csv", text)
    with pytest.raises(RecordError, match=match):
        read_angle_table(path)


def test_360_deg_export_of_a_four_stroke_is_refused(tmp_path):
    path = _table(tmp_path / "rev.csv", "CA [deg];P1 [bar]\n" + "".join(
        f"{a:g};{1 + np.cos(np.deg2rad(a))}\n" for a in np.arange(-180.0, 180.0, 1.0)))
    ds = read_angle_table(path)
    assert ds.attrs["cycle_deg"] == 360.0
    with pytest.raises(AnalysisError, match="cycles span 360 deg, but the engine is a 4-stroke"):
        indicator_analysis_cycles(ds, I4)


def test_time_records_are_not_angle_tables_and_maps_say_where_angle_tables_go(tmp_path):
    from crankbench.measure.io import read

    t = _table(tmp_path / "t.csv", "time [s];KW [deg];p [bar]\n" + "".join(
        f"{i * 1e-3};{i};1.0\n" for i in range(50)))
    assert not is_angle_table(t)
    ca = _table(tmp_path / "ca.csv", "CA [deg];P1 [bar]\n" + "".join(
        f"{a:g};1.0\n" for a in np.arange(-360.0, 360.0, 1.0)))
    with pytest.raises(RecordError, match="angle_column makes it a crank-angle-domain"):
        read(ca, map={"source": {"angle_column": 1}, "channel": {"p": {"column": 2,
                                                                         "units": "bar"}}})


def test_reading_an_angle_export_as_a_time_record_points_to_the_pressure_command():
    """`crankbench info`/`import` of an angle-domain export: the refusal says what the file is
    and which command analyses it."""
    from crankbench import measure
    from crankbench.predict.errors import RecordError

    path = Path(__file__).resolve().parents[2] / "sample_data/raw/indicating_ca.csv"
    with pytest.raises(RecordError, match=r"is a crank angle.*crankbench pressure"):
        measure.read(path)
