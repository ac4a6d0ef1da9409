"""Raw rig exports through channel maps (measure.channelmap), against the exact truth.

Each file is written by ``measure.synth.rawrig.raw_rig`` from a closed-form shaft motion: a
60-2 wheel (square pick-up, tooth 57 a runt at 11 %, noise), a TDC mark 2 samples wide on a
drifting baseline, a pressure transducer ``V = 5 (0.00385 p[kPa] + 0.115)``. Checked: edges
per revolution, mean speed within 0.1 %, one TDC mark per revolution, pressure within 0.5 %
of its peak, provenance; and the errors of bad maps.
"""

import warnings

import numpy as np
import pytest

from crankbench.analysis.speedref import speed_reference
from crankbench.measure import io
from crankbench.measure.channelmap import ChannelMap
from crankbench.measure.record import RecordWarning
from crankbench.measure.synth.rawrig import DIALECTS, raw_rig
from crankbench.predict.errors import ConfigError, RecordError


def _read(rig, **kwargs):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rec = io.read(rig.path, map=rig.map_path, **kwargs)
    return rec, [str(w.message) for w in caught if issubclass(w.category, RecordWarning)]


def _check_truth(rec, rig, *, per_rev=58.0):
    tr = rig.truth
    crank = rec["crank"].values
    inner = (tr["edges"] > 1e-3) & (tr["edges"] < tr["time"][-1] - 1e-3)
    near = np.abs(crank[:, None] - tr["edges"][inner][None, :]).min(axis=0)
    assert near.max() < 2.0 / tr["fs"]                     # every true edge found
    assert rec["crank"].attrs["missing_teeth"] == 2
    assert "edges, 58.00 per revolution" in rec["crank"].attrs["decoding"]
    # mean speed within 0.1 % over the record (speed reference at every pressure sample)
    rpm = speed_reference(rec, "pressure")
    interior = (tr["time"] > 0.1) & (tr["time"] < tr["time"][-1] - 0.1)
    assert abs(rpm[interior].mean() / tr["speed_rpm"][interior].mean() - 1) < 1e-3
    # one TDC mark per revolution (or cycle), at the true times
    np.testing.assert_allclose(rec["tdc"].values, tr["tdc"], atol=1.5 / tr["fs"])
    # calibrated pressure within 0.5 % of its peak
    p = rec["pressure"].values
    assert np.max(np.abs(p - tr["pressure_pa"])) < 0.005 * tr["pressure_pa"].max()
    assert rec["pressure"].attrs["units"] == "Pa"
    assert rec["pressure"].attrs["location"] == "cylinder 1"
    del per_rev


@pytest.mark.parametrize("dialect", [d for d in DIALECTS if d != "xlsx"])
def test_every_text_dialect_imports_to_the_truth(dialect, tmp_path):
    rig = raw_rig(tmp_path, dialect=dialect, duration=0.45)
    rec, notes = _read(rig)
    _check_truth(rec, rig)
    assert rec["crank"].attrs["runt_teeth"] == [57]
    assert any("channel 'crank' (column 1" in n and "tooth 57" in n and "is a runt pulse" in n
               for n in notes), notes


def test_spreadsheet_encoder_tdc_and_pressure(tmp_path):
    """The gasoline-engine case: a 360-line encoder, a TDC mark and pressure at 71 kHz in a
    workbook (sheet 'Data', names and units rows)."""
    rig = raw_rig(tmp_path, dialect="xlsx", fs=71_000.0, duration=0.1, speed_rpm=(2400, 2400),
                  pulses_per_rev=360, missing_teeth=0, runt_teeth=(), noise_rms=0.01)
    rec, _ = _read(rig)
    crank = rec["crank"].values
    assert rec["crank"].attrs["missing_teeth"] == 0
    # 360 edges per revolution: 2400 rpm for 0.1 s = 4 revolutions
    revs = 2400 / 60 * (crank[-1] - crank[0])
    assert (crank.size - 1) / revs == pytest.approx(360.0, rel=2e-3)
    np.testing.assert_allclose(rec["tdc"].values, rig.truth["tdc"], atol=1.5 / 71_000.0)
    rpm = speed_reference(rec, "pressure")
    assert rpm.mean() == pytest.approx(2400.0, rel=1e-3)


def test_missing_teeth_left_out_is_inferred(tmp_path):
    rig = raw_rig(tmp_path, duration=0.45, runt_teeth=(), map_missing_teeth=None)
    rec, _ = _read(rig)
    assert rec["crank"].attrs["missing_teeth"] == 2
    _check_truth(rec, rig)


def test_per_cycle_mark_and_runt_after_the_gap(tmp_path):
    rig = raw_rig(tmp_path, duration=0.5, per_cycle=True, runt_teeth=(0,),
                  speed_rpm=(1200.0, 1800.0))
    rec, _ = _read(rig)
    assert rec["tdc"].attrs["speed_ratio"] == 0.5
    assert rec["crank"].attrs["runt_teeth"] == [0]
    np.testing.assert_allclose(rec["tdc"].values, rig.truth["tdc"], atol=1.5 / 100_000.0)


def test_ringing_pickup_and_time_column(tmp_path):
    rig = raw_rig(tmp_path, dialect="comma", duration=0.45, ringing=0.25, time_column=True)
    rec, _ = _read(rig)
    tr = rig.truth
    crank = rec["crank"].values
    assert crank.size == tr["edges"].size
    # the pick-up chain delays every edge alike: intervals exact to a tenth of a sample; the
    # runt tooth's, timed at its own half height, within half a sample (the ringing left by
    # the tooth before it is 6 % of its small step)
    err = np.abs(np.diff(crank) - np.diff(tr["edges"])) * tr["fs"]
    runt = np.flatnonzero(tr["teeth"] == 57)
    near_runt = np.zeros(err.size, bool)
    near_runt[np.clip(np.r_[runt - 1, runt], 0, err.size - 1)] = True
    assert err[~near_runt].max() < 0.1
    assert err[near_runt].max() < 0.5


def test_provenance_survives_import_to_h5(tmp_path):
    rig = raw_rig(tmp_path, duration=0.3)
    rec, _ = _read(rig)
    assert rec.attrs["raw_source"] == rig.path.name
    assert rec.attrs["raw_sha256"] == io.sha256_of(rig.path)
    assert rec.attrs["channel_map"] == rig.map_path.read_text()
    out = tmp_path / "out.h5"
    io.write(rec, out)
    back = io.read(out)
    for key in ("raw_source", "raw_sha256", "channel_map", "channel_map_sha256"):
        assert back.attrs[key] == rec.attrs[key]
    assert io.source_sha256(back) == io.sha256_of(out) != back.attrs["raw_sha256"]
    np.testing.assert_array_equal(back["crank"].values, rec["crank"].values)
    assert back["crank"].attrs["pulses_per_rev"] == 60


def test_map_on_a_record_file_decodes_its_raw_channels(tmp_path):
    """A .h5 record holding the raw wheel voltage: the map names channels instead of
    columns, and decodes the wheel there too."""
    rig = raw_rig(tmp_path, duration=0.3, runt_teeth=())
    rec, _ = _read(rig)
    raw = io.read(rig.path, map={"source": dict(rig.map["source"]),
                                 "channel": {"v": {"column": 1, "units": "V"}}})
    h5 = tmp_path / "raw.h5"
    io.write(raw, h5)
    back = io.read(h5, map={"channel": {"wheel": {"column": "v", "role": "wheel",
                                                  "pulses_per_rev": 60}}})
    np.testing.assert_allclose(back["wheel"].values, rec["crank"].values, atol=1e-12)


# ------------------------------------------------------------------------------ bad maps
def _write(tmp_path, text, name="map.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.mark.parametrize("text, pattern", [
    ('[channel.p]\ncolumn = 1\nunits = "bar"\nsacle = 2.0\n',
     r"channel.p.sacle is not a known key \(did you mean 'scale'\?\)"),
    ('[source]\nsampel_rate = 1000.0\n[channel.p]\ncolumn = 1\nunits = "bar"\n',
     r"source.sampel_rate is not a known key \(did you mean 'sample_rate'\?\)"),
    ('[channel.p]\ncolumn = 0\nunits = "bar"\n', r"channel.p.column = 0 must be >= 1"),
    ('[channel.p]\ncolumn = 1\n', r"channel.p.units is missing \(required\)"),
    ('[channel.p]\ncolumn = 1\nunits = "bar"\nscale = 0.0\n', r"channel.p.scale = 0 would make"),
    ('[channel.w]\ncolumn = 1\nrole = "wheel"\n', r"channel.w.pulses_per_rev is missing"),
    ('[channel.w]\ncolumn = 1\nrole = "wheeel"\npulses_per_rev = 60\n',
     r"channel.w.role = 'wheeel' is not one of 'wheel', 'tdc' \(did you mean 'wheel'\?\)"),
    ('[channel.w]\ncolumn = 1\nrole = "wheel"\npulses_per_rev = 60\nper_cycle = true\n',
     r"channel.w.per_cycle applies to role = 'tdc' marks"),
    ('[channel.p]\ncolumn = 1\nunits = "bar"\npulses_per_rev = 60\n',
     r"channel.p.pulses_per_rev applies only to pulse channels"),
    ('[source]\nsample_rate = 1e3\ntime_column = 1\n[channel.p]\ncolumn = 2\nunits = "V"\n',
     r"source.sample_rate and time_column are both given"),
    ('[source]\ndelimiter = "colon"\n[channel.p]\ncolumn = 2\nunits = "V"\n',
     r"source.delimiter = 'colon' is not one of comma, tab"),
    ('[channel.a]\ncolumn = 1\nunits = "V"\n[channel.b]\ncolumn = 1\nunits = "V"\n',
     r"channel.b.column = 1 is also the column of channel.a"),
    ('description = "x"\n', r"channel is missing: a map names at least one channel"),
    ('[channel.a]\ncolumn = 1\nunits = "g"\nposition = [0.1, 0.2]\n',
     r"channel.a.position has 2 values, expected 3"),
    ('[channel.a]\ncolumn = 1\nunits = "g"\nposition = [0.1, 0.2, 0.3]\nmount = "FL"\n',
     r"channel.a.mount and 'position' both place the sensor"),
    ('[channel.a]\ncolumn = 1\nunits = "g"\ninstrument_damping_ratio = 0.6\n',
     r"channel.a.instrument_damping_ratio needs instrument_natural_frequency"),
    ('[channel.w]\ncolumn = 1\nrole = "wheel"\npulses_per_rev = 60\nmount = "FL"\n',
     r"channel.w.mount places a vibration sensor; it does not apply to pulse channels"),
])
def test_bad_map_keys_are_named_like_model_files(tmp_path, text, pattern):
    path = _write(tmp_path, text)
    with pytest.raises(ConfigError, match=pattern) as info:
        ChannelMap.from_toml(path)
    assert str(path) in str(info.value)


def test_column_not_in_the_file_lists_the_columns(tmp_path):
    data = tmp_path / "d.csv"
    data.write_text("Time [s];Pressure [bar];Crank [V]\n0;1;0\n0,001;1,1;5\n0,002;1,2;0\n"
                    "0,003;1,3;5\n0,004;1,4;0\n")
    path = _write(tmp_path, '[channel.p]\ncolumn = "Presure"\nunits = "bar"\n')
    with pytest.raises(ConfigError, match=r"map.toml \(for d.csv\): channel.p.column = "
                                          r"'Presure' is not a column of d.csv \(did you mean "
                                          r"'Pressure \[bar\]'\?\); columns: 'Time \[s\]'"):
        io.read(data, map=path)
    path = _write(tmp_path, '[channel.p]\ncolumn = 7\nunits = "bar"\n')
    with pytest.raises(ConfigError, match=r"channel.p.column = 7: d.csv has only 3 column\(s\) "
                                          r"\(semicolon-separated, decimal comma, 1 header row"):
        io.read(data, map=path)


def test_headerless_file_without_map_says_what_cannot_be_inferred(tmp_path):
    rig = raw_rig(tmp_path, duration=0.05, dialect="tab_headerless")
    with pytest.raises(RecordError, match=r"rig.txt: no header row \(read as tab-separated, "
                                          r"decimal point, no header row, UTF-8\): channel names "
                                          r"and units cannot be inferred for its 3 column\(s\); "
                                          r"give a channel map"):
        io.read(rig.path)
    # the map gives it: and with no time column and no sample rate, that is named
    path = _write(tmp_path, '[channel.p]\ncolumn = 3\nunits = "V"\n')
    with pytest.raises(RecordError, match=r"no time axis: the map gives neither \[source\] "
                                          r"sample_rate nor time_column"):
        io.read(rig.path, map=path)


def test_undecodable_pulse_column_names_file_column_and_what_was_seen(tmp_path):
    rig = raw_rig(tmp_path, duration=0.2, runt_teeth=())
    path = _write(tmp_path, '[source]\nsample_rate = 100000.0\ndelimiter = "tab"\n'
                            '[channel.w]\ncolumn = 3\nrole = "wheel"\npulses_per_rev = 60\n'
                            'missing_teeth = 2\n')
    with pytest.raises(RecordError, match=r"rig.txt: channel 'w' \(column 3\): no gap of 2 "
                                          r"missing teeth found in 3 edges, 0.1 revolutions of a "
                                          r"60-pitch wheel"):
        io.read(rig.path, map=path)


def test_map_places_vibrograph_sensors_for_the_mount_model(tmp_path):
    """``mount``/``position``/instrument keys reach the channel attrs, and the vibrograph
    comparison places the sensors from them: at the named mount's position (from the engine
    model, independent of the map) or at the given coordinates (quantity strings in mm)."""
    from crankbench.analysis.vibrograph import place_sensors
    from crankbench.predict.mounts import MountedEngine

    mounted = MountedEngine.from_toml("sample_data/engines/i4.toml")
    mount = mounted.mounts[0]
    fs, n = 2000.0, 4000
    t = np.arange(n) / fs
    data = np.column_stack([0.1 * np.sin(2 * np.pi * 50 * t), 0.2 * np.cos(2 * np.pi * 50 * t)])
    raw = tmp_path / "block.txt"
    np.savetxt(raw, data, delimiter="\t", fmt="%.6f")
    cmap = tmp_path / "block_map.toml"
    cmap.write_text(f"""
[source]
sample_rate = {fs}
[channel.acc_mount]
column = 1
units = "g"
direction = "z"
mount = "{mount.name}"
[channel.acc_pos]
column = 2
units = "g"
direction = "y"
position = ["350 mm", "-420 mm", "-300 mm"]
instrument_natural_frequency = "12 Hz"
instrument_damping_ratio = 0.6
""")
    rec = io.read(raw, map=cmap)
    assert rec["acc_mount"].attrs["mount"] == mount.name
    assert rec["acc_pos"].attrs["position"] == pytest.approx([0.35, -0.42, -0.30], abs=1e-12)
    assert rec["acc_pos"].attrs["instrument_natural_frequency"] == 12.0
    assert rec["acc_pos"].attrs["instrument_damping_ratio"] == 0.6
    np.testing.assert_allclose(rec["acc_mount"].values, 9.80665 * data[:, 0], rtol=1e-5,
                               atol=1e-5)
    sensors, skipped = place_sensors(rec, mounted)
    assert not skipped
    by = {s.channel: s for s in sensors}
    np.testing.assert_allclose(by["acc_mount"].position, mount.position, atol=0)
    assert by["acc_mount"].placed_by == f"mount {mount.name}"
    np.testing.assert_allclose(by["acc_pos"].position, [0.35, -0.42, -0.30], atol=1e-12)
    np.testing.assert_allclose(by["acc_pos"].direction, [0.0, 1.0, 0.0], atol=0)
