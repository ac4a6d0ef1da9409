"""Cylinder-pressure channels of the synthetic bench, with the errors of real transducers.

The true pressure of each cycle is the single-zone Wiebe trace of :mod:`predict.pressure`
at the scene's ``imep`` (evaluated on a 0.1° grid and interpolated by a periodic cubic spline).
The trace is affine in the heat released, ``p = p_motored + Q u(ψ)``, so cycle-to-cycle
variation is a random heat release per cycle, ``Q_k = Q (1 + cycle_variation ε_k)``,
ε ~ N(0, 1). The scene's load law (factor ``L`` at each speed, :class:`.scene.LoadSpec`) scales
the *gas torque* of the bench's torsional and mount channels, ``L G_q`` (the model's
convention, :func:`analysis.pipeline.predicted_response`); the pressure written is the one
that torque comes from, the gas pressure above the crankcase scaled by ``L``:

    p_k(ψ) = p_cc + L (p_motored(ψ) + Q_k u(ψ) − p_cc),        p_cc = 1 bar,

with ``L`` the law at the cycle's mean speed (cycle angle / cycle time, the speed the indicator
analysis reports), so that its net IMEP is exactly ``L`` times the scene's ``imep`` (the model's
IMEP at that load; tests/measure/test_synth_pressure.py asserts 0.5 % per cycle, steady and on a
run-up; the truth holds it to quadrature) and its
gas-torque harmonics are exactly ``L G_q``. At ``L < 1`` this is not a physical part-load
cycle: its compression is a polytropic plus ``(1 − L) p_cc``, which the polytropic peg of
:func:`analysis.pressure.indicator_analysis` reads as an offset (pass ``peg="none"`` on such a
record; a constant load, ``L = 1``, is a plain Wiebe cycle). The channel then gets

* ``offset`` (Pa: the unknown level of a piezoelectric transducer — the pegging error),
  ``gain_error``, ``drift_rate`` (Pa/s) and ``noise_rms`` (Pa): the sampled-channel faults of
  the scene's :class:`.imperfections.Imperfections`;
* ``thermal_shock`` (Pa): the flame heats the diaphragm and the reading dips during expansion,
  ``−A (Q_k/Q) g(ψ − ψ_s)`` with ``g(u) = (u/τ)² e^{2(1 − u/τ)}`` (peak 1 at ``u = τ`` =
  ``thermal_shock_deg`` after the start of combustion ψ_s), i.e. a short-term drift of the
  kind described by Rosseel et al., SAE 1999-01-0935, and AVL/Kistler transducer sheets;
* ``tdc_error_deg``: the pressure is written as if TDC were δ later than the angle marks say
  (a TDC mark set δ too early): the thermodynamic TDC lies δ after the reference.

The ground truth of each channel (:func:`pressure_truth` reads it back from a truth Dataset)
holds, per cycle, the firing-TDC time, the load factor L, the heat release (L Q_k), net and
gross IMEP and PMEP (the trapezoidal loop integral of the 0.1° model trace), the peak pressure
and its angle (a dense evaluation of the spline), MFB50 of the Wiebe law (closed form), and the
settings above.

Scene keys of a ``kind = "pressure"`` sensor: ``cylinder``, ``sample_rate``, ``location`` and
``thermal_shock``, ``thermal_shock_deg``, ``tdc_error_deg``, ``cycle_variation`` (plus the
usual ``offset``, ``gain_error``, ``noise_rms``, ``drift_rate``).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass

import numpy as np

from crankbench.predict._validate import check_nonnegative, check_range
from crankbench.predict.errors import ConfigError

from .imperfections import add_noise_and_drift

__all__ = ["TransducerErrors", "pressure_channel", "pressure_truth", "cylinder_nodes",
           "PRESSURE_KEYS"]

#: scene keys of a pressure sensor besides cylinder, sample_rate and location
PRESSURE_KEYS = ("thermal_shock", "thermal_shock_deg", "tdc_error_deg", "cycle_variation")

#: unit and plausible range of each key (a plain number is in this unit; "0.5 bar" converts)
_UNITS = {"thermal_shock": dict(unit="Pa", plausible=(1.0, 1e7)),
          "thermal_shock_deg": dict(unit="deg", plausible=(1.0, 180.0)),
          "tdc_error_deg": dict(unit="deg", plausible=(1e-4, 30.0)),
          "cycle_variation": dict(unit="1", plausible=(1e-5, 1.0))}

TWO_PI = 2.0 * np.pi
RPM = TWO_PI / 60.0
#: crankcase pressure of the gas torque (predict.torsion.excitation.tangential_torque), Pa
P_CC = 1.0e5


@dataclass(frozen=True)
class TransducerErrors:
    """Errors of a cylinder-pressure transducer chain (see the module docstring).

    Attributes
    ----------
    thermal_shock : float
        Amplitude of the thermal-shock dip, Pa (at the mean heat release).
    thermal_shock_deg : float
        Crank angle from the start of combustion to the deepest dip, deg.
    tdc_error_deg : float
        The thermodynamic TDC lies this much after the reference, deg.
    cycle_variation : float
        Relative rms of the heat release per cycle.
    """

    thermal_shock: float = 0.0
    thermal_shock_deg: float = 60.0
    tdc_error_deg: float = 0.0
    cycle_variation: float = 0.0

    def __post_init__(self):
        check_nonnegative(self.thermal_shock, "thermal_shock", error=ConfigError)
        check_range(self.thermal_shock_deg, "thermal_shock_deg", 1.0, 180.0, error=ConfigError)
        check_range(self.tdc_error_deg, "tdc_error_deg", -30.0, 30.0, error=ConfigError)
        check_range(self.cycle_variation, "cycle_variation", 0.0, 0.3, error=ConfigError)

    @classmethod
    def from_table(cls, table):
        """Read the keys of :data:`PRESSURE_KEYS` present in a TOML table."""
        values = {k: table.number(k, **_UNITS[k]) for k in PRESSURE_KEYS if k in table}
        try:
            return cls(**values)
        except ConfigError as exc:
            raise ConfigError(f"{table.where()}: {exc}") from None


def _model(engine, imep):
    """Periodic splines of the motored part and of the unit heat-release part, and the trace."""
    from scipy.interpolate import CubicSpline

    from crankbench.predict.pressure import synthetic_pressure

    npts = 1800 * engine.cycle
    full = (synthetic_pressure(engine, imep=imep, points_per_cycle=npts) if imep
            else synthetic_pressure(engine, points_per_cycle=npts))
    q = float(full.parameters["heat_release"])
    half = synthetic_pressure(engine, heat_release=0.5 * q, points_per_cycle=npts,
                              **_same_model(full))
    unit = 2.0 * (full.pressure - half.pressure) / q
    motored = full.pressure - q * unit
    period = full.period
    ang = np.append(full.angle, period)

    def spline(values):
        return CubicSpline(ang, np.append(values, values[0]), bc_type="periodic")

    return full, q, spline(motored), spline(unit)


def _same_model(trace):
    keys = ("intake_pressure", "exhaust_pressure", "polytropic_exponent",
            "combustion_start_deg", "combustion_duration_deg", "wiebe_a", "wiebe_m",
            "exhaust_opening_deg", "compression_ratio")
    return {k: trace.parameters[k] for k in keys}


def cylinder_nodes(scene) -> dict:
    """Shaft-line node of each pressure sensor's cylinder: ``{sensor name: node name}``.

    Empty without a shaft line (or one without cylinder nodes): the pressure then follows the
    mean crank angle.
    """
    system = scene.shaftline
    if system is None or not len(getattr(system, "cylinder_nodes", ())):
        return {}
    out = {}
    for s in scene.sensors:
        c = s.params.get("cylinder")
        if s.kind == "pressure" and c is not None and c <= len(system.cylinder_nodes):
            out[s.name] = system.node_names[system.cylinder_nodes[c - 1]]
    return out


def pressure_channel(scene, spec, psi0, rng, *, vibration=None):
    """One pressure channel of a scene and its ground truth.

    Parameters
    ----------
    scene : measure.synth.scene.Scene
    spec : measure.synth.scene.SensorSpec
        A ``kind = "pressure"`` sensor.
    psi0 : float
        Crank angle of cylinder 1 from its firing TDC at t = 0, rad.
    rng : numpy.random.Generator
    vibration : (ndarray, ndarray), optional
        Time grid (s) and torsional vibration of the cylinder's crank throw (rad, referred to
        the crankshaft): the pressure follows the actual crank angle ``ψ + x``, as the pulse
        wheels do (:mod:`.pulses`).

    Returns
    -------
    channel : dict
        The channel spec for :func:`measure.record.make_record` (Pa).
    truth : dict
        JSON-able ground truth (see the module docstring), SI units and degrees named.
    """
    engine = scene.engine
    c = spec.params["cylinder"]
    if c > engine.n_cylinders:
        raise ConfigError(f"sensor {spec.name!r}: cylinder={c} but the engine has "
                          f"{engine.n_cylinders} cylinders")
    err = spec.params.get("transducer", TransducerErrors())
    full, q, motored, unit = _model(engine, scene.load.imep)
    period = full.period
    fs = float(spec.sample_rate)
    prof = scene.profile
    ts = np.arange(int(np.floor(prof.duration * fs)) + 1) / fs
    fire = np.radians(engine.firing_angles_deg()[c - 1])
    psi = psi0 + prof.angle(ts) - fire                     # cylinder's own crank angle
    if vibration is not None:
        psi = psi + np.interp(ts, vibration[0], vibration[1])
    k = np.floor((psi + period / 2) / period).astype(np.int64)
    k0 = int(k.min())
    n_cyc = int(k.max()) - k0 + 1
    scale = 1.0 + err.cycle_variation * rng.standard_normal(n_cyc)
    # the load of each cycle: the law at the cycle's mean speed (time average over its
    # samples = cycle angle / cycle time, the speed the indicator analysis reports)
    counts = np.bincount(k - k0, minlength=n_cyc)
    mean_rpm = np.bincount(k - k0, weights=prof.speed(ts), minlength=n_cyc) / np.maximum(
        counts, 1) / RPM
    load = scene.load.scale(mean_rpm)[k - k0]
    shifted = psi - np.radians(err.tdc_error_deg)
    wrapped = np.mod(shifted, period)
    true = P_CC + load * (motored(wrapped) + q * scale[k - k0] * unit(wrapped) - P_CC)
    data = true
    start = np.radians(full.parameters["combustion_start_deg"])
    if err.thermal_shock > 0:
        rel = np.mod(shifted + period / 2, period) - period / 2    # from firing TDC
        u = np.clip((rel - start) / np.radians(err.thermal_shock_deg), 0.0, None)
        data = data - err.thermal_shock * load * scale[k - k0] * u * u * np.exp(2 * (1 - u))
    data = add_noise_and_drift(data, ts, spec.imperfections, rng)
    channel = dict(data=data, sample_rate=fs, units="Pa", quantity="pressure",
                   location=spec.params.get("location", f"cylinder {c}"),
                   attrs={"cylinder": int(c)})
    truth = _truth(engine, full, q, motored, unit, scale, k0, psi0, fire, prof, err, spec,
                   period, scene.load)
    return channel, truth


def _truth(engine, full, q, motored, unit, scale, k0, psi0, fire, prof, err, spec, period,
           load_spec):
    from crankbench.predict.pressure import PressureTrace

    ang = full.angle
    m_grid, u_grid = motored(ang), unit(ang)
    # one grid for the peak search: -30..90 deg from firing TDC at 0.001 deg
    fine = np.radians(np.arange(-30.0, 90.0, 0.001))
    m_f, u_f = motored(np.mod(fine, period)), unit(np.mod(fine, period))
    bdc = np.array([np.pi]) if engine.cycle == 4 else None
    rows = []
    t_end = prof.duration
    # firing TDC times of the cylinder: psi0 + angle(t) - fire - δ = k period
    t_grid = np.linspace(0.0, t_end, max(2000, int(t_end * 2000)))
    a_grid = psi0 + prof.angle(t_grid) - fire - np.radians(err.tdc_error_deg)
    for j, s in enumerate(scale):
        kk = k0 + j
        target = kk * period
        if target - period / 2 < a_grid[0] or target + period / 2 > a_grid[-1]:
            continue
        t_tdc = float(np.interp(target, a_grid, t_grid))
        t0, t1 = np.interp([target - period / 2, target + period / 2], a_grid, t_grid)
        lf = float(load_spec.scale(np.array([period / (t1 - t0) / RPM]))[0])
        tr = PressureTrace(angle=ang, pressure=P_CC + lf * (m_grid + q * s * u_grid - P_CC),
                           cycle=engine.cycle)
        net = tr.work(engine) / engine.swept_volume
        if bdc is not None:
            sel = (ang <= np.pi) | (ang >= 3 * np.pi)
            a2 = np.where(ang >= 3 * np.pi, ang - 4 * np.pi, ang)[sel]
            order = np.argsort(a2)
            a2, p2 = a2[order], tr.pressure[sel][order]
            v = engine.cylinder_volume(engine.shaft_angle(a2))[0]
            gross = float(np.sum(0.5 * (p2[1:] + p2[:-1]) * np.diff(v))) / engine.swept_volume
        else:
            gross = net
        pf = P_CC + lf * (m_f + q * s * u_f - P_CC)
        i = int(np.argmax(pf))
        rows.append({"time_s": t_tdc, "load_factor": lf, "heat_release_j": q * s * lf,
                     "imep_net_pa": net,
                     "imep_gross_pa": gross, "pmep_pa": gross - net,
                     "peak_pressure_pa": float(pf[i]),
                     "peak_angle_deg": float(np.degrees(fine[i]))})
    prm = full.parameters
    u50 = (np.log(2.0) / prm["wiebe_a"]) ** (1.0 / (prm["wiebe_m"] + 1.0))
    return {"cylinder": int(spec.params["cylinder"]), "cycles": rows,
            "mfb50_deg": float(prm["combustion_start_deg"] + prm["combustion_duration_deg"]
                               * u50),
            "polytropic_exponent": float(prm["polytropic_exponent"]),
            "model": {k: float(v) for k, v in prm.items()},
            "errors": asdict(spec.params.get("transducer", TransducerErrors())),
            "noise_rms_pa": float(spec.imperfections.noise_rms),
            "offset_pa": float(spec.imperfections.offset),
            "gain_error": float(spec.imperfections.gain_error),
            "drift_rate_pa_per_s": float(spec.imperfections.drift_rate)}


def pressure_truth(truth) -> dict:
    """Ground truth of the pressure channels of a synthetic run: ``{channel: dict}``.

    Examples
    --------
    >>> import xarray as xr
    >>> pressure_truth(xr.Dataset(attrs={"pressure": '{"p1": {"cylinder": 1}}'}))
    {'p1': {'cylinder': 1}}
    """
    text = truth.attrs.get("pressure")
    return {} if text is None else json.loads(text)
