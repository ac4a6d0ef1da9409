"""Closed-form indicator diagrams and raw records made from them, for the pressure tests.

Everything here is written independently of ``crankbench.analysis``: the slider-crank volume
is the textbook closed form, the reference IMEP comes from ``scipy.integrate.quad`` (or the
Otto-cycle integral), the reference peak from ``scipy.optimize`` on the closed form, and the
records are built sample by sample from an explicit crank-angle law θ(t) with speed
fluctuations at orders ½ and 2.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import quad
from scipy.optimize import minimize_scalar

from crankbench.measure.record import make_record
from crankbench.predict.engine import Engine

R, L, BORE, EPS = 0.045, 0.15, 0.085, 10.0
AREA = np.pi * BORE ** 2 / 4
VS = AREA * 2 * R
VC = VS / (EPS - 1)
K = 1.33
P_IN, P_EX = 0.95e5, 1.15e5


def engine(cycle=4):
    return Engine(crank_angles_deg=[0], crank_radius=R, rod_length=L, reciprocating_mass=0.5,
                  bore=BORE, compression_ratio=EPS, cycle=cycle)


def volume(theta):
    """V(θ) = V_c + A (r + l − r cos θ − sqrt(l² − r² sin² θ)) (Heywood eq. 2.4)."""
    s = np.sin(theta)
    return VC + AREA * (R + L - R * np.cos(theta) - np.sqrt(L * L - R * R * s * s))


def volume_slope(theta):
    s, c = np.sin(theta), np.cos(theta)
    return AREA * (R * s + R * R * s * c / np.sqrt(L * L - R * R * s * s))


class SmoothCycle:
    """Polytropic compression/expansion times a compact combustion bump
    ``1 + B (1 − ((θ − θc)/w)²)⁴`` on ``|θ − θc| < w`` (C³ smooth, zero before θc − w);
    constant-pressure exhaust and intake strokes. θ in rad from firing TDC, any range
    (periodic, 4π)."""

    def __init__(self, bump=3.0, centre_deg=22.0, width_deg=42.0):
        self.bump, self.centre, self.width = bump, np.radians(centre_deg), np.radians(width_deg)

    def closed(self, th):
        v1 = volume(np.pi)
        u = np.clip(1 - ((th - self.centre) / self.width) ** 2, 0.0, None)
        return P_IN * (v1 / volume(th)) ** K * (1 + self.bump * u ** 4)

    def __call__(self, theta):
        th = np.mod(np.asarray(theta, float) + 2 * np.pi, 4 * np.pi) - 2 * np.pi
        return np.where(np.abs(th) <= np.pi, self.closed(th),
                        np.where(th > 0, P_EX, P_IN))

    def reference(self):
        """Peak (Pa), its angle (deg), gross/net IMEP and PMEP (Pa) by quadrature."""
        res = minimize_scalar(lambda x: -self.closed(x), bounds=(-0.2, 0.8), method="bounded",
                              options={"xatol": 1e-10})
        gross, _ = quad(lambda x: self.closed(x) * volume_slope(x), -np.pi, np.pi, limit=400,
                        points=[0.0, self.centre], epsabs=1e-9, epsrel=1e-12)
        pmep = P_EX - P_IN
        return {"peak": -res.fun, "angle_deg": np.degrees(res.x), "imep_gross": gross / VS,
                "imep_net": gross / VS - pmep, "pmep": pmep}


class OttoCycle:
    """Ideal Otto cycle: isentropic compression, constant-volume heat addition at TDC
    (pressure ratio ``rp``), isentropic expansion; exhaust and intake at constant pressure."""

    def __init__(self, rp=3.5):
        self.rp = rp

    def __call__(self, theta):
        th = np.mod(np.asarray(theta, float) + 2 * np.pi, 4 * np.pi) - 2 * np.pi
        v1 = volume(np.pi)
        comp = P_IN * (v1 / volume(th)) ** K
        return np.where(np.abs(th) <= np.pi, np.where(th > 0, self.rp * comp, comp),
                        np.where(th > 0, P_EX, P_IN))

    def reference(self):
        """Closed-form Otto work: W = (p3 V2 − p4 V1 − p2 V2 + p1 V1) / (k − 1)."""
        v1, v2 = VC + VS, VC
        p1 = P_IN
        p2 = p1 * (v1 / v2) ** K
        p3 = self.rp * p2
        p4 = p3 * (v2 / v1) ** K
        gross = (p3 * v2 - p4 * v1 - p2 * v2 + p1 * v1) / (K - 1) / VS
        return {"imep_gross": gross, "imep_net": gross - (P_EX - P_IN), "pmep": P_EX - P_IN}


def crank_law(speed_rpm=1500.0, start_deg=-500.0, a_half=0.04, a_two=0.006):
    """θ(t) = θ0 + Ω t + a½ sin(Ω t / 2) + a₂ sin(2 Ω t): speed fluctuation at orders ½ and 2."""
    w = speed_rpm * np.pi / 30

    def theta(t):
        t = np.asarray(t, float)
        return np.radians(start_deg) + w * t + a_half * np.sin(0.5 * w * t) + a_two * np.sin(
            2 * w * t)

    return theta


def _invert(theta, targets, t_end):
    grid = np.linspace(0.0, t_end, int(t_end * 20000) + 2)
    t = np.interp(targets, theta(grid), grid)
    for _ in range(3):                                   # Newton on the exact law
        h = 1e-7
        t = t - (theta(t) - targets) * 2 * h / (theta(t + h) - theta(t - h))
    return t


def record(cycle_fn, *, duration=1.0, fs=100_000.0, speed_rpm=1500.0, start_deg=-500.0,
           wheel="60-2", tdc_offset_deg=84.0, mark=True, mark_every_rev=True, cam=False,
           noise_pa=0.0, offset_pa=0.0, drift_pa_s=0.0, tdc_error_deg=0.0, seed=0,
           law=None, cam_deg=-90.0):
    """A raw record: pressure (Pa) at ``fs``, a 60-2 wheel as edge times (TDC of cylinder 1
    ``tdc_offset_deg`` after the first tooth after the gap) or a 360-ppr encoder as a sampled
    square wave, a TDC mark as a two-sample voltage pulse, optionally a cam mark per cycle.
    ``tdc_error_deg``: the pressure is written as if TDC were that much later; the cam mark
    sits ``cam_deg`` from the firing TDC of cylinder 1."""
    theta = law or crank_law(speed_rpm, start_deg)
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration * fs)) / fs
    th = theta(t)
    p = cycle_fn(th - np.radians(tdc_error_deg)) + offset_pa + drift_pa_s * t
    if noise_pa:
        p = p + noise_pa * rng.standard_normal(t.size)
    chans = {"p_cyl1": dict(data=p, sample_rate=fs, units="Pa", quantity="pressure",
                            location="cylinder 1")}
    lo, hi = th[0], th[-1]
    if wheel == "60-2":
        k = np.arange(int(np.floor(lo / (np.pi / 30))) - 1, int(np.ceil(hi / (np.pi / 30))) + 1)
        ang = k * np.pi / 30 - np.radians(tdc_offset_deg)      # tooth k%60 at 6 k deg
        keep = (np.mod(k, 60) < 58) & (ang > lo) & (ang < hi)
        chans["crank"] = dict(data=_invert(theta, ang[keep], duration), quantity="pulse_times",
                              units="s", pulses_per_rev=60, missing_teeth=2)
    else:                                                     # 360-ppr encoder, square wave
        chans["encoder"] = dict(data=np.where(np.mod(np.degrees(th), 1.0) < 0.5, 5.0, 0.0),
                                sample_rate=fs, units="V", quantity="voltage",
                                attrs={"pulses_per_rev": 360})
    period = 2 * np.pi if mark_every_rev else 4 * np.pi
    if mark:
        v = np.zeros(t.size)
        tm = _invert(theta, np.arange(np.ceil(lo / period), np.floor(hi / period) + 1) * period,
                     duration)
        for x in tm:                                          # two samples wide
            i = int(np.ceil(x * fs))
            v[i:i + 2] = 5.0
        chans["tdc"] = dict(data=v, sample_rate=fs, units="V", quantity="voltage")
    if cam:
        v = np.zeros(t.size)
        c = 4 * np.pi
        tm = _invert(theta, (np.arange(np.ceil(lo / c), np.floor(hi / c) + 1) * c
                             + np.radians(cam_deg)), duration)
        for x in tm[(tm > 0) & (tm < duration - 1e-3)]:
            i = int(np.ceil(x * fs))
            v[i:i + 50] = 5.0
        chans["cam"] = dict(data=v, sample_rate=fs, units="V", quantity="voltage")
    return make_record(chans)
