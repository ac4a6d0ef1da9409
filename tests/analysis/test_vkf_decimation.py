"""The Vold–Kalman solve rate (``analysis.vkf_decimate._decimation_factor``): chosen between 2.5 and 4
times the highest order frequency by the work it saves, without changing what the filter
passes, what it lets alias, or the tracks (independent references: the designed cascade's own
response, the synthesised amplitudes, the same solve at 4 f_max)."""

import math
import warnings

import numpy as np
import pytest

from crankbench.analysis import vkf_decimate as vkf
from crankbench.analysis.orders import order_track
from crankbench.analysis.resample import shaft_angle
from crankbench.analysis.vkf_smear import cascade_gain

FS = 20_000.0
F_MAX = 4.5 * 3000.0 / 60.0 + 0.5            # the bench run-up's top order frequency + band


def _designed_macs(fs, f_max, q):
    """Multiply-adds per input sample of the cascade actually designed for ``q``."""
    rate, cost = fs, 0.0
    for qs, h in vkf._decimator(fs, f_max, q):
        rate /= qs
        cost += h.shape[0] * rate / fs
    return cost


@pytest.mark.parametrize("q", [22, 24, 30, 33, 35])
def test_the_cost_estimate_is_the_designed_cascade(q):
    """Kaiser's length formula (the estimate the choice uses) against the taps designed."""
    est, reach = vkf._fir_macs(FS, F_MAX, q)
    assert est == pytest.approx(_designed_macs(FS, F_MAX, q), rel=0.02)
    longest = max(h.shape[0] / (FS / math.prod(s for s, _ in vkf._decimator(FS, F_MAX, q)[:k + 1])
                                * s)
                  for k, (s, h) in enumerate(vkf._decimator(FS, F_MAX, q)))
    assert reach >= 0.4 * longest           # half of the longest stage, in seconds, at least


def test_the_bench_run_up_is_solved_at_a_lower_rate_and_a_short_sweep_is_not():
    """10 s run-up, 3 orders (7 columns): q = 33 (606 Hz) rather than 22 (909 Hz); its
    cascade leaves 50 ms incomplete at either end, within 0.5 % of the record. A 0.47 s record
    would lose 11 % that way: it keeps q = 22. One order (3 columns) asks less of the solve."""
    assert math.floor(FS / (4 * F_MAX)) == 22
    assert vkf._decimation_factor(FS, F_MAX, 7, 10.0) == 33
    assert vkf._fir_macs(FS, F_MAX, 33)[1] <= 0.005 * 10.0
    assert vkf._decimation_factor(FS, F_MAX, 7, 0.47) == 22
    q1 = vkf._decimation_factor(FS, F_MAX, 3, 10.0)
    assert 22 <= q1 <= math.floor(FS / (2.5 * F_MAX))


@pytest.mark.parametrize("q", [22, 33, 35])
def test_the_cascade_is_flat_to_f_max_and_stops_what_would_alias(q):
    """The designed cascade (its own taps, not the estimate): |H − 1| ≤ 1e-5 on [0, f_max],
    and ≤ 1e-5 (100 dB) wherever a frequency folds into [0, f_max] at the solve rate."""
    stages = vkf._decimator(FS, F_MAX, q)
    fs_d = FS / q
    band = np.linspace(0.0, F_MAX, 2001)
    assert np.abs(cascade_gain(stages, FS, band) - 1.0).max() <= 1e-5
    folds = np.concatenate([np.linspace(k * fs_d - F_MAX, min(k * fs_d + F_MAX, FS / 2), 2001)
                            for k in range(1, int(FS / 2 // fs_d) + 1)])
    assert np.abs(cascade_gain(stages, FS, folds)).max() <= 1e-5


def _runup(noise, seed=5, duration=10.0, extra=None):
    t = np.arange(int(duration * FS)) / FS
    rpm = 1000 + 2000 * t / duration
    phi = shaft_angle(rpm, FS)
    truth = {1.0: 1.0, 2.0: 0.5, 4.5: 0.25}
    x = sum(a * np.cos(o * phi + 0.1 * o) for o, a in truth.items())
    if extra is not None:
        x = x + extra(t)
    if noise:
        x = x + np.random.default_rng(seed).normal(0.0, noise, t.size)
    return t, rpm, x, truth


def _track(x, rpm, monkeypatch=None, q=None):
    if q is not None:
        monkeypatch.setattr(vkf, "_decimation_factor", lambda *a: q)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return order_track(x, fs=FS, speed_rpm=rpm, orders=[1.0, 2.0, 4.5], method="vkf",
                           bandwidth_hz=0.5)


def test_tracks_and_stated_noise_are_those_of_the_4_f_max_solve(monkeypatch):
    """Clean: every order within 2e-6 of its synthesised amplitude at either rate (1 s in from
    each end). Noisy (0.1 rms): the two tracks agree within a fifth of their stated σ, and the
    stated σ is the error's at either rate (rms error / rms σ within 0.5-1.4; the local noise
    estimate is itself a statistic: its frames are 3.4 s at 606 Hz, 2.3 s at 909 Hz, and the
    two σ differ by 8 % in the median)."""
    _, rpm, clean, truth = _runup(0.0)
    _, _, noisy, _ = _runup(0.1)
    new_c, new_n = _track(clean, rpm), _track(noisy, rpm)
    assert new_c.attrs["solve_rate_hz"] == pytest.approx(FS / 33)
    old_c, old_n = _track(clean, rpm, monkeypatch, 22), _track(noisy, rpm, monkeypatch, 22)
    assert old_c.attrs["solve_rate_hz"] == pytest.approx(FS / 22)
    for ds in (new_c, old_c):
        t = ds["time"].values
        inner = (t > 1.0) & (t < 9.0)
        for j, a in enumerate(truth.values()):
            assert np.abs(ds["amplitude"].values[j][inner] / a - 1.0).max() < 2e-6
    for j in range(3):
        tn, to = new_n["time"].values, old_n["time"].values
        a_old = np.interp(tn, to, old_n["amplitude"].values[j])
        inner = (tn > 1.0) & (tn < 9.0)
        sigma = new_n["amplitude_uncertainty"].values[j][inner]
        assert np.abs(new_n["amplitude"].values[j][inner] - a_old[inner]).max() < 0.2 * sigma.min()
        s_old = np.interp(tn, to, old_n["amplitude_uncertainty"].values[j])[inner]
        assert np.median(np.abs(sigma / s_old - 1.0)) < 0.2
        a_true = list(truth.values())[j]
        for ds in (new_n, old_n):
            t = ds["time"].values
            keep = (t > 1.0) & (t < 9.0)
            err = ds["amplitude"].values[j][keep] - a_true
            unc = ds["amplitude_uncertainty"].values[j][keep]
            assert 0.5 < np.sqrt(np.mean(err ** 2) / np.mean(unc ** 2)) < 1.4


def test_a_tone_that_would_fold_onto_an_order_is_stopped():
    """A unit tone at fs_d − f(4.5 × 2900 rpm) folds onto order 4.5 near the top of the run-up
    at the lower solve rate: the order's track moves by less than 1e-5 there."""
    fs_d = FS / 33
    f_order = 4.5 * 2900.0 / 60.0
    tone = lambda t: np.cos(2 * np.pi * (fs_d - f_order) * t)          # noqa: E731
    _, rpm, plain, _ = _runup(0.0)
    _, _, dirty, _ = _runup(0.0, extra=tone)
    a, b = _track(plain, rpm), _track(dirty, rpm)
    t = a["time"].values
    near = (t > 8.5) & (t < 9.2)
    assert np.abs(b["amplitude"].values[2][near] - a["amplitude"].values[2][near]).max() < 1e-5
