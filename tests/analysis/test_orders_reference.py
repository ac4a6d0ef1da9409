"""Order phases referred to TDC from the pulse edges, and the order-spacing check (issue 13,
point 5). Truth by construction: edge times of a 60-2 wheel in closed form, a signal written
against the crank angle from TDC of cylinder 1."""

import warnings

import numpy as np
import pytest
import xarray as xr

from crankbench.analysis.orders import OrderWarning, order_track
from crankbench.analysis.speedref import speed_reference
from crankbench.predict.errors import AnalysisError


def _wheel_record(tdc_offset_deg, truth, *, fs=2000.0, duration=6.0, f0=12.0, rate=1.0,
                  start_teeth=17):
    """Run-up f0 + rate·t rev/s; the wheel's first tooth after the gap is the reference, TDC of
    cylinder 1 follows it by ``tdc_offset_deg``; the record starts ``start_teeth`` pitches
    after a reference."""
    ppr, missing = 60, 2
    theta0 = 2 * np.pi * start_teeth / ppr               # wheel angle at t = 0

    def theta(t):
        return theta0 + 2 * np.pi * (f0 * t + 0.5 * rate * t * t)

    k = np.arange(start_teeth + 1, int(theta(duration) / (2 * np.pi / ppr)))
    # θ(t) = 2π k/ppr solved for t
    c = (2 * np.pi * k / ppr - theta0) / (2 * np.pi)
    t_edges = (-f0 + np.sqrt(f0 ** 2 + 2 * rate * c)) / rate
    t_edges = t_edges[np.mod(k, ppr) < ppr - missing]
    t = np.arange(int(duration * fs)) / fs
    psi = theta(t) - np.radians(tdc_offset_deg)             # crank angle from TDC
    x = sum(a * np.cos(o * psi + np.radians(p)) for o, (a, p) in truth.items())
    rec = xr.Dataset(
        {"acc": ("time", x, {"units": "m/s^2", "quantity": "acceleration", "sample_rate": fs}),
         "tacho": ("pulse", t_edges, {"units": "s", "quantity": "pulse_times",
                                      "pulses_per_rev": ppr, "missing_teeth": missing,
                                      "tdc_offset_deg": tdc_offset_deg})},
        coords={"time": t})
    return rec


@pytest.mark.parametrize("tdc_offset_deg", [0.0, 84.0, 250.0])
@pytest.mark.parametrize("method", ["auto", "cot"])
def test_phases_are_referred_to_tdc_of_cylinder_1(tdc_offset_deg, method):
    truth = {1.0: (0.5, 40.0), 2.0: (1.0, -75.0), 3.0: (0.3, 160.0)}
    rec = _wheel_record(tdc_offset_deg, truth)
    n = speed_reference(rec, "acc")
    assert "TDC of cylinder 1" in n.attrs["angle_reference"]
    kw = {"revolutions": 4} if method == "cot" else {}
    tr = order_track(rec["acc"], speed_rpm=n, orders=list(truth), method=method, **kw)
    assert "TDC of cylinder 1" in tr.attrs["phase_reference"]
    tt = tr["time"].values
    keep = (tt > 1.0) & (tt < 5.0)
    deg = str(tr["phase"].attrs.get("units", "rad")).startswith("deg")
    for o, (a, p) in truth.items():
        ph = tr["phase"].sel(order=o).values[keep]
        ph = ph if deg else np.degrees(ph)
        d = (ph - p + 180.0) % 360.0 - 180.0
        assert np.nanmax(np.abs(d)) < 0.5, (o, np.nanmax(np.abs(d)))
        amp = tr["amplitude"].sel(order=o).values[keep]
        assert np.nanmax(np.abs(amp / a - 1)) < 0.01


def test_orders_inside_each_others_main_lobe_are_named():
    """Orders 2 and 2.5 at equal amplitude (the former code read 0.17…1.85 with 1-revolution
    blocks, a spurious beat): 1-revolution blocks cannot separate them and are refused with
    the setting to use; 2-revolution blocks put them inside each other's main lobe and the
    least-squares fit separates them (a warning names the noise amplification where it
    exceeds 1.5, e.g. order 0.5 beside the trend); 4 need no warning; a duplicate order is
    refused."""
    fs = 2000.0
    t = np.arange(int(4 * fs)) / fs
    rpm = np.full(t.size, 1200.0)
    phi = 2 * np.pi * 20.0 * t
    x = np.cos(2.0 * phi) + np.cos(2.5 * phi + 1.0)
    with pytest.raises(AnalysisError, match=r"cannot be separated: use revolutions >= 4"):
        order_track(x, fs=fs, speed_rpm=rpm, orders=[2.0, 2.5], method="cot", revolutions=1)
    tr = order_track(x, fs=fs, speed_rpm=rpm, orders=[2.0, 2.5], method="cot", revolutions=2)
    assert np.nanmax(np.abs(tr["amplitude"].values - 1.0)) < 0.01
    # order 0.5 next to order 0 (the trend) in 2-revolution blocks: separated, noise x1.7
    with pytest.warns(OrderWarning, match=r"main lobe .* noise amplified up to 1\.7x"):
        tr = order_track(x + np.cos(0.5 * phi), fs=fs, speed_rpm=rpm, orders=[0.5, 2.0, 2.5],
                         method="cot", revolutions=2)
    assert np.nanmax(np.abs(tr["amplitude"].values - 1.0)) < 0.01
    with warnings.catch_warnings():
        warnings.simplefilter("error", OrderWarning)
        tr = order_track(x, fs=fs, speed_rpm=rpm, orders=[2.0, 2.5], method="cot",
                         revolutions=4)
    assert np.nanmax(np.abs(tr["amplitude"].values - 1.0)) < 0.01
    with pytest.raises(AnalysisError):
        order_track(x, fs=fs, speed_rpm=rpm, orders=[2.0, 2.0], method="cot", revolutions=4)
