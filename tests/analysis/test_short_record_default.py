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
