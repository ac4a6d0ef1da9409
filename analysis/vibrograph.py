"""Vibrograph comparison: block and mount vibration per order against the engine on its mounts.

The engine block is a rigid body on elastic mounts (:class:`predict.mounts.MountedEngine`),
shaken per order by the loads of :func:`predict.mounts.block_excitation`: the free inertia
forces and moments of any layout (the balance model, counterweights and the model's
``[[balance.mass]]`` included) and the reaction to the crankshaft torque (gas part scaled with
the run's load law, inertia part with speed squared). For every vibrograph channel placed on
the block and every order the engine excites, the predicted order amplitude at the channel's
point and direction is set beside the measured order track, and judged:

* **sensor placement** — the channel attrs of the Record (see docs/DESIGN.md, "Vibrograph
  sensors"): ``position`` = [x, y, z] in m in the engine frame of :mod:`predict.mounts`
  (x along the crankshaft, y horizontal the way the top of the crank moves, z up), or a
  ``mount``/``location`` naming a mount of the model (its elastic centre); ``direction`` =
  ``x``/``y``/``z`` (optionally signed), ``axial``/``horizontal``/``vertical`` or three
  numbers. A channel that cannot be placed is listed with the reason, never guessed;
* **measured** — computed order tracking (:func:`analysis.order_track`, ``revolutions``
  revolution blocks, no overlap so that the blocks' noise is independent) against the record's
  speed reference; the 1-σ noise of each block from the track's broadband floor;
* **predicted** — the exact harmonic response of the mounted block at each block's speed
  (:meth:`MountedEngine.receptance`), quantity and direction of the channel, read through
  the channel's seismic instrument when its attrs name one (``instrument_natural_frequency``,
  ``instrument_damping_ratio``: :class:`measure.instruments.SeismicInstrument`);
* **verdict per (sensor, order)** (:class:`analysis.verdict.Verdict`) — over the blocks where
  the prediction is at least 10 % of its largest value, the ratio of the measured to the
  predicted peak and the median ratio must both lie within ``[1/(1+t), 1+t]``
  (``tolerance`` t, default 0.5). Orders predicted below ``min_snr`` times the noise or
  below ``significant_fraction`` of the channel's strongest order are listed, not required
  (pass when they agree all the same, else inconclusive: too weak to judge).
  An order the model calls balanced but the measurement shows clearly (above both
  thresholds) is judged against the vibration its manufacturing tolerances allow
  (:mod:`predict.balance_tolerance`), or inconclusive when the model states none.

With enough sensors the shaking force and moment vectors are estimated back from the same
tracks (:mod:`analysis.residuals`) and judged against the balance model and its tolerances.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from crankbench.measure.provenance import source_sha256
from crankbench.predict._validate import check_positive, check_range
from crankbench.predict.errors import AnalysisError, ConfigError, ModelError, RecordError

from .vibro_sensors import _QUANTITIES, VibroSensor, place_sensors  # the last two re-exported

__all__ = ["VibroSensor", "VibrographResult", "place_sensors", "load_engine_model",
           "model_kind", "compare_vibrograph"]

log = logging.getLogger("crankbench")

_TWO_PI = 2.0 * np.pi


def model_kind(path) -> str:
    """'shaftline' for a file with a ``[shaftline]`` table, 'engine' for an engine model.

    Raises
    ------
    ConfigError
        Neither table.
    """
    from crankbench.predict._toml import load_toml

    doc = load_toml(path, error=ConfigError)
    if "shaftline" in doc:
        return "shaftline"
    if "engine" in doc:
        return "engine"
    raise ConfigError(f"{path}: neither a [shaftline] nor an [engine] table; give a shaft-line "
                      "model or an engine model with [mounts]")


def load_engine_model(model):
    """Engine, mounted engine and balance spec of an engine TOML (or of a shaft-line TOML's
    engine).

    Returns
    -------
    (Engine, MountedEngine, BalanceSpec, str)

    Raises
    ------
    ConfigError
        The model has no ``[mounts]``.
    """
    from crankbench.predict._toml import load_toml
    from crankbench.predict.balance_tolerance import BalanceSpec
    from crankbench.predict.engine import Engine
    from crankbench.predict.mounts import MountedEngine

    path = Path(model)
    doc = load_toml(path, error=ConfigError)
    if "shaftline" in doc:
        ref = doc.table("shaftline").raw("engine", None)
        if not isinstance(ref, str):
            raise ConfigError(f"{path}: [shaftline] names no engine file; the vibrograph "
                              "comparison needs the engine model with [mounts]")
        path = (path.parent / ref).resolve()
        doc = load_toml(path, error=ConfigError)
    if "mounts" not in doc:
        raise ConfigError(f"{path}: has no [mounts] table; the vibrograph comparison needs the "
                          "engine on its mounts (mass, inertia, cg, [[mounts.mount]])")
    return (Engine.from_toml(path), MountedEngine.from_toml(path), BalanceSpec.from_toml(path),
            str(model))


@dataclass(frozen=True)
class VibrographResult:
    """Measured against predicted block/mount vibration per (sensor, order).

    Attributes
    ----------
    source, record_sha256, model_path : str
    sensors : tuple of VibroSensor
    skipped : tuple of (channel, reason)
        Vibrograph channels that could not be placed.
    table : pandas.DataFrame
        One row per (sensor, order): ``sensor``, ``order``, ``measured`` and ``predicted``
        (peak order amplitude over the judged speeds, SI units of the channel), ``ratio``,
        ``ratio_median``, ``speed_rpm`` (of the measured peak), ``noise`` (1-σ block noise),
        ``snr`` (predicted / noise), ``allowed`` (largest amplitude the model's
        manufacturing tolerances allow, NaN without), ``units``, ``significant``,
        ``verdict``, ``passed``, ``required``, ``rule``, ``reason``.
    verdicts : tuple of Verdict
    residuals : ResidualEstimate or None
    curves : dict
        ``{(sensor, order): (speed_rpm, measured, predicted)}`` per block.
    measured_excitation : Excitation, SpeedExcitation or None
        The excitation from the record's cylinder pressure (``indicator`` of
        :func:`compare_vibrograph`); with it the table has ``predicted_measured_excitation``
        and ``ratio_measured_excitation``, and ``curves_measured_excitation`` holds
        ``{(sensor, order): predicted}`` per block from it.
    indicator : dict
        ``{channel: IndicatorResult}`` the measured excitation rests on (empty without).
    speed_range_rpm : tuple
    sweep_rate_rpm_per_s : float
    tolerance : float
    settings : dict
    """

    source: str
    record_sha256: str
    model_path: str
    sensors: tuple
    skipped: tuple
    table: object
    verdicts: tuple
    residuals: object
    curves: dict
    speed_range_rpm: tuple
    sweep_rate_rpm_per_s: float
    tolerance: float
    settings: dict = field(default_factory=dict)
    measured_excitation: object = None
    curves_measured_excitation: dict = field(default_factory=dict)
    indicator: dict = field(default_factory=dict)

    @property
    def verdict(self):
        """Overall verdict of the per-(sensor, order) checks and the residual checks."""
        from .verdict import combine

        extra = tuple(self.residuals.verdicts) if self.residuals is not None else ()
        return combine(self.verdicts + extra, name="vibrograph comparison")

    @property
    def passed(self) -> bool:
        return self.verdict.status == "pass"

    def to_frame(self):
        """The (sensor, order) table (copy)."""
        return self.table.copy()

    def worst(self):
        """The judged row whose ratio is furthest from 1 (log scale), or None."""
        t = self.table[self.table["required"] & self.table["verdict"].isin(["pass", "fail"])
                       & np.isfinite(self.table["ratio"]) & (self.table["ratio"] > 0)]
        if not len(t):
            return None
        return t.iloc[int(np.argmax(np.abs(np.log(t["ratio"].to_numpy(float)))))]

    def summary(self) -> dict:
        """One flat row for batch tables and ``--json``."""
        w = self.worst()
        res = self.residuals
        rv = None
        if res is not None:
            from .verdict import combine

            rv = combine(res.verdicts, name="residuals").status
        return {"record": self.source, "sha256": self.record_sha256, "model": self.model_path,
                "sensors": len(self.sensors), "sensors_skipped": len(self.skipped),
                "speed_min_rpm": self.speed_range_rpm[0],
                "speed_max_rpm": self.speed_range_rpm[1],
                "sweep_rate_rpm_per_s": self.sweep_rate_rpm_per_s,
                "vibration_rows": int(len(self.table)),
                "vibration_judged": int(self.table["required"].sum()) if len(self.table) else 0,
                "vibration_failed": int(((self.table["verdict"] == "fail")
                                         & self.table["required"]).sum())
                if len(self.table) else 0,
                "vibration_worst_ratio": float(w["ratio"]) if w is not None else float("nan"),
                "vibration_worst": f"{w['sensor']} order {w['order']:g}" if w is not None
                else "",
                "residual_verdict": rv or "not estimated",
                "vibration_verdict": self.verdict.status, "passed": self.passed}

    def plot(self, ax=None, *, sensor=None):
        """Measured (solid) and predicted (dashed) order amplitudes of one sensor against
        speed, the judged orders, and (dotted) the prediction from the measured excitation
        when there is one; returns the figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots(figsize=(7, 4))
        else:
            fig = ax.figure
        name = sensor or (self.sensors[0].channel if self.sensors else None)
        rows = self.table[(self.table["sensor"] == name) & self.table["required"]]
        for _, r in rows.iterrows():
            rpm, meas, pred = self.curves[(name, float(r["order"]))]
            line, = ax.semilogy(rpm, meas, lw=1.0, label=f"order {r['order']:g}")
            ax.semilogy(rpm, pred, "--", color=line.get_color(), lw=1.2)
            px = self.curves_measured_excitation.get((name, float(r["order"])))
            if px is not None:
                ax.semilogy(rpm, px, ":", color=line.get_color(), lw=1.5)
        units = rows["units"].iloc[0] if len(rows) else ""
        ax.set_xlabel("speed (rpm)")
        ax.set_ylabel(f"order amplitude, peak ({units})")
        ax.set_title(f"{name}: measured (solid) and predicted (dashed" + (
            "; dotted: from the measured pressure)" if self.curves_measured_excitation
            else ")"), fontsize=9)
        if len(rows):
            ax.legend(fontsize=7, ncol=2)
        ax.grid(alpha=0.3)
        return fig


def _orders(engine, orders, max_order, fs_min, hi_rpm):
    step = 0.5 if engine.cycle == 4 else 1.0
    if orders is None:
        orders = np.arange(step, float(max_order) + step / 2, step)
    orders = np.asarray([float(o) for o in orders], float)
    if orders.size == 0 or (orders <= 0).any():
        raise ConfigError(f"orders={orders.tolist()} must be positive numbers")
    keep = orders * hi_rpm / 60.0 < 0.4 * fs_min
    if not keep.any():
        raise AnalysisError(f"no order lies below 0.4 × the lowest sample rate ({fs_min:g} Hz) "
                            f"at {hi_rpm:.0f} rpm")
    if not keep.all():
        log.info("orders above 0.4 × the sample rate at %.0f rpm not compared: %s", hi_rpm,
                 ", ".join(f"{o:g}" for o in orders[~keep]))
    return orders[keep]


def _phase_reference(rec, sensor_name, rpm, fs, revolutions, block_times):
    """At each block time, the angle of cylinder 1 from its TDC minus the tracker's integrated
    angle, as ``e^{i delta}`` (order 1), from a tacho with a TDC reference; (None, reason)
    without."""
    from crankbench.measure.tacho import angle_from_pulses

    from .orders import order_track

    for name in rec.data_vars:
        v = rec[name]
        if v.attrs.get("quantity") != "pulse_times" or "tdc_offset_deg" not in v.attrs:
            continue
        ppr = int(v.attrs.get("pulses_per_rev", 0))
        missing = int(v.attrs.get("missing_teeth", 0))
        if ppr < 1 or (missing == 0 and ppr != 1):
            continue
        try:
            trace = angle_from_pulses(np.asarray(v.values, float), pulses_per_rev=ppr,
                                      missing_teeth=missing,
                                      tdc_offset_deg=float(v.attrs["tdc_offset_deg"]))
            var = rec[sensor_name]
            dim = var.dims[0]
            t = (np.asarray(rec[dim].values, float) if dim in rec.coords
                 else np.arange(var.size) / fs)
            ref = order_track(np.cos(trace.at(t)), fs=fs, speed_rpm=rpm, orders=[1.0],
                              revolutions=revolutions, overlap=0.0)
        except (AnalysisError, RecordError, ValueError) as exc:
            log.info("tacho %r gives no phase reference: %s", name, exc)
            continue
        ph = np.unwrap(ref["phase"].sel(order=1.0).values)
        ph = np.interp(block_times, ref["time"].values, ph)
        return np.exp(1j * ph), f"TDC of cylinder 1 from tacho {name!r}"
    return None, "relative: no tacho with a TDC reference (attr 'tdc_offset_deg')"


def _instrument(attrs, quantity):
    """The seismic instrument a channel's attrs describe (``instrument_natural_frequency`` Hz,
    ``instrument_damping_ratio``), whose reading the channel is; None without."""
    fn = attrs.get("instrument_natural_frequency")
    if fn is None:
        return None
    from crankbench.measure.instruments import SeismicInstrument

    return SeismicInstrument(float(fn), float(attrs.get("instrument_damping_ratio", 0.65)),
                             quantity)


def _measured_excitation(rec, engine, indicator, orders, load):
    """(excitation, note, indicator results) from the record's cylinder pressure, or
    (None, "", {})."""
    if indicator is None:
        return None, "", {}
    from crankbench.predict.errors import CrankbenchError

    from .excitation_compare import excitation_from_indicator
    from .pressure import indicator_analyses, pressure_channels

    try:
        if isinstance(indicator, str):
            if indicator != "auto":
                raise ConfigError(f"indicator={indicator!r} must be 'auto', None or a dict of "
                                  "IndicatorResult")
            if not pressure_channels(rec):
                return None, "", {}
            indicator = indicator_analyses(rec, engine)
        from .pressure import IndicatorResult

        if not isinstance(indicator, dict) or not all(
                isinstance(v, IndicatorResult) for v in indicator.values()):
            raise ConfigError("indicator= must be 'auto', None or a dict {channel: "
                              "IndicatorResult} (analysis.pressure.indicator_analyses), got "
                              f"{type(indicator).__name__}")
        exc, note = excitation_from_indicator(indicator, engine, orders=orders, load=load)
        return exc, note, dict(indicator)
    except ConfigError:
        raise
    except CrankbenchError as exc:
        log.warning("block vibration from the measured excitation skipped: %s", exc)
        return None, "", {}


def compare_vibrograph(record, model, *, load=None, speed_channel=None, orders=None,
                       max_order=12.0, tolerance=0.5, revolutions=8, significant_fraction=0.02,
                       min_snr=10.0, channels=None, residual_orders=None, speed_rpm=None,
                       indicator="auto", channel_map=None, progress=None) -> VibrographResult:
    """Compare a record's vibrograph channels with the engine model on its mounts.

    Parameters
    ----------
    record : path-like or xarray.Dataset
    model : path-like
        Engine TOML with ``[mounts]`` (or a shaft-line TOML, whose engine file is used).
    load : LoadCase or dict, optional
        Gas load for the torque reaction (default: the model's imep, constant).
    speed_channel : str, optional
    orders : sequence of float, optional
        Default: every order of the cycle up to ``max_order`` (0.5 steps for a 4-stroke).
    max_order : float
    tolerance : float
        Ratio band ``[1/(1+t), 1+t]`` for agreement.
    revolutions : int
        Order-tracking block, revolutions (resolution ``1/revolutions`` orders).
    significant_fraction : float
        Orders predicted below this fraction of the channel's strongest are not required.
    min_snr : float
        Orders predicted below ``min_snr`` × the block noise are not required.
    channels : sequence of str, optional
        Vibrograph channels (default: all placeable).
    residual_orders : sequence of int, optional
        Orders whose shaking force and moment are estimated back (default: the integer
        orders up to 8 that are compared).
    speed_rpm : float, optional
        Speed at which residual forces and moments are reported (default: the highest
        measured).
    indicator : "auto", dict or None
        Cylinder pressure for a second prediction from the *measured* excitation
        (:func:`analysis.excitation_compare.excitation_from_indicator`: the gas-torque
        reaction from the measured pressure, the inertia loads from the model): ``"auto"``
        analyses the record's pressure channels when it has any
        (:func:`analysis.pressure.indicator_analyses`; a failure is logged, not raised), a
        dict ``{channel: IndicatorResult}`` is used as given, None skips it. The table then
        has ``predicted_measured_excitation`` and ``ratio_measured_excitation`` (measured
        peak over that prediction's peak, same speeds) beside ``predicted``; the verdicts
        stay on the model's prediction.
    channel_map : path-like or ChannelMap, optional
        How to read ``record`` when it is a path (columns, units, sensor placement of a text
        or raw export: :func:`measure.read`'s ``map``).
    progress : callable, optional

    Returns
    -------
    VibrographResult

    Raises
    ------
    RecordError
        No vibrograph channel can be placed on the model (the reasons listed).
    ConfigError
        The model has no ``[mounts]``.

    Examples
    --------
    The shipped I4 block-accelerometer record against its engine model (order 2: the free
    second-order force and the torque reaction, m/s² peak at about 2950 rpm):

    >>> res = compare_vibrograph("sample_data/records/i4_runup.h5",
    ...                          "sample_data/engines/i4.toml")
    >>> row = res.table[res.table["order"] == 2.0].iloc[0]
    >>> round(float(row["predicted"]), 1), round(float(row["ratio"]), 2), res.verdict.status
    (24.8, 1.0, 'pass')
    """
    import pandas as pd

    from crankbench.predict.mounts import block_excitation

    from .orders import order_track
    from .pipeline import LoadCase, _load_record
    from .speedref import find_speed_channel, speed_reference
    from .verdict import Verdict

    tolerance = check_positive(tolerance, "tolerance", error=ConfigError)
    significant_fraction = check_range(significant_fraction, "significant_fraction", 0.0, 1.0,
                                       error=ConfigError)
    min_snr = check_positive(min_snr, "min_snr", error=ConfigError)

    def step(name):
        if progress is not None:
            progress(name)

    step("read")
    rec, source = _load_record(record, channel_map)
    engine, mounted, spec, model_path = load_engine_model(model)
    if load is None:
        load = LoadCase.from_record(rec, engine)      # the load the record states, if any
    load_stated = load is not None
    load = LoadCase.from_any(load, engine)
    sensors, skipped = place_sensors(rec, mounted, channels=channels)
    for name, why in skipped:
        log.info("channel %r not compared: %s", name, why)
    if not sensors:
        why = "; ".join(f"{n}: {r}" for n, r in skipped) or "the record has no acceleration, " \
            "velocity or displacement channel"
        raise RecordError(f"no vibrograph channel can be placed on the model {model_path}: {why}")
    rpms, lo, hi = {}, np.inf, 0.0
    for s in sensors:
        sc = speed_channel or find_speed_channel(rec, s.channel)
        r = np.asarray(speed_reference(rec, s.channel, speed_channel=sc), float)
        if not np.isfinite(r).any():
            raise RecordError(f"channel {s.channel!r}: no finite speed from {sc!r}")
        r = np.nan_to_num(r, nan=float(np.nanmedian(r)))
        rpms[s.channel] = (r, sc)
        lo, hi = min(lo, float(r.min())), max(hi, float(r.max()))
    fs_min = min(float(rec[s.channel].attrs["sample_rate"]) for s in sensors)
    orders = _orders(engine, orders, max_order, fs_min, hi)
    excitation = None
    try:
        from crankbench.predict.torsion.excitation import engine_excitation

        excitation = engine_excitation(engine, imep=load.imep, orders=orders)
    except (ModelError, ValueError) as exc:
        log.info("no gas-torque reaction predicted (%s); inertia loads only", exc)
    loads = block_excitation(engine, orders, excitation=excitation, counterweights=spec.masses)
    measured_x, x_note, indicator = _measured_excitation(rec, engine, indicator, orders, load)
    tol = None
    integer = [int(round(q)) for q in orders if abs(q - round(q)) < 1e-9]
    if integer:
        from crankbench.predict.balance_tolerance import allowed_residuals

        tol = allowed_residuals(engine, spec, omega=1.0, orders=integer)["tolerance"]

    step("order tracking")
    lo_band, hi_band = 1.0 / (1.0 + tolerance), 1.0 + tolerance
    rows, verdicts, curves, blocks, curves_x = [], [], {}, {}, {}
    rate, tracked = [], []
    for s in sensors:
        var = rec[s.channel]
        fs = float(var.attrs["sample_rate"])
        rpm, sc = rpms[s.channel]
        # dropouts (NaN spans) are masked by the tracker: their blocks are left out
        track = order_track(np.asarray(var.values, float), fs=fs, speed_rpm=rpm, orders=orders,
                            revolutions=revolutions, overlap=0.0)
        amp = np.asarray(track["amplitude"].values, float)                  # (n_o, n_b)
        noise = np.asarray(track["amplitude_noise"].values, float)
        ok = np.isfinite(amp).all(axis=0) & np.isfinite(noise) & (noise > 0)
        if ok.sum() < 3:
            skipped = skipped + ((s.channel, f"only {int(ok.sum())} order-tracking blocks "
                                              "without dropouts"),)
            continue
        t_b = track["time"].values[ok]
        rpm_b = np.asarray(track["rpm"].values, float)[ok]
        if rpm_b.size >= 2:
            rate.append(np.abs(np.gradient(rpm_b, t_b)))
        amp = amp[:, ok]
        meas_c = amp * np.exp(1j * np.asarray(track["phase"].values, float)[:, ok])
        noise = noise[ok]
        omega_b = rpm_b * np.pi / 30.0
        p = _QUANTITIES[s.quantity]
        # predicted complex amplitude per order and block; H: per unit load (F, M) at point
        h = np.empty((orders.size, omega_b.size, 6), complex)
        inst = _instrument(var.attrs, s.quantity)
        for k, q in enumerate(orders):
            g = mounted.receptance(q * omega_b / _TWO_PI, at=[s.position],
                                   directions=[s.direction], point=loads.point)[:, 0, :]
            h[k] = g * ((1j * q * omega_b) ** p)[:, None]
            if inst is not None:        # the channel is a seismic instrument's reading
                h[k] *= inst.frf(q * omega_b / _TWO_PI)[:, None]
        lf = load.scale(rpm_b)
        pred_c = np.einsum("kbj,kj->kb", h, loads.gas) * lf[None, :] + \
            np.einsum("kbj,kj->kb", h, loads.inertia) * (omega_b**2)[None, :]
        pred = np.abs(pred_c)
        pred_x = None
        if measured_x is not None:         # the gas roll from the measured pressure
            from crankbench.predict.gas_torque import torque_reaction

            roll = torque_reaction(engine, measured_x, orders, omega_b).T         # (n_o, n_b)
            if not getattr(measured_x, "speed_dependent", False):
                roll = roll * lf[None, :]
            pred_x = np.abs(np.einsum("kbj,kj->kb", h, loads.inertia) * (omega_b**2)[None, :]
                            + h[:, :, 3] * roll)
        blocks[s.channel] = dict(time=t_b, rpm=rpm_b, measured=meas_c, noise=noise, h=h,
                                 load=lf, fs=fs, speed_rpm=rpm)
        tracked.append(s)
        sigma = float(np.median(noise))
        strongest_p = float(pred.max()) if pred.size else 0.0
        strongest_m = float(amp.max()) if amp.size else 0.0
        basis = (f"{s.describe()}; COT {revolutions}-revolution blocks, "
                 f"{rpm_b.min():.0f}-{rpm_b.max():.0f} rpm, speed from {sc!r}; model "
                 f"{model_path}")
        for k, q in enumerate(orders):
            pk, mk = pred[k], amp[k]
            p_max = float(pk.max())
            if p_max <= 1e-9 * strongest_p:       # round-off of a balanced order: zero
                pk = np.zeros_like(pk)
                p_max = 0.0
            use = pk >= 0.1 * p_max if p_max > 0 else np.ones_like(pk, bool)
            m_peak = float(mk[use].max())
            p_peak = float(pk[use].max())
            j = int(np.flatnonzero(use)[np.argmax(mk[use])])
            ratio = m_peak / p_peak if p_peak > 0 else float("inf")
            with np.errstate(divide="ignore", invalid="ignore"):
                med = float(np.median(mk[use] / pk[use])) if p_peak > 0 else float("inf")
            allowed = float("nan")
            n = int(round(q))
            if tol is not None and abs(q - n) < 1e-9 and n in integer:
                i = integer.index(n)
                d_force = tol["force_forward"][i] + tol["force_backward"][i]
                d_moment = tol["moment_forward"][i] + tol["moment_backward"][i]
                if d_force > 0 or d_moment > 0:
                    extra = (omega_b**2) * (d_force * np.abs(h[k, :, 1:3]).sum(axis=1)
                                            + d_moment * np.abs(h[k, :, 4:6]).sum(axis=1))
                    allowed = float((pk + extra).max())
            snr = p_peak / sigma
            significant = p_peak >= significant_fraction * strongest_p and snr >= min_snr
            unexpected = (not significant and m_peak >= min_snr * sigma
                          and m_peak >= significant_fraction * strongest_m)
            name = f"{s.channel} order {q:g}"
            rule = (f"measured/predicted order amplitude (peak and median over the speeds where "
                    f"the prediction is >= 10 % of its largest) within [{lo_band:.2f}, "
                    f"{hi_band:.2f}]")
            gas_share = 0.0
            if not load_stated and measured_x is None and p_peak > 0:
                gas_k = np.abs(np.einsum("bj,j->b", h[k], loads.gas[k]) * lf)
                gas_share = float(gas_k[j] / max(pk[j], 1e-300))
            if significant and gas_share > 0.2:
                at = (f"imep {load.imep / 1e5:.4g} bar" if load.imep is not None else
                      "the engine's default combustion (predict.pressure)")
                v = Verdict.inconclusive(
                    name, rule=rule, basis=basis,
                    reason=f"ratio {ratio:.3g}, not judged: the gas-torque reaction is "
                           f"{100 * gas_share:.0f} % of the predicted amplitude and the run's "
                           f"load is not stated (the prediction assumes {at} at every speed); "
                           "give --imep and --load-law (or imep/load_law in the channel map's "
                           "[source]), or record the cylinder pressure")
            elif significant:
                ok = lo_band <= ratio <= hi_band and lo_band <= med <= hi_band
                v = Verdict.from_bool(name, ok, rule=rule, basis=basis,
                                      reason="" if ok else
                                      f"peak ratio {ratio:.3g}, median ratio {med:.3g}")
            elif unexpected:
                rule = ("an order the model predicts weak but the record shows clearly: "
                        "measured peak within what the model's manufacturing tolerances allow")
                if np.isfinite(allowed) and allowed > 0:
                    ok = m_peak <= allowed
                    v = Verdict.from_bool(name, ok, rule=rule, basis=basis,
                                          reason="" if ok else
                                          f"measured {m_peak:.3g} {s.units} above the allowed "
                                          f"{allowed:.3g}")
                else:
                    v = Verdict.inconclusive(
                        name, rule=rule, basis=basis,
                        reason=f"measured {m_peak:.3g} {s.units} where the model predicts "
                               f"{p_peak:.3g}; the model states no manufacturing tolerance "
                               "([balance] in the engine file) to judge it")
            else:
                why = (f"predicted {p_peak:.3g} {s.units} is below {min_snr:g} × the noise "
                       f"{sigma:.3g}" if snr < min_snr else
                       f"predicted {p_peak:.3g} {s.units} is below {significant_fraction:g} of "
                       f"the channel's strongest order ({strongest_p:.3g})")
                if snr >= 3.0 and p_peak > 0 and lo_band <= ratio <= hi_band:
                    v = Verdict.passed(name, rule=rule, basis=basis, required=False,
                                       reason=why)
                elif snr >= 3.0 and p_peak > 0:
                    v = Verdict.inconclusive(name, rule=rule, basis=basis, required=False,
                                             reason=f"ratio {ratio:.3g}, not judged: {why}")
                else:
                    v = Verdict.inconclusive(name, rule=rule, basis=basis, reason=why,
                                             required=False)
            if p_max == 0.0 and not unexpected:
                continue    # nothing predicted (round-off), nothing seen: not a row
            verdicts.append(v)
            rows.append(dict(sensor=s.channel, order=float(q), measured=m_peak,
                             predicted=p_peak, ratio=ratio, ratio_median=med,
                             speed_rpm=float(rpm_b[j]), noise=sigma, snr=snr,
                             allowed=allowed, units=s.units, quantity=s.quantity,
                             significant=bool(significant), verdict=v.status,
                             passed=v.status == "pass", required=v.required, rule=v.rule,
                             reason=v.reason))
            curves[(s.channel, float(q))] = (rpm_b, mk, pk)
            if pred_x is not None:         # same speeds as the model's peak
                px = float(pred_x[k][use].max())
                rows[-1].update(predicted_measured_excitation=px,
                                ratio_measured_excitation=m_peak / px if px > 0
                                else float("inf"))
                curves_x[(s.channel, float(q))] = pred_x[k]
    cols = ["sensor", "order", "measured", "predicted", "ratio", "ratio_median", "speed_rpm",
            "noise", "snr", "allowed", "units", "quantity", "significant", "verdict", "passed",
            "required", "rule", "reason"]
    if measured_x is not None:
        cols[4:4] = ["predicted_measured_excitation", "ratio_measured_excitation"]
    table = pd.DataFrame(rows, columns=cols)
    sweep = float(np.median(np.concatenate(rate))) if rate else 0.0

    step("residuals")
    residuals = None
    res_orders = [int(o) for o in (residual_orders if residual_orders is not None else
                                   [n for n in integer if n <= 8])]
    if res_orders and len(tracked) >= 3:
        from .residuals import estimate_residuals

        phase = {}
        for s in tracked:
            b = blocks[s.channel]
            phase[s.channel] = _phase_reference(rec, s.channel, b["speed_rpm"], b["fs"],
                                                revolutions, b["time"])
        residuals = estimate_residuals(
            blocks, [s.channel for s in tracked], orders, loads, engine, spec,
            phase=phase, residual_orders=res_orders, speed_rpm=speed_rpm,
            excitation_has_gas=excitation is not None)
    elif res_orders:
        log.info("residual forces and moments not estimated: %d sensor(s) tracked; at least 3 "
                 "(better 5 or more directions) are needed", len(tracked))
    settings = {"model": model_path, "orders": ", ".join(f"{o:g}" for o in orders),
                "order tracking": f"COT, {revolutions}-revolution blocks, no overlap, hann",
                "tolerance": f"ratio within [{lo_band:.3f}, {hi_band:.3f}]",
                "significant": f">= {significant_fraction:g} of the channel's strongest order "
                               f"and >= {min_snr:g} x the block noise",
                "load": f"{load.law}" + (f", imep {load.imep / 1e5:.4g} bar" if load.imep
                                         else ", model imep"),
                "gas-torque reaction": "yes" if excitation is not None else "no (no combustion "
                                                                            "data)",
                "measured excitation": x_note or "none (no cylinder pressure)",
                "balance masses": len(spec.masses),
                "manufacturing tolerances": "stated" if spec.stated else "none in the model",
                "sensors": "; ".join(s.describe() for s in sensors),
                "skipped": "; ".join(f"{n}: {r}" for n, r in skipped) or "none"}
    return VibrographResult(
        source=source, record_sha256=source_sha256(rec, missing=""), model_path=model_path,
        sensors=tuple(tracked), skipped=skipped, table=table, verdicts=tuple(verdicts),
        residuals=residuals, curves=curves, speed_range_rpm=(lo, hi),
        sweep_rate_rpm_per_s=sweep, tolerance=tolerance, settings=settings,
        measured_excitation=measured_x, curves_measured_excitation=curves_x,
        indicator=indicator)
