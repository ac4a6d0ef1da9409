"""Property tests (hypothesis, bounded): round trips are exact, bad bytes give RecordError.

No input may make a reader hang, crash with an unrelated exception or return NaN silently.
"""

import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from crankbench.measure import io
from crankbench.measure.record import RecordWarning, make_record
from crankbench.predict.errors import RecordError

SETTINGS = dict(max_examples=50, deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])

UNITS = [("m/s^2", "acceleration"), ("g", "acceleration"), ("mm/s", "velocity"),
         ("um", "displacement"), ("deg", "angle"), ("rpm", "rotational_speed"),
         ("bar", "pressure"), ("mV", "voltage"), ("kN", "force"), ("N*m", "torque")]
names = st.text(alphabet="abcdefghijklmnopqrstuvwxyzABCXYZ0123456789_-. ", min_size=1,
                max_size=12).map(str.strip).filter(bool)


@st.composite
def records(draw):
    n = draw(st.integers(2, 200))
    dtype = draw(st.sampled_from([np.float32, np.float64]))
    fs = draw(st.floats(0.5, 2e5, allow_nan=False))
    t0 = draw(st.sampled_from([0.0, 0.25, -1.5]))
    width = 32 if dtype == np.float32 else 64
    elements = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False, width=width)
    chan_names = draw(st.lists(names, min_size=1, max_size=3, unique=True))
    spec = {}
    for i, name in enumerate(chan_names):
        unit, quantity = draw(st.sampled_from(UNITS))
        data = np.array(draw(st.lists(elements, min_size=n, max_size=n)), dtype=dtype)
        spec[name] = dict(data=data, sample_rate=fs, t0=t0, units=unit, quantity=quantity)
    if draw(st.booleans()):
        m = draw(st.integers(2, 20))
        spec["slow"] = dict(data=np.linspace(0.0, 1.0, m), sample_rate=fs / 7.0, units="rad/s",
                            quantity="rotational_speed")
    if draw(st.booleans()):
        gaps = draw(st.lists(st.floats(1e-6, 1.0), min_size=1, max_size=30))
        spec["tacho"] = dict(data=np.cumsum(gaps), units="s", quantity="pulse_times",
                             pulses_per_rev=draw(st.integers(1, 120)))
    return make_record(spec, start_time="2026-05-06T07:08:09+00:00")


@pytest.mark.parametrize("ext", [".csv", ".h5"])
@settings(**SETTINGS)
@given(rec=records())
def test_round_trip_exact(ext, rec):
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / f"r{ext}"
        io.write(rec, path)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RecordWarning)
            back = io.read(path)
    assert list(back.data_vars) == list(rec.data_vars)
    for name, var in rec.data_vars.items():
        got = back[name]
        assert got.dtype == var.dtype
        np.testing.assert_array_equal(got.values, var.values)
        assert not np.isnan(got.values).any()
        # a flat run at the extremes is reported as clipping: the only attr reading may add
        attrs = {k: v for k, v in got.attrs.items() if k != "clipped_spans_s"}
        assert attrs == var.attrs
        dim = var.dims[0]
        if dim in rec.coords:
            np.testing.assert_array_equal(back[dim].values, rec[dim].values)


@settings(**SETTINGS)
@given(data=st.binary(min_size=1, max_size=400),
       ext=st.sampled_from([".h5", ".csv", ".mf4", ".tdms", ".uff", ".wav", ".nc"]),
       prefix=st.sampled_from([b"", b"\x89HDF\r\n\x1a\n", b"MDF     ", b"TDSm",
                               b"RIFF\x00\x10\x00\x00WAVE", b"    -1\n    58\n",
                               b"time [s],acc [g]\n"]))
def test_arbitrary_bytes_give_record_error_or_valid_record(data, ext, prefix):
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / f"fuzz{ext}"
        path.write_bytes(prefix + data)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                rec = io.read(path)
        except RecordError as exc:
            assert "fuzz" in str(exc)
            return
        for var in rec.data_vars.values():
            assert np.isfinite(var.values).all()


@pytest.fixture(scope="module")
def valid_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("valid")
    rec = make_record({
        "acc": dict(data=np.arange(300, dtype=np.float32), sample_rate=100.0, units="g"),
        "tacho": dict(data=np.arange(1, 11) * 0.3, units="s", quantity="pulse_times",
                      pulses_per_rev=1)})
    out = {}
    for ext in (".h5", ".csv", ".mf4", ".tdms", ".uff", ".wav"):
        out[ext] = d / f"valid{ext}"
        io.write(rec, out[ext])
    return out


@settings(**SETTINGS)
@given(ext=st.sampled_from([".h5", ".csv", ".mf4", ".tdms", ".uff", ".wav"]),
       fraction=st.floats(0.01, 0.9999))
def test_any_truncation_is_reported(valid_files, ext, fraction, tmp_path_factory):
    src = valid_files[ext]
    d = tmp_path_factory.mktemp("cut")
    dst = d / f"cut{ext}"
    data = src.read_bytes()
    dst.write_bytes(data[: max(1, int(len(data) * fraction))])
    if ext == ".wav":
        dst.with_name(dst.name + ".json").write_bytes(
            src.with_name(src.name + ".json").read_bytes())
    _error_or_identical(dst, src)


@pytest.mark.parametrize("ext", [".h5", ".csv", ".mf4", ".tdms", ".uff", ".wav"])
@pytest.mark.parametrize("cut", [1, 2, 3, 7])
def test_cutting_the_last_bytes_is_reported(valid_files, ext, cut, tmp_path):
    """A logger that dies while writing the last few bytes must not yield a silently short or
    wrong record."""
    src = valid_files[ext]
    dst = tmp_path / f"cut{ext}"
    dst.write_bytes(src.read_bytes()[:-cut])
    if ext == ".wav":
        dst.with_name(dst.name + ".json").write_bytes(
            src.with_name(src.name + ".json").read_bytes())
    _error_or_identical(dst, src)


def _error_or_identical(dst, src):
    """A cut file raises RecordError naming it, or (only a trailing newline lost) reads back
    complete and identical — never silently short or wrong."""
    try:
        back = io.read(dst)
    except RecordError as exc:
        assert dst.name in str(exc)
        return
    whole = io.read(src)
    assert list(back.data_vars) == list(whole.data_vars)
    for name in whole.data_vars:
        np.testing.assert_array_equal(back[name].values, whole[name].values)
