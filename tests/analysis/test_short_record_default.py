"""A record too short for the adaptive Vold–Kalman default (the raw genset export: 0.5 s,
11 revolutions, a 60-2 wheel with a runt tooth) is tracked by computed order tracking instead,
stated, and its amplitudes agree with a second method: the Fourier series of each cycle of
the indicator analysis (pressure resampled to crank angle from TDC, a different code path)."""

import warnings

import numpy as np
import pytest

from crankbench.analysis import indicator_analysis
from crankbench.analysis.orders import order_track
from crankbench.analysis.speedref import speed_reference
from crankbench.measure import read
from crankbench.predict.engine import Engine

ROOT = __import__("pathlib").Path(__file__).resolve().parents[2]


def test_short_record_defaults_to_stated_cot_and_agrees_with_per_cycle_fourier():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")          # the runt tooth is warned about elsewhere
        rec = read(ROOT / "sample_data/raw/genset_60-2.txt",
                   map=ROOT / "sample_data/raw/genset_60-2_map.toml")
        ind = indicator_analysis(rec, Engine.from_toml(ROOT / "sample_data/engines/single.toml"))
        rpm = speed_reference(rec, "pressure")
        tracks = order_track(rec["pressure"], speed_rpm=rpm, orders=[0.5, 1.0])
    # second method: per-cycle Fourier coefficients on the 720-degree crank-angle grid
    p = np.asarray(ind.pressure)
    coef = 2 * np.abs(np.fft.rfft(p, axis=-1)) / p.shape[-1]
    truth = {0.5: coef[:, 1].mean(), 1.0: coef[:, 2].mean()}
    assert "too short for the adaptive Vold-Kalman default" in tracks.attrs["auto_settings"]
    for order, ref in truth.items():
        amp = tracks["amplitude"].sel(order=order).values
        assert np.isfinite(amp).all() and amp.size >= 2
        assert np.mean(amp) == pytest.approx(ref, rel=0.03), order


def test_untracked_grid_lines_leaking_into_short_blocks_are_named():
    """Explicit 2-revolution Hann blocks on the same pressure: order 1.5 (not asked for) sits
    in order 1's main lobe; the means read 2.7x and 1.7x the per-cycle Fourier values (the
    figures :mod:`analysis.leakage` states) and the check names the leaking line. A channel
    holding only the tracked orders gets no such warning."""
    from crankbench.analysis.orders import OrderWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rec = read(ROOT / "sample_data/raw/genset_60-2.txt",
                   map=ROOT / "sample_data/raw/genset_60-2_map.toml")
        ind = indicator_analysis(rec, Engine.from_toml(ROOT / "sample_data/engines/single.toml"))
        rpm = speed_reference(rec, "pressure")
    p = np.asarray(ind.pressure)
    coef = 2 * np.abs(np.fft.rfft(p, axis=-1)) / p.shape[-1]
    with pytest.warns(OrderWarning, match=r"lines at orders 1\.5, not tracked.*leak"):
        short = order_track(rec["pressure"], speed_rpm=rpm, orders=[0.5, 1.0], method="cot",
                            revolutions=2)
    ratio = [float(short["amplitude"].sel(order=o).mean()) / coef[:, k].mean()
             for o, k in ((0.5, 1), (1.0, 2))]
    assert ratio == pytest.approx([2.7, 1.7], abs=0.05)
    # a signal with only the tracked orders: nothing leaks, nothing is said
    fs, n = 5000.0, 40000
    t = np.arange(n) / fs
    phi = 2 * np.pi * 20.0 * t
    x = 1.0 + np.cos(0.5 * phi) + 0.5 * np.cos(phi + 0.2)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        clean = order_track(x, fs=fs, speed_rpm=np.full(n, 1200.0), orders=[0.5, 1.0],
                            method="cot", revolutions=2)
    said = [str(w.message) for w in caught if issubclass(w.category, OrderWarning)]
    assert said and not [m for m in said if "leak" in m], said   # the spacing note only
    np.testing.assert_allclose(clean["amplitude"].mean("time").values, [1.0, 0.5], rtol=1e-3)
