"""Resonance identification: speed against error through swept resonances.

An SDOF mode (f_n = 20 Hz, order 6, critical 200 rpm) driven through a linear run-up (or
run-down) is simulated with ``scipy.signal.lsim`` and complex-demodulated into an order track
(independent of the code under test). For each sweep rate and damping ratio:

* ``find_resonances`` (modal fit with the swept-SDOF model): relative error of the critical
  speed against the closed-form ``f_n`` and of the sweep-corrected amplitude against the
  steady-state peak ``1/(2ζ√(1−ζ²))``; bounds 0.5 % and 5 % (the issue's acceptance for
  sweeps ≤ 100 rpm/s);
* baseline, timed side by side (interleaved rounds, paired ratio: :func:`analysis.bench.compare`):
  the raw peak of the track (speed of the maximum and its amplitude, parabolic interpolation)
  — what one reads off an order-track plot.
"""

from __future__ import annotations

import numpy as np

from . import compare

__all__ = ["run", "swept_track"]

SUITE = "resonance"


def swept_track(rate_rpm_s, *, fn=20.0, zeta=0.03, order=6.0, rpm0=100.0, rpm1=300.0,
                fs=2000.0):
    """Order track of an SDOF swept through resonance (lsim + complex demodulation)."""
    import xarray as xr
    from scipy import signal

    dwell = 2.0
    t = np.arange(-dwell, (rpm1 - rpm0) / abs(rate_rpm_s), 1 / fs)
    ramp = abs(rate_rpm_s) * np.clip(t, 0, None)
    rpm = rpm0 + ramp if rate_rpm_s > 0 else rpm1 - ramp
    phi = 2 * np.pi * np.cumsum(order * rpm / 60) / fs
    wn = 2 * np.pi * fn
    _, x, _ = signal.lsim(signal.lti([wn**2], [1, 2 * zeta * wn, wn**2]), np.cos(phi),
                          t - t[0])
    sos = signal.butter(8, 0.8 * order * rpm0 / 60 / (fs / 2), output="sos")
    comp = signal.sosfiltfilt(sos, 2 * x * np.exp(-1j * phi))
    keep = np.flatnonzero(t >= 0)[::5]
    c = comp[keep]
    return xr.Dataset({"amplitude": (("order", "time"), np.abs(c)[None], {"units": "rad"}),
                       "phase": (("order", "time"), np.angle(c)[None], {"units": "rad"})},
                      coords={"order": [order], "rpm": ("time", rpm[keep]),
                              "time": ("time", t[keep])})


def _raw_peak(track):
    from crankbench.analysis.resonance import _parabolic

    a = track["amplitude"].values[0]
    r = track["rpm"].values
    k = np.argsort(r)
    r, a = r[k], a[k]
    return _parabolic(r, a, int(np.argmax(a)))


def run(quick: bool) -> list:
    from crankbench.analysis.resonance import find_resonances

    cases = [(10.0, 0.03), (100.0, 0.05)] if quick else \
        [(1.0, 0.02), (10.0, 0.02), (30.0, 0.03), (100.0, 0.05), (-100.0, 0.03), (100.0, 0.02)]
    rows = []
    fn_rpm = 200.0
    for rate, zeta in cases:
        track = swept_track(rate, zeta=zeta)
        steady = 1 / (2 * zeta * np.sqrt(1 - zeta**2))
        res = find_resonances(track)
        timing = compare({"fit": lambda: find_resonances(track), "raw": lambda: _raw_peak(track)},
                         rounds=3 if quick else 5, min_time=0.01)
        setting = f"{rate:+g} rpm/s, ζ={zeta:g}"
        if len(res) != 1:
            rows.append(timing.row(SUITE, "find_resonances", "fit", None, setting,
                                   float("nan"), "found", "one resonance expected",
                                   note=f"found {len(res)}"))
            continue
        r = res.resonances[0]
        speed_err = abs(r.speed_rpm / fn_rpm - 1)
        amp_err = abs(r.amplitude_corrected / steady - 1)
        rpm_pk, a_pk = _raw_peak(track)
        # the steady peak of a receptance sits at f_n √(1 − 2ζ²)
        raw_speed_err = abs(rpm_pk / (fn_rpm * np.sqrt(1 - 2 * zeta**2)) - 1)
        raw_amp_err = abs(a_pk / steady - 1)
        within = abs(rate) <= 100.0
        ref = "closed-form SDOF (f_n, 1/(2ζ√(1−ζ²))); lsim swept track"
        base = ("raw", "raw peak")
        rows += [
            timing.row(SUITE, "find_resonances: critical speed", "fit", base, setting,
                       speed_err, "rel", ref, bound=0.005 if within else float("inf"),
                       note=f"{r.method}; η={r.sweep_eta:.3g}"),
            timing.row(SUITE, "find_resonances: amplitude (sweep-corrected)", "fit", base,
                       setting, amp_err, "rel", ref, bound=0.05 if within else float("inf"),
                       note=f"estimated peak loss {r.sweep_peak_loss:.3f}"),
            timing.row(SUITE, "raw peak: speed of the maximum", "raw", None, setting,
                       raw_speed_err, "rel", ref, note="baseline, informational"),
            timing.row(SUITE, "raw peak: amplitude", "raw", None, setting, raw_amp_err, "rel",
                       ref, note="baseline, informational"),
        ]
    return rows
