"""Tables whose time column is a clock time or a date-time (``2026-11-24 10:00:00.301``,
``24.11.2026 10:00:00,301``, ``10:00:00.301``), as test-bench loggers write them: read as
seconds from the first stamp, the first stamp kept as the record's start time.

The stamps are written here with :mod:`datetime` from known seconds (the ground truth), not
with the pandas parser under test."""

import datetime as dt
import json
import logging

import numpy as np
import pytest

from crankbench.measure import read
from crankbench.measure.readers.text import sniff
from crankbench.predict.errors import ConfigError, RecordError

START = dt.datetime(2026, 11, 24, 10, 0, 0, 301000)


def _stamps(t, fmt, *, start=START, cut=0, tz=None):
    """Stamps of the times ``t`` (s) from ``start``, ``cut`` trailing digits dropped."""
    out = []
    for a in t:
        # whole microseconds, rounded half away from zero: the true stamp of a µs clock
        stamp = start + dt.timedelta(microseconds=int(round(float(a) * 1e6)))
        text = stamp.strftime(fmt)
        out.append((text[:-cut] if cut else text) + (tz or ""))
    return out


def _write(path, header, stamps, columns, *, sep=",", decimal="."):
    rows = [sep.join(header)]
    for i, stamp in enumerate(stamps):
        cells = [f"{c[i]:.6f}".replace(".", decimal) for c in columns]
        rows.append(sep.join([stamp] + cells))
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")


DIALECTS = {
    # name: (strftime, digits cut, tz suffix, delimiter, decimal, start attr)
    "iso_space_us": ("%Y-%m-%d %H:%M:%S.%f", 0, None, ",", ".",
                     {"start_time": "2026-11-24T10:00:00.301000"}),
    "iso_T_offset": ("%Y-%m-%dT%H:%M:%S.%f", 0, "+01:00", ",", ".",
                     {"start_time": "2026-11-24T10:00:00.301000+01:00"}),
    "european_ms": ("%d.%m.%Y %H:%M:%S,%f", 3, None, ";", ",",
                    {"start_time": "2026-11-24T10:00:00.301000"}),
    "time_of_day_tab": ("%H:%M:%S.%f", 0, None, "\t", ".",
                        {"start_time_of_day": "10:00:00.301000"}),
    "ymd_slash_pipe": ("%Y/%m/%d %H:%M:%S.%f", 3, None, "|", ".",
                       {"start_time": "2026-11-24T10:00:00.301000"}),
    "iso_whitespace": ("%Y-%m-%d %H:%M:%S.%f", 0, None, "  ", ".",
                       {"start_time": "2026-11-24T10:00:00.301000"}),
}


@pytest.mark.parametrize("name", list(DIALECTS))
def test_each_stamp_dialect_reads_to_the_true_seconds(tmp_path, name):
    fmt, cut, tz, sep, decimal, start = DIALECTS[name]
    fs = 500.0                                    # 2 ms: exact in every stamp resolution
    t = np.arange(1500) / fs
    speed = 1230.1 + 40 * t
    acc = 0.46 * np.sin(2 * np.pi * 41.0 * t)
    path = tmp_path / f"{name}.csv"
    _write(path, ["Timestamp", "Speed [rpm]", "Acc [m/s^2]"], _stamps(t, fmt, cut=cut, tz=tz),
           [speed, acc], sep=sep, decimal=decimal)
    rec = read(path)
    np.testing.assert_allclose(rec["time"].values, t, rtol=0, atol=1e-9)
    assert rec["Acc"].attrs["sample_rate"] == pytest.approx(fs, rel=1e-12)
    np.testing.assert_allclose(rec["Acc"].values, acc, atol=1e-6)
    np.testing.assert_allclose(rec["Speed"].values, speed * np.pi / 30, rtol=1e-8)
    for key, value in start.items():
        assert rec.attrs[key] == value
    assert "date/time in column 1" in sniff(path).describe()


def test_time_of_day_over_midnight_keeps_increasing(tmp_path):
    fs = 200.0
    t = np.arange(1000) / fs                      # 23:59:58 .. 00:00:02.995
    start = dt.datetime(2026, 11, 24, 23, 59, 58)
    path = tmp_path / "night.csv"
    _write(path, ["Zeit", "Acc [g]"], _stamps(t, "%H:%M:%S.%f", start=start, cut=3),
           [np.cos(t)])
    rec = read(path)
    np.testing.assert_allclose(rec["time"].values, t, atol=1e-9)
    assert rec.attrs["start_time_of_day"] == "23:59:58.000000"


def test_date_time_over_midnight_and_a_second_without_fraction(tmp_path):
    """Some loggers drop the fraction on a whole second (``10:00:01`` between ``…00.999``)."""
    fs = 4.0
    t = np.arange(40) / fs
    start = dt.datetime(2026, 12, 31, 23, 59, 55)
    stamps = [s.removesuffix(".000000") for s in _stamps(t, "%Y-%m-%d %H:%M:%S.%f",
                                                         start=start)]
    assert "2027-01-01 00:00:00" in stamps
    path = tmp_path / "newyear.csv"
    _write(path, ["DateTime", "p [bar]"], stamps, [t])
    rec = read(path)
    np.testing.assert_allclose(rec["time"].values, t, atol=1e-9)


def test_utc_offsets_across_a_daylight_saving_change(tmp_path):
    """02:59:59.5+02:00 is followed by 02:00:00+01:00 half a second later (CEST -> CET): the
    stamps are put on UTC, so the seconds do not jump back an hour."""
    fs = 2.0
    t = np.arange(20) / fs
    utc = dt.datetime(2026, 10, 25, 0, 59, 55)
    stamps = []
    for a in t:
        u = utc + dt.timedelta(seconds=float(a))
        offset = 2 if u < dt.datetime(2026, 10, 25, 1, 0, 0) else 1
        stamps.append((u + dt.timedelta(hours=offset)).strftime("%Y-%m-%dT%H:%M:%S.%f")[:-3]
                      + f"+0{offset}:00")
    path = tmp_path / "dst.csv"
    _write(path, ["Timestamp", "Acc [g]"], stamps, [t])
    rec = read(path)
    np.testing.assert_allclose(rec["time"].values, t, atol=1e-9)
    assert rec.attrs["start_time"] == "2026-10-25T02:59:55+02:00"


def test_millisecond_stamps_at_5_khz_are_rebuilt_as_the_uniform_clock(tmp_path, caplog):
    """A logger stamps 5 kHz samples to the millisecond, truncating: five rows share a stamp.
    The clock they round is rebuilt (rate within 1e-4, every time within 0.6 ms)."""
    fs = 5000.0
    t = np.arange(20_000) / fs
    stamps = [(START + dt.timedelta(milliseconds=int(a * 1e3 + 1e-9))).strftime(
        "%Y-%m-%d %H:%M:%S.%f")[:-3] for a in t]
    assert len(set(stamps)) == 4000
    path = tmp_path / "fast.csv"
    _write(path, ["Timestamp", "Acc [m/s^2]"], stamps, [np.sin(2 * np.pi * 37 * t)])
    with caplog.at_level(logging.WARNING, logger="crankbench"):
        rec = read(path)
    assert rec["Acc"].attrs["sample_rate"] == pytest.approx(fs, rel=1e-4)
    np.testing.assert_allclose(rec["time"].values, t, atol=6e-4)
    assert any("rounded to 0.001 s" in r.getMessage() for r in caplog.records)


def test_bad_stamp_past_the_sniffed_sample_names_line_column_and_format(tmp_path):
    t = np.arange(6000) / 1000.0                  # ~200 kB: the bad cell is read in chunks
    stamps = _stamps(t, "%d.%m.%Y %H:%M:%S,%f", cut=3)
    stamps[5000] = "24.11.2026 10:00:05,3O1"      # a letter O for a zero
    path = tmp_path / "bad.csv"
    _write(path, ["Zeit", "Acc [g]"], stamps, [t], sep=";", decimal=",")
    with pytest.raises(RecordError, match=r"line 5002, column 1 \('Zeit'\): '24.11.2026 "
                       r"10:00:05,3O1' is not a date/time of the column's format "
                       r"%d.%m.%Y %H:%M:%S,%f \(like '24.11.2026 10:00:00,301'\)"):
        read(path)


def test_bad_stamp_in_the_sniffed_sample_and_a_number_among_stamps(tmp_path):
    t = np.arange(50) / 100.0
    stamps = _stamps(t, "%Y-%m-%d %H:%M:%S.%f")
    stamps[20] = "2026-11-24 10:00:0"
    path = tmp_path / "bad.csv"
    _write(path, ["Timestamp", "Acc [g]"], stamps, [t])
    with pytest.raises(RecordError, match=r"line 22, column 1: '2026-11-24 10:00:0' is not a "
                       r"date/time of the column's format %Y-%m-%d %H:%M:%S.%f"):
        read(path)
    stamps[20] = "0.2"
    _write(path, ["Timestamp", "Acc [g]"], stamps, [t])
    with pytest.raises(RecordError, match=r"line 22, column 1: '0.2' is not a date/time"):
        read(path)


def test_a_text_column_that_is_no_time_is_still_refused(tmp_path):
    path = tmp_path / "status.csv"
    path.write_text("Status,Acc [g]\n" + "".join(f"OK,{i}\n" for i in range(20)))
    with pytest.raises(RecordError, match="cannot find rows of numbers to read"):
        read(path)
    path.write_text("Date,Acc [g]\n" + "".join(f"2026-11-{i + 1:02d},{i}\n" for i in range(20)))
    with pytest.raises(RecordError, match="cannot find rows of numbers to read"):
        read(path)                                # a date alone times no samples


def test_channel_map_names_the_date_time_column(tmp_path):
    fs = 1000.0
    t = np.arange(800) / fs
    path = tmp_path / "rig.txt"
    _write(path, ["Datum", "CH2"], _stamps(t, "%d.%m.%Y %H:%M:%S,%f", cut=3),
           [2.0 + np.sin(2 * np.pi * 25 * t)], sep=";", decimal=",")
    cmap = tmp_path / "map.toml"
    cmap.write_text('[source]\ntime_column = "Datum"\n[channel.acc]\ncolumn = 2\n'
                    'units = "g"\nscale = 0.5\n')
    rec = read(path, map=cmap)
    np.testing.assert_allclose(rec["time"].values, t, atol=1e-9)
    assert rec["acc"].attrs["sample_rate"] == pytest.approx(fs, rel=1e-12)
    np.testing.assert_allclose(rec["acc"].values, 9.80665 * 0.5 * (2 + np.sin(2 * np.pi * 25 * t)),
                               rtol=1e-6)
    assert rec.attrs["start_time"] == "2026-11-24T10:00:00.301000"
    cmap.write_text('[source]\ntime_column = 1\ntime_units = "ms"\n[channel.acc]\ncolumn = 2\n'
                    'units = "g"\n')
    with pytest.raises(ConfigError, match="holds dates/times"):
        read(path, map=cmap)


def test_analyse_a_date_time_run_up(tmp_path, capsys):
    """``crankbench analyse FILE --channel Acc --orders 2`` on a logger's date-time CSV of a
    run-up 1200 -> 1800 rpm at 2 kHz: order 2 at its true 0.8 m/s² within 1 %."""
    from crankbench.analysis.cli import main

    fs = 2000.0
    t = np.arange(int(6 * fs)) / fs
    rpm = 1200 + 100 * t
    angle = 2 * np.pi * (1200 * t + 50 * t ** 2) / 60      # ∫ rpm/60 dt, exact
    acc = 0.8 * np.cos(2 * angle) + 0.2 * np.cos(4.5 * angle + 1.0)
    path = tmp_path / "runup.csv"
    _write(path, ["Timestamp", "Speed [rpm]", "Acc [m/s^2]"],
           _stamps(t, "%Y-%m-%d %H:%M:%S.%f"), [rpm, acc])
    assert main(["analyse", str(path), "--channel", "Acc", "--orders", "2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    amps = {row["order"]: row["mean_amplitude"] for row in out["summary"]}
    assert amps[2.0] == pytest.approx(0.8, rel=0.01)
