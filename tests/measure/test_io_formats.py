"""Format-specific behaviour: files written by other tools, unit conversion at ingest, streaming.

Foreign files are built with each format's own library (not with our writers), so these tests
check our readers against the format as others write it.
"""

import datetime as dt
import json
import math

import numpy as np
import pytest
import xarray as xr

from crankbench.measure import io
from crankbench.measure.record import RecordWarning, make_record
from crankbench.predict.errors import RecordError

G0 = 9.80665
RPM = 2 * math.pi / 60


def test_foreign_csv_units_converted_and_rate_inferred(tmp_path):
    path = tmp_path / "bench.csv"
    t = np.arange(50) / 200.0
    rows = "\n".join(f"{a!r},{0.5 * i!r},{3000.0!r}" for i, a in enumerate(t.tolist()))
    path.write_text("# exported by a test bench\ntime [s],acc [g],speed (rpm)\n" + rows + "\n")
    rec = io.read(path)
    assert rec["acc"].attrs == {"units": "m/s^2", "quantity": "acceleration",
                                "sample_rate": pytest.approx(200.0, rel=1e-12)}
    assert rec["acc"].values[2] == pytest.approx(1.0 * G0, rel=1e-15)
    assert rec["speed"].attrs["quantity"] == "rotational_speed"
    assert rec["speed"].values[0] == pytest.approx(3000 * RPM, rel=1e-15)
    assert rec["speed"].dims == ("time",)


def test_foreign_csv_time_in_ms(tmp_path):
    path = tmp_path / "ms.csv"
    path.write_text("t [ms],p [bar]\n0,1\n0.5,2\n1.0,3\n")
    rec = io.read(path)
    np.testing.assert_allclose(rec["time"].values, [0, 5e-4, 1e-3])
    assert rec["p"].attrs["sample_rate"] == pytest.approx(2000.0)
    np.testing.assert_allclose(rec["p"].values, [1e5, 2e5, 3e5])


def test_foreign_tdms_waveform(tmp_path):
    import nptdms

    path = tmp_path / "ni.tdms"
    start = np.datetime64("2026-02-03T04:05:06.500000", "us")
    props = {"unit_string": "mm/s", "wf_increment": 1 / 2560.0, "wf_start_offset": 0.0,
             "wf_samples": 100, "wf_start_time": start}
    with nptdms.TdmsWriter(str(path)) as w:
        w.write_segment([
            nptdms.ChannelObject("Vibration", "vel", np.full(100, 2.0), properties=props),
            nptdms.ChannelObject("Speed", "n", np.full(10, 1500.0), properties={
                "unit_string": "rpm", "wf_increment": 0.1, "wf_start_offset": 0.0}),
        ])
    rec = io.read(path)
    assert rec["vel"].dims == ("time",) and rec["n"].dims == ("time_Speed",)
    assert rec["vel"].values[0] == pytest.approx(2e-3)
    assert rec["vel"].attrs["sample_rate"] == pytest.approx(2560.0)
    assert rec["n"].values[0] == pytest.approx(50 * math.pi)
    assert rec.attrs["start_time"] == "2026-02-03T04:05:06.500000+00:00"
    lazy = io.open(path, chunk_seconds=0.01)
    assert lazy["vel"].chunks == ((26, 26, 26, 22),)


def test_foreign_tdms_time_channel(tmp_path):
    import nptdms

    path = tmp_path / "logger.tdms"
    t = np.arange(20) / 50.0
    with nptdms.TdmsWriter(str(path)) as w:
        w.write_segment([nptdms.ChannelObject("g", "Time", t, properties={"unit_string": "s"}),
                         nptdms.ChannelObject("g", "p", np.ones(20),
                                              properties={"unit_string": "kPa"})])
    rec = io.read(path)
    assert list(rec.data_vars) == ["p"]
    np.testing.assert_array_equal(rec["time"].values, t)
    assert rec["p"].attrs["sample_rate"] == pytest.approx(50.0)
    assert rec["p"].values[0] == 1000.0


def test_foreign_mdf_two_rates(tmp_path):
    from asammdf import MDF, Signal

    path = tmp_path / "ecu.mf4"
    t_fast = np.arange(1000) / 1000.0
    t_slow = np.arange(10) / 10.0
    mdf = MDF(version="4.10")
    mdf.append([Signal(np.full(1000, 0.5, np.float32), t_fast, name="acc", unit="g")])
    mdf.append([Signal(np.full(10, 1200.0), t_slow, name="nmot", unit="1/min")])
    mdf.header.start_time = dt.datetime(2026, 4, 5, 6, 7, 8, tzinfo=dt.timezone.utc)
    mdf.save(str(path))
    mdf.close()
    rec = io.read(path)
    assert rec["acc"].dims == ("time",) and rec["nmot"].dims == ("time_nmot",)
    assert rec["acc"].dtype == np.float32
    assert rec["acc"].values[0] == np.float32(0.5 * G0)
    assert rec["nmot"].values[0] == pytest.approx(40 * math.pi)
    assert rec["nmot"].attrs["sample_rate"] == pytest.approx(10.0)
    assert rec.attrs["start_time"].startswith("2026-04-05T06:07:08")


def test_foreign_uff_ascii(tmp_path):
    import pyuff

    path = tmp_path / "modal.uff"
    x = np.arange(64) / 1024.0
    pyuff.UFF(str(path)).write_sets([dict(
        type=58, binary=0, id1="pt1 +z", id2="", id3="", id4="", id5="", func_type=1, func_id=1,
        ver_num=0, load_case_id=0, rsp_ent_name="pt1", rsp_node=1, rsp_dir=3,
        ref_ent_name="NONE", ref_node=0, ref_dir=0, ord_data_type=2, abscissa_spacing=1,
        abscissa_spec_data_type=17, abscissa_axis_units_lab="s", ordinate_spec_data_type=12,
        ordinate_axis_units_lab="g", orddenom_spec_data_type=0, z_axis_spec_data_type=0,
        z_axis_value=0.0, data=np.full(64, 0.25), x=x)], mode="overwrite")
    rec = io.read(path)
    assert list(rec.data_vars) == ["pt1 +z"]
    assert rec["pt1 +z"].attrs["sample_rate"] == pytest.approx(1024.0, rel=1e-5)
    assert rec["pt1 +z"].values[0] == pytest.approx(0.25 * G0, rel=1e-5)


def test_wav_pcm_with_scale(tmp_path):
    import soundfile as sf

    path = tmp_path / "rec.wav"
    frames = (np.array([0, 8192, -16384, 32767], dtype=np.int16)).reshape(-1, 1)
    sf.write(str(path), frames, 8000, subtype="PCM_16", format="WAV")
    side = {"crankbench_sidecar": 1, "attrs": {"start_time": "2026-01-01T00:00:00+00:00"},
            "channels": [{"name": "acc", "units": "g", "scale": 50.0,
                          "sensitivity": 100.0, "sensitivity_units": "mV/g"}]}
    (tmp_path / "rec.wav.json").write_text(json.dumps(side))
    rec = io.read(path)
    # PCM_16 sample k reads as k / 32768 of full scale; 50 g full scale
    expected = np.array([0, 8192, -16384, 32767]) / 32768 * 50 * G0
    np.testing.assert_allclose(rec["acc"].values, expected, rtol=1e-6)
    assert rec["acc"].attrs["sensitivity"] == pytest.approx(0.1 / G0)
    assert rec["acc"].attrs["sample_rate"] == 8000.0


def test_wav_header_rate_rounded_sidecar_exact(tmp_path):
    rec = make_record({"x": dict(data=np.zeros(100), sample_rate=1000.4, units="V")})
    io.write(rec, tmp_path / "odd.wav")
    back = io.read(tmp_path / "odd.wav")
    assert back["x"].attrs["sample_rate"] == 1000.4
    np.testing.assert_array_equal(back["time"].values, rec["time"].values)


def test_netcdf_from_xarray_with_foreign_units(tmp_path):
    path = tmp_path / "x.nc"
    t = np.arange(10) / 100.0
    xr.Dataset({"disp": ("time", np.ones(10), {"units": "um"})},
               coords={"time": ("time", t, {"units": "s"})}).to_netcdf(path, engine="h5netcdf")
    rec = io.read(path)
    assert rec["disp"].attrs["units"] == "m" and rec["disp"].values[0] == pytest.approx(1e-6)
    assert rec["disp"].attrs["sample_rate"] == pytest.approx(100.0)


def test_lazy_record_written_blockwise_and_streamed(tmp_path):
    import dask.array as da
    from xarray.indexes import RangeIndex

    from crankbench.measure.timeindex import is_implicit_time

    n, fs = 100_000, 1000.0
    data = da.arange(n, chunks=30_000, dtype=np.float32)
    ds = xr.Dataset({"x": (("time",), data, {"units": "V", "quantity": "voltage",
                                            "sample_rate": fs})})
    ds = ds.assign_coords(xr.Coordinates.from_xindex(
        RangeIndex.linspace(0.0, (n - 1) / fs, n, dim="time")))
    io.write(ds, tmp_path / "lazy.h5")
    lazy = io.open(tmp_path / "lazy.h5", chunk_seconds=20.0)
    assert is_implicit_time(lazy.xindexes["time"])   # no time array in memory
    total = sum(float(b.astype(np.float64).sum()) for _, b in io.iter_blocks(lazy, "x"))
    assert total == n * (n - 1) / 2
    assert float(lazy["time"][-1]) == pytest.approx((n - 1) / fs)


def test_failed_write_leaves_nothing(tmp_path):
    rec = make_record({"a,b": dict(data=np.zeros(3), sample_rate=1.0, units="V")})
    with pytest.raises(RecordError, match=r"channel name 'a,b' cannot be a CSV column header"):
        io.write(rec, tmp_path / "bad.csv")
    assert list(tmp_path.iterdir()) == []


def test_write_validates_record(tmp_path):
    rec = make_record({"a": dict(data=np.zeros(3), sample_rate=1.0, units="V")})
    rec["a"].attrs["units"] = "mV"
    with pytest.raises(RecordError, match=r"channel 'a' has non-SI units 'mV'"):
        io.write(rec, tmp_path / "r.h5")


def test_wav_without_sidecar_warns_once(tmp_path):
    import soundfile as sf

    sf.write(str(tmp_path / "plain.wav"), np.zeros(10, np.float32), 100, subtype="FLOAT")
    with pytest.warns(RecordWarning, match="no sidecar 'plain.wav.json'"):
        rec = io.read(tmp_path / "plain.wav")
    assert rec["ch1"].attrs["units"] == "1"


def test_uff_refuses_nan_instead_of_corrupting(tmp_path):
    x = np.ones(100)
    x[40:45] = np.nan
    rec = make_record({"acc": dict(data=x, sample_rate=100.0, units="g")}, allow_nonfinite=True)
    with pytest.raises(RecordError, match=r"drop.uff: channel 'acc' has NaN/inf samples \(1 "
                                          r"span\(s\), first samples 40..44\); UFF 58 cannot "
                                          r"store NaN/inf"):
        io.write(rec, tmp_path / "drop.uff")
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("ext", [".h5", ".csv", ".mf4", ".tdms", ".wav"])
def test_nan_dropouts_survive_every_other_format(ext, tmp_path):
    x = np.ones(100)
    x[40:45] = np.nan
    rec = make_record({"acc": dict(data=x, sample_rate=100.0, units="g")}, allow_nonfinite=True)
    io.write(rec, tmp_path / f"drop{ext}")
    with pytest.raises(RecordError, match=r"channel 'acc' has 5 NaN/inf sample"):
        io.read(tmp_path / f"drop{ext}")
    with pytest.warns(RecordWarning, match=r"0.4..0.44 s \(samples 40..44\)"):
        back = io.read(tmp_path / f"drop{ext}", allow_nonfinite=True)
    np.testing.assert_array_equal(np.isnan(back["acc"].values), np.isnan(x))


def test_clipping_flagged_on_read(tmp_path):
    t = np.arange(2000) / 1000.0
    x = np.clip(1.3 * np.sin(2 * np.pi * 5 * t), -0.8, 0.8)
    rec = make_record({"acc": dict(data=x, sample_rate=1000.0, units="m/s^2"),
                       "speed": dict(data=np.full(20, 3000.0), sample_rate=10.0, units="rpm")})
    io.write(rec, tmp_path / "clip.h5")
    with pytest.warns(RecordWarning, match=r"clip.h5: channel 'acc' looks clipped .*in 20 flat "
                                           r"run\(s\) at its extremes 0.8 / -0.8 m/s\^2") as rec_w:
        back = io.read(tmp_path / "clip.h5")
    assert len(rec_w) == 1, "the constant speed channel is not clipping"
    spans = back["acc"].attrs["clipped_spans_s"].reshape(-1, 2)
    # |1.3 sin(2 pi 5 t)| >= 0.8 from t = asin(0.8/1.3)/(2 pi 5) = 0.02109 s after each zero
    first = np.arcsin(0.8 / 1.3) / (2 * np.pi * 5)
    assert spans[0, 0] == pytest.approx(first, abs=1e-3)
    np.testing.assert_array_equal(back["acc"].values, x)   # kept as recorded
