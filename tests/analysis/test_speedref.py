"""Speed reference from a speed channel on another clock or from a pulse train."""

import numpy as np
import pytest
import xarray as xr

from crankbench.analysis.speedref import find_speed_channel, speed_reference
from crankbench.predict.errors import AnalysisError, RecordError


def _record_with_pulses(ppr=60, missing=0, fs=5000.0, duration=4.0):
    # run-up at constant angular acceleration: θ(t) = ω0 t + α t²/2 (edge times in closed form)
    omega0, alpha = 2 * np.pi * 1000 / 60, 2 * np.pi * 500 / 60        # rpm 1000 + 500 t
    theta = np.arange(1, int((omega0 * duration + alpha * duration ** 2 / 2) / (2 * np.pi / ppr)))
    theta = theta * (2 * np.pi / ppr)
    edges = (-omega0 + np.sqrt(omega0 ** 2 + 2 * alpha * theta)) / alpha
    if missing:
        keep = np.mod(np.arange(edges.size), ppr) < ppr - missing
        edges = edges[keep]
    t = np.arange(int(duration * fs)) / fs
    return xr.Dataset(
        {"acc": ("time", np.zeros(t.size), {"units": "m/s^2", "quantity": "acceleration",
                                             "sample_rate": fs}),
         "tacho": ("pulse", edges, {"units": "s", "quantity": "pulse_times",
                                    "pulses_per_rev": ppr, "missing_teeth": missing})},
        coords={"time": t}), 1000 + 500 * t


@pytest.mark.parametrize("missing", [0, 2])
def test_pulses_give_the_run_up_speed(missing):
    """Closed-form truth: speed 1000 + 500 t rpm from edge times of constant acceleration."""
    rec, truth = _record_with_pulses(missing=missing)
    rpm = speed_reference(rec, "acc")
    inner = slice(1000, -1000)      # the one-revolution window leaves the ends held constant
    assert np.abs(rpm[inner] - truth[inner]).max() < 1e-3


def test_speed_channel_on_other_clock_is_interpolated():
    t = np.arange(1000) / 1000.0
    ts = np.arange(0, 1.0001, 0.01)
    rec = xr.Dataset(
        {"x": ("time", np.zeros(t.size), {"units": "m", "sample_rate": 1000.0}),
         "speed": ("time_slow", 2 * np.pi * (20 + 10 * ts), {"units": "rad/s",
                                                             "quantity": "rotational_speed"})},
        coords={"time": t, "time_slow": ts})
    assert find_speed_channel(rec, "x") == "speed"
    assert np.allclose(speed_reference(rec, "x"), 60 * (20 + 10 * t), rtol=1e-12)


def test_errors():
    rec = xr.Dataset({"x": ("time", np.zeros(10), {"units": "m"})}, coords={"time": np.arange(10.0)})
    with pytest.raises(AnalysisError, match="record has no speed reference"):
        speed_reference(rec, "x")
    with pytest.raises(RecordError, match="record has no channel 'y'"):
        speed_reference(rec, "y")
    rec["n"] = ("time", np.zeros(10), {"units": "rad/s", "quantity": "rotational_speed"})
    with pytest.raises(AnalysisError, match="needs the shaft turning"):
        speed_reference(rec, "x")


def test_pulse_angle_of_a_vibrating_wheel_is_the_mean_rotation():
    """A 60-2 wheel on a node that vibrates (2e-3 rad at order 4.5, 1e-3 rad at order 1.5): the
    shaft angle given to the trackers is the mean rotation (closed-form edge times of
    θ0 + vibration), so a channel's small orders next to a large order 4.5 are not
    modulated by the reference (before the fix: order 3 −9 %, 7.5 +33 % on the marine run-up)."""
    from crankbench.analysis.orders import order_track

    fs, duration = 2000.0, 12.0
    f0, rate = 10.0, 0.5                       # rev/s and rev/s²: 600 → 960 rpm

    def theta0(t):
        return 2 * np.pi * (f0 * t + 0.5 * rate * t * t)

    def vib(phi):
        return 2e-3 * np.cos(4.5 * phi) + 1e-3 * np.cos(1.5 * phi + 0.4)

    # edge k at θ0 + vib(θ0) = 2π k / 60 + 30° (TDC 30° before the gap), by Newton iteration
    ppr, missing = 60, 2
    k = np.arange(1, int(theta0(duration) / (2 * np.pi / ppr)) - 2)
    target = k * (2 * np.pi / ppr)
    t_e = (-f0 + np.sqrt(f0 ** 2 + 2 * rate * target / (2 * np.pi))) / rate
    for _ in range(8):
        phi = theta0(t_e)
        g = phi + vib(phi) - target
        dphi = 2 * np.pi * (f0 + rate * t_e)
        dvib = (-2e-3 * 4.5 * np.sin(4.5 * phi) - 1.5e-3 * np.sin(1.5 * phi + 0.4))
        t_e -= g / (dphi * (1 + dvib))
    t_e = t_e[np.mod(k, ppr) < ppr - missing]
    t = np.arange(int(duration * fs)) / fs
    phi0 = theta0(t)
    amps = {3.0: 1.3e-4, 4.5: 5e-3, 6.5: 6e-5, 7.5: 5e-5}
    x = sum(a * np.cos(q * phi0 + 0.3 * q) for q, a in amps.items())
    rec = xr.Dataset(
        {"tv": ("time", x, {"units": "rad", "quantity": "angle", "sample_rate": fs}),
         "tacho": ("pulse", t_e, {"units": "s", "quantity": "pulse_times",
                                  "pulses_per_rev": ppr, "missing_teeth": missing})},
        coords={"time": t})
    n = speed_reference(rec, "tv", check=False)
    mean = n["shaft_angle"].values
    inner = slice(int(2 * fs), int(-2 * fs))
    d = (mean - phi0)[inner]
    # a constant (the TDC zero) aside, the vibration (3e-3 rad peak) is averaged out
    assert np.abs(d - np.median(d)).max() < 3e-5
    tr = order_track(x, fs=fs, speed_rpm=n, orders=sorted(amps), method="vkf",
                     bandwidth_orders=0.25)
    tt = tr["time"].values
    keep = (tt > 2.0) & (tt < duration - 2.0)
    for q, a in amps.items():
        got = np.nanmean(tr["amplitude"].sel(order=q).values[keep])
        assert got == pytest.approx(a, rel=0.01), q


def test_fast_speed_channel_with_its_vibration_analysed_against_itself():
    """An IAS exported as a speed channel ('ias [rpm]', quantity rotational_speed) carrying
    orders 3 and 6 of torsional vibration, analysed with itself as the speed source: the
    resampling speed is its mean rotation, so the orders come out within 0.2 % (with the raw
    channel as speed they read 0.26 % and 0.9 % off: phase modulation by the vibration)."""
    import xarray as xr

    from crankbench.analysis import order_track
    from crankbench.analysis.speedref import speed_reference

    fs = 5000.0
    t = np.arange(int(10 * fs)) / fs
    rpm = 1500 + 30 * t
    phi = np.cumsum(rpm / 60 * 2 * np.pi / fs)
    ias = rpm + 12 * np.cos(3 * phi) + 4 * np.cos(6 * phi + 0.5)
    w = ias * 2 * np.pi / 60
    rec = xr.Dataset({"ias": ("time", w, {"units": "rad/s", "quantity": "rotational_speed",
                                          "sample_rate": fs})}, coords={"time": t})
    ref = speed_reference(rec, "ias")
    assert np.max(np.abs(ref.values - rpm)[5000:-5000]) < 0.05       # the mean rotation
    tr = order_track(rec["ias"], speed_rpm=ref, orders=[3, 6])
    a = tr["amplitude"].values
    n = a.shape[1]
    got = np.nanmean(a[:, n // 5: -n // 5], axis=1)
    np.testing.assert_allclose(got, np.array([12.0, 4.0]) * 2 * np.pi / 60, rtol=2e-3)


def _runup_record(speed_rpm_values, fs=5000.0, seconds=8.0):
    t = np.arange(int(seconds * fs)) / fs
    rpm = 1200 + 100 * t
    phi = np.cumsum(rpm / 60 * 2 * np.pi / fs)
    acc = 0.5 * np.sin(2 * phi)
    speed = speed_rpm_values(t, rpm) * 2 * np.pi / 60
    rec = xr.Dataset({"acc": ("time", acc, {"units": "m/s^2", "quantity": "acceleration",
                                            "sample_rate": fs}),
                      "speed": ("time", speed, {"units": "rad/s",
                                                "quantity": "rotational_speed",
                                                "sample_rate": fs})}, coords={"time": t})
    return rec, rpm


def test_counter_glitches_in_the_speed_channel_are_bridged(caplog):
    """A 65535 overflow spike and a 5-sample drop to 0 in a running speed channel: bridged
    (warned), so order 2 stays within 0.1 % everywhere (the spike had put 6.6 % into the
    peak, the drop split the record into 'stopped' spans)."""
    from crankbench.analysis import order_track

    def dirty(t, rpm):
        out = rpm.copy()
        out[10000:10005] = 0.0
        out[20000] = 65535.0
        return out

    rec, rpm = _runup_record(dirty)
    with caplog.at_level("WARNING", logger="crankbench"):
        ref = speed_reference(rec, "acc")
    assert any("6 glitch sample(s)" in r.getMessage() for r in caplog.records)
    np.testing.assert_allclose(ref.values, rpm, rtol=1e-3)
    a = order_track(rec["acc"], speed_rpm=ref, orders=[2])["amplitude"].values[0]
    inner = a[len(a) // 10: -len(a) // 10]
    assert np.nanmax(np.abs(inner / 0.5 - 1)) < 1e-3


def test_a_real_stop_is_not_a_glitch():
    """Speed at 0 for 0.5 s in the middle (a real stop): kept, not interpolated over."""
    def stop(t, rpm):
        out = rpm.copy()
        out[(t > 3.0) & (t < 3.5)] = 0.0
        return out

    rec, _ = _runup_record(stop)
    ref = speed_reference(rec, "acc", check=False)
    t = rec["time"].values
    assert np.all(ref.values[(t > 3.05) & (t < 3.45)] < 1.0)


def test_a_speed_channel_negative_throughout_is_taken_by_its_magnitude(caplog):
    rec, rpm = _runup_record(lambda t, rpm: -rpm)
    with caplog.at_level("WARNING", logger="crankbench"):
        ref = speed_reference(rec, "acc")
    np.testing.assert_allclose(ref.values, rpm, rtol=1e-4)    # (cycle-averaged: 5 kHz)
    assert any("negative throughout" in r.getMessage() for r in caplog.records)
    mixed, _ = _runup_record(lambda t, rpm: np.where(t < 4, rpm, -rpm))
    with pytest.raises(AnalysisError, match="turning one way"):
        speed_reference(mixed, "acc", check=False)
