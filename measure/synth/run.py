"""``synthesize(scene)``: a synthetic test-bench record with its ground truth.

One call drives the prediction models through the operating profile and samples every sensor
of the scene:

* torsiograph channels and pulse wheels on shaft-line nodes from the time-domain torsional
  response (:mod:`.torsional`: complex modal integration through the resonances, so a fast
  sweep shows its transient - lower, later, broader peaks);
* vibrograph channels at mount points from the balance residuals and the torque reaction
  through the mount model (:mod:`.vibrograph`, quasi-steady);
* cylinder pressure from the synthetic Wiebe trace of :mod:`predict.pressure` with the
  transducer errors of :mod:`.pressure` (offset, drift, thermal shock, noise, TDC error);
* the bench speed channel (mean speed of the profile);

then adds the scene's imperfections (:mod:`.imperfections`). The ground truth carries, per
channel, the amplitude and phase of every order along the run (for torsional channels the
modulus of each order's own time-domain response, i.e. including the sweep's transient; for
mount channels the quasi-steady response), the steady-state amplitudes of the torsional
channels from :func:`predict.torsion.forced_response` at the same speeds (a second,
frequency-domain method: at a slow sweep the two agree, at a fast sweep their difference is the
transient effect), the critical speeds and natural frequencies, and the scene's parameters.
"""

from __future__ import annotations

import json
import logging
import time as _time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from crankbench.predict._validate import check_option
from crankbench.predict.errors import ConfigError

from .imperfections import add_noise_and_drift as _add_noise_and_drift
from .pulses import pickup_voltage, wheel_edges
from .scene import Scene

__all__ = ["synthesize", "SyntheticRun"]

log = logging.getLogger("crankbench")

TWO_PI = 2.0 * np.pi
RPM = TWO_PI / 60.0


@dataclass(frozen=True)
class SyntheticRun:
    """A synthetic record and its ground truth.

    Attributes
    ----------
    record : xarray.Dataset
        The Record (``measure.record`` schema).
    truth : xarray.Dataset
        ``amplitude`` and ``phase`` over (``channel``, ``order``, ``time``) with ``rpm`` along
        ``time`` and ``units`` along ``channel``; ``amplitude_steady`` (torsional channels);
        ``critical_*`` over ``critical`` (resonance peaks of the damped model the record was
        made with: mode, order, speed_rpm, frequency_hz, damping_ratio, major);
        ``predicted_critical_*`` over ``predicted`` (undamped critical speeds of
        :mod:`predict.torsion`, for comparison); ``natural_frequency_hz``/``damping_ratio``
        over ``mode``; attrs with the scene and fidelity.
    scene : Scene
    fidelity : dict
        Settings used and error estimates (integration rate, modal split, interpolation).
    elapsed_s : float
        Wall time of the synthesis.
    """

    record: object
    truth: object
    scene: Scene
    fidelity: dict = field(default_factory=dict)
    elapsed_s: float = float("nan")

    def write(self, path, *, overwrite=False):
        """Write record and truth (HDF5 group ``truth``) atomically (:func:`measure.io.write`)."""
        from crankbench.measure.io import write

        write(self.record, path, truth=self.truth, overwrite=overwrite)

    def to_frame(self):
        """One row per channel: ``channel``, ``quantity``, ``units``, ``samples``, ``rms``."""
        import pandas as pd

        rows = []
        for name, var in self.record.data_vars.items():
            values = np.asarray(var.values, float)
            rows.append({"channel": name, "quantity": var.attrs.get("quantity"),
                         "units": var.attrs.get("units"),
                         "sample_rate_hz": var.attrs.get("sample_rate", np.nan),
                         "samples": values.size,
                         "rms": float(np.sqrt(np.mean(values**2))) if var.attrs.get(
                             "quantity") != "pulse_times" else np.nan})
        return pd.DataFrame(rows)

    def plot(self, ax=None, *, channel=None, orders=None):
        """Truth order amplitudes of one channel against speed; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots() if ax is None else (ax.figure, ax)
        truth = self.truth
        if "channel" not in truth.dims:
            ax.plot(truth["time"], truth["rpm"])
            ax.set_xlabel("time (s)")
            ax.set_ylabel("speed (rpm)")
            return fig
        ch = channel or str(truth["channel"].values[0])
        amp = truth["amplitude"].sel(channel=ch)
        peak = amp.max("time")
        pick = orders if orders is not None else truth["order"].values[
            np.argsort(-peak.values)[:5]]
        for q in pick:
            ax.plot(truth["rpm"], amp.sel(order=q), label=f"order {q:g}")
        ax.set_xlabel("speed (rpm)")
        ax.set_ylabel(f"{ch} amplitude ({truth['units'].sel(channel=ch).item()})")
        ax.legend(fontsize="small")
        return fig


def synthesize(scene, *, method="split", integration_rate=None):
    """Synthesize a test-bench record from a scene.

    Parameters
    ----------
    scene : Scene or path-like
        The scene (a path is read with :meth:`Scene.from_toml`).
    method : {"split", "full"}
        Torsional integration: ``"full"`` integrates every mode in time, ``"split"`` (default)
        only those the orders sweep through or below, the others quasi-statically
        (:meth:`.torsional.ModalModel.respond`; relative difference about 1e-4 on a 40 s
        run-up).
    integration_rate : float, optional
        Time step of the torsional integration, Hz. Default: the fastest torsiograph channel,
        and at least 8 samples per period of the highest order frequency (the integration is
        exact for any step; the rate sets the accuracy of interpolating the motion between
        samples for pulse edges, about ``(2 pi f h)**4 / 384``, reported in ``fidelity``).

    Returns
    -------
    SyntheticRun

    References
    ----------
    Jiaotong University, *IC-engine dynamics*, 1958, part 2 ch. 4 (critical speeds, resonance
    amplitudes and curves) and ch. 5 (torsiograph records); Liang 1948 ch. 4 and ch. 9.

    Examples
    --------
    >>> from pathlib import Path
    >>> root = Path(__file__).resolve().parents[2]
    >>> run = synthesize(root / "sample_data/scenes/i4_runup.toml")
    >>> sorted(run.truth["amplitude"].dims)
    ['channel', 'order', 'time']
    """
    t_start = _time.perf_counter()
    if not isinstance(scene, Scene):
        scene = Scene.from_toml(scene)
    check_option(method, "method", ("split", "full"))
    rng = np.random.default_rng(scene.seed)
    engine = scene.engine
    prof = scene.profile
    duration = prof.duration
    step = 0.5 if engine.cycle == 4 else 1.0
    orders = np.arange(step, scene.max_order + step / 2, step)
    psi0 = np.radians(scene.start_angle_deg)
    speed_max = float(prof.speed_rpm.max()) * RPM
    f_max = scene.max_order * speed_max / TWO_PI
    excitation = _excitation(scene, orders)
    channels: dict = {}
    truth_rows: list = []          # (channel, units, kind, amp (o, t), phase (o, t), steady)
    t_truth = np.arange(0.0, duration + 1e-9, 1.0 / scene.truth_rate)
    rpm_truth = prof.speed(t_truth) / RPM
    load_truth = scene.load.scale(rpm_truth)
    crank_vibration = {}
    fidelity = {"method": method, "max_order": float(scene.max_order),
                "orders": int(orders.size), "truth_rate_hz": float(scene.truth_rate),
                "max_sweep_rate_rpm_per_s": prof.max_sweep_rate()}

    # ---------------------------------------------------------------- torsional ----------
    tors = [s for s in scene.sensors if s.kind in ("torsiograph", "encoder", "tacho")]
    modal = None
    if tors:
        from .torsional import ModalModel, order_forcing

        system = scene.shaftline
        rates = [s.sample_rate for s in tors if s.kind == "torsiograph"]
        rate = float(integration_rate or max(rates + [8.0 * f_max, 1000.0]))
        n_t = int(np.ceil(duration * rate)) + 1
        tg = np.arange(n_t) / rate
        psi = psi0 + prof.angle(tg)
        spd = prof.speed(tg)
        load_fn = lambda w: scene.load.scale(w / RPM)  # noqa: E731 - gas scale vs speed
        modal = ModalModel.from_system(system, omega=float(np.mean(spd)),
                                       max_frequency_hz=2.0 * f_max)
        gas, inertia = order_forcing(system, excitation, orders)
        from .pressure import cylinder_nodes

        crank_nodes = cylinder_nodes(scene)          # pressure follows its cylinder's angle
        node_names = sorted({s.params["node"] for s in tors} | set(crank_nodes.values()),
                            key=system.node_names.index)
        nodes = [modal.node_index(nm) for nm in node_names]
        ratio = modal.node_ratio[nodes]
        x_tot = np.zeros((len(nodes), n_t))
        v_tot = np.zeros((len(nodes), n_t))
        it = np.clip(np.rint(t_truth * rate).astype(int), 0, n_t - 1)
        amp_x = np.zeros((len(nodes), orders.size, it.size))
        ph_x = np.zeros_like(amp_x)
        amp_v = np.zeros_like(amp_x)
        ph_v = np.zeros_like(amp_x)
        diagnostics: dict = {}
        for k, q in enumerate(orders):
            x, v = modal.respond(tg, psi, q, gas[k], inertia[k], spd, load=load_fn,
                                 nodes=nodes, method=method, diagnostics=diagnostics)
            x_tot += x.real
            v_tot += v.real
            back = np.exp(-1j * q * psi[it])
            amp_x[:, k] = np.abs(x[:, it]) * ratio[:, None]
            ph_x[:, k] = np.angle(x[:, it] * back)
            amp_v[:, k] = np.abs(v[:, it]) * ratio[:, None]
            ph_v[:, k] = np.angle(v[:, it] * back)
        crank_vibration = {name: (tg, x_tot[node_names.index(node)])
                           for name, node in crank_nodes.items()}
        steady_x, steady_v = _steady_state(system, excitation, orders, rpm_truth, load_truth,
                                           nodes)
        fidelity.update(integration_rate_hz=rate, modal_condition=modal.condition,
                        rigid_body_regularised=modal.regularised,
                        damping="the model's own: steady state by its exact harmonic solve "
                                "(hysteretic loss factors included); each mode's sweep "
                                "transient with its damping at that mode's frequency",
                        steady_interpolation_rel_error=float(
                            diagnostics.get("steady_interpolation_rel_error", 0.0)),
                        steady_points=int(diagnostics.get("steady_points", 0)),
                        hermite_interpolation_rel_error=float(
                            (TWO_PI * f_max / rate) ** 4 / 384.0))
        for s in tors:
            i = node_names.index(s.params["node"])
            if s.kind == "torsiograph":
                if s.params["quantity"] == "angle":
                    data_g, units, quantity = x_tot[i] * ratio[i], "rad", "angle"
                    amp, ph, st = amp_x[i], ph_x[i], steady_x[:, :, i].T
                else:
                    data_g, units, quantity = v_tot[i] * ratio[i], "rad/s", "angular_velocity"
                    amp, ph, st = amp_v[i], ph_v[i], steady_v[:, :, i].T
                fs = float(s.sample_rate)
                ts = np.arange(int(np.floor(duration * fs)) + 1) / fs
                data = _resample(tg, data_g, ts, rate, fs,
                                 v_tot[i] * ratio[i] if quantity == "angle" else None)
                data = _read_out(data, ts, s.imperfections, rng, s, quantity)
                channels[s.name] = dict(data=data, sample_rate=fs, units=units,
                                        quantity=quantity,
                                        attrs={**_instrument_attrs(s), "node": s.params["node"]},
                                        location=s.params.get("location", s.params["node"]),
                                        direction="torsional")
                truth_rows.append((s.name, units, s.kind, amp, ph, st))
                continue
            edges, clean = wheel_edges(
                prof, start_angle=psi0, ratio=float(ratio[i]), grid_time=tg,
                vibration=x_tot[i], vibration_velocity=v_tot[i],
                pulses_per_rev=s.params["pulses_per_rev"],
                missing_teeth=s.params["missing_teeth"],
                tdc_offset=np.radians(s.params["tdc_offset_deg"]),
                imperfections=s.imperfections, rng=rng, duration=duration)
            attrs = {"node": s.params["node"], "tdc_offset_deg": float(s.params["tdc_offset_deg"])}
            if s.kind == "tacho" and s.params.get("output") == "analogue":
                fs = float(s.sample_rate)
                ts = np.arange(int(np.floor(duration * fs)) + 1) / fs
                volts = pickup_voltage(clean, time=ts, params=s.params, profile=prof)
                volts = _read_out(volts, ts, s.imperfections, rng)
                channels[s.name] = dict(data=volts, sample_rate=fs, units="V",
                                        quantity="voltage",
                                        location=s.params.get("location", s.params["node"]),
                                        attrs={**attrs,
                                               "pulses_per_rev": s.params["pulses_per_rev"],
                                               "missing_teeth": s.params["missing_teeth"]})
                continue
            channels[s.name] = dict(data=edges, units="s", quantity="pulse_times",
                                    pulses_per_rev=s.params["pulses_per_rev"],
                                    missing_teeth=s.params["missing_teeth"],
                                    location=s.params.get("location", s.params["node"]),
                                    attrs=attrs)
            truth_rows.append((s.name, "rad", s.kind, amp_x[i], ph_x[i], steady_x[:, :, i].T))

    # ---------------------------------------------------------------- mounts -------------
    vib = [s for s in scene.sensors if s.kind == "vibrograph"]
    if vib:
        _mount_channels(scene, vib, excitation, orders, psi0, t_truth, rpm_truth, load_truth,
                        rng, channels, truth_rows)
        fidelity["mount_response"] = "quasi-steady (no mount-mode transient)"

    # ---------------------------------------------------------------- others -------------
    pressure_truth = {}
    for s in scene.sensors:
        if s.kind == "pressure":
            from .pressure import pressure_channel

            channels[s.name], pressure_truth[s.name] = pressure_channel(
                scene, s, psi0, rng, vibration=crank_vibration.get(s.name))
        elif s.kind == "speed":
            fs = float(s.sample_rate)
            ts = np.arange(int(np.floor(duration * fs)) + 1) / fs
            data = _read_out(prof.speed(ts), ts, s.imperfections, rng)
            channels[s.name] = dict(data=data, sample_rate=fs, units="rad/s",
                                    quantity="rotational_speed",
                                    location=s.params.get("location", "bench speed channel"))
    # keep the scene's sensor order
    channels = {s.name: channels[s.name] for s in scene.sensors if s.name in channels}

    from crankbench.measure.record import make_record

    record = make_record(channels, attrs={
        "source": f"synthetic: {Path(scene.source).name}",
        "engine_id": engine.name, "test_id": scene.name, "synthetic": 1,
        "seed": int(scene.seed)})
    truth = _truth_dataset(scene, orders, t_truth, rpm_truth, truth_rows, modal, fidelity)
    if pressure_truth:                           # measure.synth.pressure.pressure_truth reads it
        truth.attrs["pressure"] = json.dumps(pressure_truth)
    elapsed = _time.perf_counter() - t_start
    log.debug("synthesized %r: %d channels, %.1f s of record in %.2f s", scene.name,
             len(channels), duration, elapsed)
    return SyntheticRun(record=record, truth=truth, scene=scene, fidelity=fidelity,
                        elapsed_s=elapsed)


# ------------------------------------------------------------------------------------------
_INSTRUMENT_KIND = {"angle": "displacement", "displacement": "displacement",
                    "angular_velocity": "velocity", "velocity": "velocity",
                    "acceleration": "acceleration"}


def _instrument(spec, quantity):
    """The seismic instrument of a sensor (None if it has none)."""
    if "instrument_frequency" not in spec.params:
        return None
    from crankbench.measure.instruments import SeismicInstrument

    return SeismicInstrument(spec.params["instrument_frequency"],
                             spec.params["instrument_damping"], _INSTRUMENT_KIND[quantity])


def _read_out(data, time, imperfections, rng, spec=None, quantity=None):
    """The sensor's instrument response (if any), then its noise and drift."""
    inst = None if spec is None else _instrument(spec, quantity)
    if inst is not None:
        time = np.asarray(time, float)
        data = inst.simulate(data, fs=1.0 / (time[1] - time[0]))
    return _add_noise_and_drift(data, time, imperfections, rng)


def _excitation(scene, orders):
    from crankbench.predict.torsion.excitation import engine_excitation

    try:
        return engine_excitation(scene.engine, imep=scene.load.imep, orders=orders)
    except Exception as exc:  # a model without bore/combustion data
        if scene.engine.bore is None:
            raise ConfigError(f"scene {scene.name!r}: the engine {scene.engine.name!r} has no "
                              "bore; the torque excitation needs it") from exc
        raise


def _resample(tg, data, ts, rate, fs, derivative=None):
    """Sample ``data`` (on the uniform grid ``tg``) at times ``ts``."""
    if fs == rate and ts.size <= tg.size:
        return data[: ts.size].copy()
    if derivative is not None:
        from scipy.interpolate import CubicHermiteSpline

        return CubicHermiteSpline(tg, data, derivative)(np.clip(ts, tg[0], tg[-1]))
    from scipy.interpolate import CubicSpline

    return CubicSpline(tg, data)(np.clip(ts, tg[0], tg[-1]))


def _steady_state(system, excitation, orders, rpm, load, nodes):
    """Steady-state node angles/velocities per order from predict.torsion (the prediction)."""
    g = excitation.harmonics(np.array([0.0]), orders)[0]
    i1 = excitation.harmonics(np.array([1.0]), orders)[0] - g
    w = np.maximum(rpm, 1e-9) * RPM
    harm = load[:, None, None] * g[None] + (w**2)[:, None, None] * i1[None]
    res = system.forced_response(np.maximum(rpm, 1e-9), torque=harm, orders=orders,
                                 superpose=False)
    ang = np.abs(res.angle[:, :, nodes])                          # (n_s, n_o, nodes), real
    vel = ang * (orders[None, :, None] * w[:, None, None])
    return ang, vel


def _mount_channels(scene, sensors, excitation, orders, psi0, t_truth, rpm_truth, load_truth,
                    rng, channels, truth_rows):
    import math

    from .torsional import _cis
    from .vibrograph import MountChannels

    mounted = scene.mounts
    names = {m.name: m.position for m in mounted.mounts}
    points = []
    for s in sensors:
        if "point" in s.params:
            points.append(s.params["point"])
        else:
            if s.params["mount"] not in names:
                from crankbench.predict._validate import suggest

                raise ConfigError(f"sensor {s.name!r}: mount={s.params['mount']!r} is not a mount "
                                  f"of the model{suggest(s.params['mount'], names)}; mounts: "
                                  f"{', '.join(names)}")
            points.append(names[s.params["mount"]])
    prof = scene.profile
    speeds = prof.speed_rpm * RPM
    n_grid = 150 if np.ptp(speeds) > 0 else 1
    grid = np.linspace(speeds.min(), speeds.max(), n_grid)
    mc = MountChannels(mounted, scene.engine, excitation, orders, np.array(points), grid,
                       counterweights=tuple(scene.balance_masses) + tuple(scene.imbalance))
    load_fn = lambda w: scene.load.scale(w / RPM)  # noqa: E731
    step = float(orders[0])
    # per sensor: response tables on the speed grid and the orders worth synthesising
    tables, keep = [], []
    for p, s in enumerate(sensors):
        tab = np.array([mc.table(k, p, s.params["direction"], s.params["quantity"], load_fn)
                        for k in range(orders.size)])                      # (n_o, n_grid)
        amp = np.abs(tab)
        tables.append(tab)
        keep.append(np.flatnonzero(amp.max(axis=1) > 1e-9 * max(amp.max(), 1e-300)))
        # truth on the truth grid
        at = np.array([np.interp(rpm_truth * RPM, grid, tab[k].real)
                       + 1j * np.interp(rpm_truth * RPM, grid, tab[k].imag)
                       if n_grid > 1 else np.full(t_truth.size, tab[k, 0])
                       for k in range(orders.size)])
        units = {"acceleration": "m/s^2", "velocity": "m/s", "displacement": "m"}[
            s.params["quantity"]]
        truth_rows.append((s.name, units, s.kind, np.abs(at), np.angle(at), None))
    # sensors sharing a sample rate share the crank angle, speed and carriers
    by_rate: dict = {}
    for p, s in enumerate(sensors):
        by_rate.setdefault(float(s.sample_rate), []).append(p)
    data = {}
    chunk = 1 << 19
    for fs, members in by_rate.items():
        n = int(np.floor(prof.duration * fs)) + 1
        for p in members:
            data[p] = np.zeros(n)
        needed = sorted(set().union(*[set(keep[p].tolist()) for p in members]))
        if not needed:
            continue
        multiples = [int(round(orders[k] / step)) for k in needed]
        base_mult = math.gcd(*multiples)
        for a in range(0, n, chunk):
            ts = np.arange(a, min(n, a + chunk)) / fs
            psi = psi0 + prof.angle(ts)
            spd = prof.speed(ts)
            if n_grid > 1:
                u = np.clip((spd - grid[0]) / (grid[1] - grid[0]), 0.0, n_grid - 1 - 1e-9)
                j = u.astype(np.int64)
                w = u - j
            base = _cis(base_mult * step * psi)
            carrier = np.ones_like(base)
            power = 0
            for k, m in zip(needed, multiples):
                while power < m // base_mult:
                    carrier *= base
                    power += 1
                for p in members:
                    if k not in keep[p]:
                        continue
                    tab = tables[p][k]
                    if n_grid > 1:
                        amp = tab[j] + w * (tab[j + 1] - tab[j])
                    else:
                        amp = tab[0]
                    data[p][a:a + ts.size] += (amp * carrier).real
    for p, s in enumerate(sensors):
        fs = float(s.sample_rate)
        ts = np.arange(data[p].size) / fs
        values = _read_out(data[p], ts, s.imperfections, rng, s, s.params["quantity"])
        units = truth_rows[-len(sensors) + p][1]
        attrs = dict(_instrument_attrs(s), position=[float(v) for v in points[p]])
        if "mount" in s.params:
            attrs["mount"] = s.params["mount"]
        channels[s.name] = dict(data=values, sample_rate=fs, units=units,
                                quantity=s.params["quantity"], attrs=attrs,
                                location=s.params.get("location", s.params.get(
                                    "mount", f"point {points[p]}")),
                                direction=s.params["direction"])


def _instrument_attrs(spec):
    if "instrument_frequency" not in spec.params:
        return {}
    return {"instrument_natural_frequency": float(spec.params["instrument_frequency"]),
            "instrument_damping_ratio": float(spec.params["instrument_damping"])}


def _truth_dataset(scene, orders, t_truth, rpm_truth, rows, modal, fidelity):
    import xarray as xr

    coords = {"time": ("time", t_truth, {"units": "s"}),
              "rpm": ("time", rpm_truth, {"units": "rpm", "long_name": "mean speed"}),
              "order": ("order", orders, {"units": "1"})}
    data_vars = {}
    if rows:
        names = [r[0] for r in rows]
        coords["channel"] = ("channel", names)
        coords["units"] = ("channel", [r[1] for r in rows])
        coords["kind"] = ("channel", [r[2] for r in rows])
        data_vars["amplitude"] = (("channel", "order", "time"), np.stack([r[3] for r in rows]),
                                  {"amplitude": "peak", "long_name": "order amplitude",
                                   "units_by_channel": "see coordinate 'units'"})
        data_vars["phase"] = (("channel", "order", "time"), np.stack([r[4] for r in rows]),
                              {"units": "rad", "convention": "signal = amplitude * cos(order * "
                               "psi + phase), psi = mean crank angle of cylinder 1 from firing "
                               "TDC"})
        steady = np.stack([r[5] if r[5] is not None else np.full((orders.size, t_truth.size),
                                                                 np.nan) for r in rows])
        data_vars["amplitude_steady"] = (("channel", "order", "time"), steady,
                                         {"amplitude": "peak", "long_name": "steady-state "
                                          "amplitude at the same speed (predict.torsion."
                                          "forced_response: the prediction)"})
    if scene.shaftline is not None:
        prof = scene.profile
        span = (float(prof.speed_rpm.min()), float(prof.speed_rpm.max()))
        pred = scene.shaftline.critical_speeds(orders, span)
        data_vars.update({
            "predicted_critical_mode": ("predicted", pred["mode"].to_numpy(int)),
            "predicted_critical_order": ("predicted", pred["order"].to_numpy(float)),
            "predicted_critical_speed_rpm": ("predicted", pred["speed_rpm"].to_numpy(float),
                                             {"units": "rpm", "long_name": "undamped critical "
                                              "speeds of predict.torsion (the prediction)"}),
            "predicted_critical_major": ("predicted", pred["major"].to_numpy(bool))})
        if modal is not None:
            table = modal.critical_speeds(orders, span,
                                          major=scene.shaftline.major_orders(orders))
            data_vars.update({
                "critical_mode": ("critical", table["mode"].to_numpy(int)),
                "critical_order": ("critical", table["order"].to_numpy(float)),
                "critical_speed_rpm": ("critical", table["speed_rpm"].to_numpy(float),
                                       {"units": "rpm", "long_name": "resonance peaks of the "
                                        "damped model the record was synthesized with"}),
                "critical_frequency_hz": ("critical", table["frequency_hz"].to_numpy(float),
                                          {"units": "Hz"}),
                "critical_damping_ratio": ("critical", table["damping_ratio"].to_numpy(float)),
                "critical_major": ("critical", table["major"].to_numpy(bool))})
    if modal is not None:
        fn, zeta = modal.natural_frequencies()
        data_vars["natural_frequency_hz"] = ("mode", fn, {"units": "Hz", "long_name":
                                             "damped natural frequencies of the time-domain "
                                             "model"})
        data_vars["damping_ratio"] = ("mode", zeta, {"units": "1"})
    attrs = {"scene": scene.name, "scene_source": scene.source, "seed": int(scene.seed),
             "scene_toml": json.dumps(scene.settings, default=str, sort_keys=True),
             "fidelity": json.dumps(fidelity, default=float, sort_keys=True),
             "profile": scene.profile.kind,
             "description": "ground truth of a synthetic crankbench record"}
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)
