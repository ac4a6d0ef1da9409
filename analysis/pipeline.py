"""The end-to-end chain: record + shaft-line model → order analysis → prediction → comparison.

:func:`analyse` takes a Record (or a record file) and a shaft-line TOML and returns a
:class:`PipelineResult`: the order track of the torsional channel, the resonances found in
it, the predicted critical speeds with their resonance amplitudes at the measured node, the
assignment of one to the other, and the limit checks (vibratory stress against the model's
``[limits]``, vibration severity of any vibrograph channel). :func:`analysis.report.build`
turns the result into the test report. The CLI commands ``demo``, ``compare``, ``report`` and
``batch`` are thin layers over these two calls.

Steps and their fidelity knobs:

1. speed reference per sample (:func:`analysis.speedref.speed_reference`);
2. order tracking (:mod:`analysis.pipeline_tracking`) of every engine order up to
   ``max_order`` — Vold–Kalman (joint, default;
   ``bandwidth_orders`` sets its −3 dB width) or computed order tracking (``revolutions``);
3. :func:`analysis.find_resonances` (baseline stripping, modal fit, sweep correction);
4. (:mod:`analysis.pipeline_prediction`) the model's critical speeds in the measured speed
   range and the steady-state forced
   response (exact harmonic solve) at the measured node with the run's load law, refined
   around each critical (``refine_points`` speeds within ±6 %);
5. :func:`analysis.match_criticals`;
6. limit checks (:mod:`analysis.pipeline_limits`): measured vibratory stress = measured order
   amplitude × the model's stress per unit node amplitude of that order (the classical
   torsiograph evaluation), superposed over the cycle with the model's phases, against the
   continuous/transient limits;
7. block/mount vibration: every vibrograph channel placed on the engine block against the
   engine model on its mounts, per (sensor, order) (:mod:`analysis.vibrograph`).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from crankbench.measure.provenance import source_sha256
from crankbench.predict._validate import check_option, check_positive, suggest
from crankbench.predict.errors import AnalysisError, ConfigError, RecordError

from .pipeline_limits import _limit_checks
from .pipeline_prediction import _prediction, predicted_response  # noqa: F401 (re-exported)
from .pipeline_tracking import _track, _tracking_settings

__all__ = ["LoadCase", "PipelineResult", "analyse", "torsional_channel"]

log = logging.getLogger("crankbench")

_TORSIONAL = ("angle", "angular_velocity")


@dataclass(frozen=True)
class LoadCase:
    """Engine load along the run for the predicted excitation.

    Attributes
    ----------
    imep : float or None
        Mean indicated pressure, Pa (at ``reference_rpm`` for the propeller law); None takes
        the model's ``imep`` (``[shaftline] imep``) or the engine's combustion data.
    law : {'constant', 'propeller'}
        Propeller law: gas load ∝ speed². The factor scales the whole gas torque, the
        compression (motored) part included; the synthetic bench's pressure channels follow
        the same law (gauge pressure × factor, :mod:`measure.synth.pressure`), so a synthetic
        record agrees with it. A real cylinder at part load keeps its compression torque:
        at low speed on a propeller law the prediction then underestimates the gas-torque
        harmonics, most at the major orders, whose rigid-body response dominates at low
        speed. The measured-excitation comparison (:mod:`analysis.excitation_compare`) shows
        it whenever the record has cylinder pressure.
    reference_rpm : float or None
        Speed where ``imep`` applies for the propeller law (default: the engine's rated
        speed).

    Examples
    --------
    >>> load = LoadCase(imep=2.4e6, law="propeller", reference_rpm=720.0)
    >>> print(load.scale([360.0, 720.0]))
    [0.25 1.  ]
    """

    imep: float | None = None
    law: str = "constant"
    reference_rpm: float | None = None

    def __post_init__(self):
        check_option(self.law, "law", ("constant", "propeller"), error=ConfigError)
        if self.imep is not None:
            check_positive(self.imep, "imep", error=ConfigError)
        if self.reference_rpm is not None:
            check_positive(self.reference_rpm, "reference_rpm", error=ConfigError)

    def scale(self, speed_rpm):
        """Gas-load factor at each speed."""
        speed_rpm = np.asarray(speed_rpm, float)
        if self.law == "constant":
            return np.ones_like(speed_rpm)
        return (speed_rpm / self.reference_rpm) ** 2

    @classmethod
    def from_record(cls, record, engine=None):
        """The load a record states in its attrs (``imep`` in Pa, ``load_law``,
        ``load_reference_rpm`` — a channel map's ``[source]`` writes them), or None.

        Examples
        --------
        >>> import xarray as xr
        >>> rec = xr.Dataset(attrs={"imep": 1.3e6, "load_law": "constant"})
        >>> LoadCase.from_record(rec)
        LoadCase(imep=1300000.0, law='constant', reference_rpm=None)
        """
        attrs = getattr(record, "attrs", {}) or {}
        if not any(k in attrs for k in ("imep", "load_law")):
            return None
        try:
            imep = float(attrs["imep"]) if "imep" in attrs else None
            ref = float(attrs["load_reference_rpm"]) if "load_reference_rpm" in attrs else None
        except (TypeError, ValueError):
            raise ConfigError(f"record attrs imep={attrs.get('imep')!r}, load_reference_rpm="
                              f"{attrs.get('load_reference_rpm')!r}: expected numbers (Pa, "
                              "rpm)") from None
        return cls.from_any(dict(imep=imep, law=str(attrs.get("load_law", "constant")),
                                 reference_rpm=ref), engine)

    @classmethod
    def from_any(cls, load, engine=None):
        """From None, a LoadCase, a dict, or an object with imep/law/reference_rpm."""
        if load is None:
            return cls()
        if isinstance(load, cls):
            out = load
        elif isinstance(load, dict):
            out = cls(**load)
        else:
            out = cls(imep=getattr(load, "imep", None), law=getattr(load, "law", "constant"),
                      reference_rpm=getattr(load, "reference_rpm", None))
        if out.law == "propeller" and out.reference_rpm is None:
            ref = getattr(engine, "rated_speed_rpm", None)
            if ref is None:
                raise ConfigError("load law 'propeller' needs reference_rpm (the engine has no "
                                  "rated_speed_rpm)")
            out = cls(imep=out.imep, law=out.law, reference_rpm=float(ref))
        return out


@dataclass(frozen=True)
class PipelineResult:
    """Everything the chain produced for one record (see :func:`analyse`).

    Attributes
    ----------
    source : str
        Record file (or the record's ``source`` attr).
    record_sha256 : str
    model_path : str
    channel, node, quantity, units : str
        Analysed torsional channel, the shaft-line node it measures, its quantity and units.
    speed_channel : str
    speed_range_rpm : tuple
    sweep_rate_rpm_per_s : float
        Median |d(rpm)/dt| over the record from straight-line fits over a tenth of it (0 for a
        steady-speed record: ±1 % of its median).
    track : xarray.Dataset
        Order track of the channel.
    resonances : ResonanceTable
    predicted : pandas.DataFrame
        Critical speeds in range with ``amplitude`` (predicted resonance amplitude at the node,
        channel units, peak), ``speed_rpm``, ``mode``, ``order``, ``frequency_hz``.
    response : xarray.DataArray
        Predicted order amplitude at the node over (``order``, ``rpm``), channel units.
    comparison : CriticalComparison
    limits : tuple of LimitCheck
    system : TorsionalSystem
    record : xarray.Dataset
        The record analysed (for figures; not copied).
    settings : dict
        Every parameter used.
    timings : dict
        Seconds per step.
    steady_orders : pandas.DataFrame or None
        For a steady-speed record: the steady-state order table
        (:func:`analysis.steady.steady_orders`: amplitude and phase per order with their
        uncertainty) shown instead of a sweep rate and resonances.
    balance : tuple
        Kept for compatibility (empty): the vibrograph channels are compared in
        ``vibrograph``.
    vibrograph : VibrographResult or None
        Block/mount vibration per (sensor, order) against the shaft line's engine on its
        mounts (:func:`analysis.vibrograph.compare_vibrograph`), with the residual forces and
        moments when enough sensors; None when the engine has no ``[mounts]`` or the record
        no placeable vibrograph channel.
    pressure : analysis.excitation_compare.ExcitationComparison or None
        With cylinder pressure in the record: the indicator analysis and the response
        predicted from the measured excitation beside the model's.
    """

    source: str
    record_sha256: str
    model_path: str
    channel: str
    node: str
    quantity: str
    units: str
    speed_channel: str
    speed_range_rpm: tuple
    sweep_rate_rpm_per_s: float
    track: object
    resonances: object
    predicted: object
    response: object
    comparison: object
    limits: tuple
    system: object = field(repr=False)
    record: object = field(repr=False)
    settings: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    balance: tuple = ()
    pressure: object = None
    extra_verdicts: tuple = ()
    steady_orders: object = None
    vibrograph: object = None

    @property
    def steady(self) -> bool:
        """The record is a steady-speed run (speed span under 3 % of the mean speed)."""
        lo, hi = self.speed_range_rpm
        return (hi - lo) < 0.03 * max(0.5 * (hi + lo), 1e-9)

    @property
    def verdicts(self) -> tuple:
        """Every check as a :class:`analysis.verdict.Verdict`: the comparison with the model,
        each limit check, the block/mount vibration against the engine on its mounts (one
        combined verdict of :attr:`vibrograph`) and any added by other steps
        (``extra_verdicts``, e.g. a steady-state order comparison)."""
        lo, hi = self.speed_range_rpm
        out = [self.comparison.verdict(
            steady=self.steady,
            basis=f"record {self.source}, channel {self.channel} at {self.node}, "
                  f"{lo:.0f}–{hi:.0f} rpm, {len(self.resonances)} resonance(s) found")]
        out += [c.verdict for c in self.limits]
        if self.vibrograph is not None:
            out.append(self.vibrograph.verdict)
        return tuple(out) + tuple(self.extra_verdicts)

    @property
    def verdict(self):
        """The overall verdict: :func:`analysis.verdict.combine` of :attr:`verdicts`."""
        from .verdict import combine

        return combine(self.verdicts)

    @property
    def passed(self) -> bool:
        """True only when the overall verdict is a pass (inconclusive is not)."""
        return self.verdict.status == "pass"

    def to_frame(self):
        """The summary as a one-row DataFrame."""
        import pandas as pd

        return pd.DataFrame([self.summary()])

    def plot(self, ax=None):
        """Measured against predicted critical speeds (see CriticalComparison.plot)."""
        return self.comparison.plot(ax=ax)

    def summary(self) -> dict:
        """One flat row for batch tables and ``--json``: the overall verdict and its reason,
        the comparison's and the limits' verdicts, counts and worst deviations."""
        from .verdict import combine

        s = self.comparison.summary()
        overall = self.verdict
        limits = combine([c.verdict for c in self.limits], name="limits")
        comp = self.comparison.verdict(steady=self.steady)
        return {"verdict": overall.status, "verdict_reason": overall.reason,
                "comparison_verdict": comp.status, "limits_verdict": limits.status,
                "record": self.source, "sha256": self.record_sha256, "channel": self.channel,
                "node": self.node, "speed_min_rpm": self.speed_range_rpm[0],
                "speed_max_rpm": self.speed_range_rpm[1],
                "sweep_rate_rpm_per_s": self.sweep_rate_rpm_per_s,
                "steady_speed": self.steady_orders is not None,
                "resonances": len(self.resonances), "matched": s["matched"],
                "unmatched_measured": s["unmatched_measured"],
                "unmatched_predicted_significant": s["unmatched_predicted_significant"],
                "max_abs_deviation_pct": s["max_abs_deviation_pct"],
                "model_agrees": s["agrees"],
                "vibration_worst_ratio": self.vibrograph.summary()["vibration_worst_ratio"]
                if self.vibrograph is not None else float("nan"),
                "vibration_verdict": self.vibrograph.verdict.status
                if self.vibrograph is not None else "no vibrograph channel",
                "elapsed_s": float(sum(self.timings.values()))}


def torsional_channel(record, channel=None) -> str:
    """The channel to analyse: ``channel`` if given, else the first angle/angular-velocity one.

    Raises
    ------
    RecordError
        Unknown channel (with a did-you-mean) or no torsional channel in the record.

    Examples
    --------
    >>> import xarray as xr
    >>> rec = xr.Dataset({"acc": ("time", np.zeros(4), {"quantity": "acceleration"}),
    ...                   "tv": ("time", np.zeros(4), {"quantity": "angle"})})
    >>> torsional_channel(rec)
    'tv'
    """
    names = [str(n) for n in record.data_vars]
    if channel is not None:
        if channel not in names:
            raise RecordError(f"record has no channel {channel!r}{suggest(channel, names)}; "
                              f"channels: {', '.join(names)}")
        return channel
    for n in names:
        if record[n].attrs.get("quantity") in _TORSIONAL and record[n].ndim == 1:
            return n
    raise RecordError(f"record has no torsional channel (quantity 'angle' or "
                      f"'angular_velocity'); channels: {', '.join(names)}; give --channel")


def _node_of(record, channel, system):
    attrs = record[channel].attrs
    for key in ("node", "location"):
        value = attrs.get(key)
        if value in system.node_names:
            return value
    log.info("channel %r names no shaft-line node (attrs 'node'/'location'); assuming the "
             "first node %r", channel, system.node_names[0])
    return system.node_names[0]


def _load_record(record, channel_map=None):
    if isinstance(record, (str, Path)):
        from crankbench import measure

        path = Path(record)
        return measure.read(path, map=channel_map), str(path)
    if hasattr(record, "data_vars"):
        return record, str(record.attrs.get("source", "record"))
    raise RecordError(f"record must be a path or an xarray.Dataset Record, got "
                      f"{type(record).__name__}")


def _load_model(model):
    if isinstance(model, (str, Path)):
        from crankbench.predict.torsion import from_toml

        return from_toml(model), str(model)
    if hasattr(model, "critical_speeds"):
        return model, str(getattr(model, "operating", {}).get("source", "model"))
    raise ConfigError(f"model must be a shaft-line TOML path or a TorsionalSystem, got "
                      f"{type(model).__name__}")


#: the steps of :func:`analyse`, in order, as its ``progress`` callback names them
STEPS = ("read", "prediction", "order tracking", "resonances", "comparison",
         "measured excitation", "balance", "limits")


def analyse(record, model, *, channel=None, speed_channel=None, orders=None, max_order=12.0,
            method="vkf", bandwidth_orders=None, revolutions=4, load=None, gate=0.15,
            tolerance=0.03, amplitude_tolerance=0.5, machine_class=None,
            vibration_standard=None, operating_range_rpm=None, base_points=1500,
            order_fraction=0.05, max_tracked=8, resonance_options=None,
            vibration_tolerance=0.5, progress=None, channel_map=None) -> PipelineResult:
    """Run the chain on one record against one shaft-line model.

    Parameters
    ----------
    record : path-like or xarray.Dataset
        Record file (any supported format) or Record.
    model : path-like or TorsionalSystem
        Shaft-line TOML (``[shaftline]`` naming its engine) or a built system.
    channel : str, optional
        Torsional channel (default: the first with quantity 'angle' or 'angular_velocity').
    speed_channel : str, optional
        Speed source (default: found in the record).
    orders : sequence of float, optional
        Orders to track (default: those of the engine's orders up to ``max_order`` whose
        predicted resonance amplitude in the range is at least ``order_fraction`` of the
        largest, at most ``max_tracked`` of them).
    max_order : float
    method : {'vkf', 'auto', 'cot'}
        Order tracker: Vold–Kalman with ``bandwidth_orders`` chosen from the sweep rate (default:
        the resonance identification and the comparison are calibrated on it), the adaptive
        settings of :mod:`analysis.autotrack` (never narrower than ``bandwidth_orders``), or
        computed order tracking.
    bandwidth_orders : float, optional
        VKF −3 dB bandwidth in orders ('vkf'; with 'auto' the floor under the chosen
        bandwidth, which the resonance identification needs). Default from the sweep rate R
        (rpm/s): 0.25 up to
        25 rpm/s, then 0.25·√(R/25) up to 0.5 — a resonance crossed quickly has a wider
        envelope spectrum, and a narrow filter would flatten its peak (measured on the 6L32
        scene at 100 rpm/s: amplitude −17 % at 0.25 orders, −4 % at 0.5).
    revolutions : int
        COT block length, revolutions.
    load : LoadCase or dict, optional
        Load law of the predicted excitation (default: the model's imep, constant).
    gate, tolerance, amplitude_tolerance : float
        Matching settings (:func:`analysis.match_criticals`).
    machine_class : str or int, optional
        Vibration-severity class of ``vibration_standard`` (default: the model's
        ``[limits.vibration] machine_class``, else for ISO 10816-6 chosen from the rated
        power (``[limits.vibration] rated_power_kw``, else the indicated power, said so) and
        mounting (``[limits.vibration] mounting``, else resilient when the engine model has
        ``[mounts]``), see :func:`analysis.limits.reciprocating_class`).
    vibration_standard : {'ISO 10816-6', 'ISO 10816-1'}, optional
        Default: the model's ``[limits.vibration] standard``, else ISO 10816-6 (reciprocating
        machines).
    operating_range_rpm : (float, float), optional
        Continuous-operation range for the stress check (default: the model's
        ``[limits] operating_range_rpm``).
    base_points : int
        Fidelity of the predicted resonance curves: speeds over the range (uniform).
    order_fraction : float
        See ``orders``.
    max_tracked : int
        At most this many orders are tracked (the strongest predicted); the joint VKF costs
        O(N K²) in the number of orders K.
    resonance_options : dict, optional
        Passed to :func:`analysis.find_resonances`.
    vibration_tolerance : float
        Ratio band of the vibrograph comparison (:func:`analysis.vibrograph.compare_vibrograph`)
        of any block/mount channel when the engine has ``[mounts]``.
    progress : callable, optional
        ``progress(step_name)`` called before each step (CLI progress bars).
    channel_map : path-like, dict or ChannelMap, optional
        Channel map for a record file (:mod:`measure.channelmap`).

    Returns
    -------
    PipelineResult

    Raises
    ------
    RecordError, ConfigError, ModelError, AnalysisError
        Naming the file, channel or key at fault.

    Examples
    --------
    The demo's chain (a few seconds; ``crankbench demo`` runs it from the command line):

    >>> from crankbench.measure.synth import Scene, synthesize             # doctest: +SKIP
    >>> scene = Scene.from_toml("sample_data/scenes/marine_6l_runup.toml")  # doctest: +SKIP
    >>> res = analyse(synthesize(scene).record, "sample_data/shaftlines/marine_6l.toml",
    ...               load=LoadCase.from_any(scene.load, scene.engine))  # doctest: +SKIP
    >>> res.comparison.agrees, len(res.comparison.matched)       # doctest: +SKIP
    (True, 10)
    """
    from .compare import match_criticals
    from .resonance import find_resonances
    from .speedref import find_speed_channel, speed_reference

    check_option(method, "method", ("auto", "vkf", "cot"), error=ConfigError)
    timings = {}

    def step(name):
        if progress is not None:
            progress(name)
        timings[name] = time.perf_counter()

    def done(name):
        timings[name] = time.perf_counter() - timings[name]
        log.debug("step %-15s %.2f s", name, timings[name])

    step("read")
    rec, source = _load_record(record, channel_map)
    system, model_path = _load_model(model)
    load, unstated = _load_basis(load, system, rec)
    channel = torsional_channel(rec, channel)
    var = rec[channel]
    quantity = var.attrs.get("quantity", "angle")
    if quantity not in _TORSIONAL:
        raise RecordError(f"channel {channel!r} has quantity {quantity!r}; expected 'angle' or "
                          "'angular_velocity' for the torsional comparison")
    units = str(var.attrs.get("units", "rad"))
    node = _node_of(rec, channel, system)
    speed_channel = speed_channel or find_speed_channel(rec, channel)
    rpm = speed_reference(rec, channel, speed_channel=speed_channel)
    fs = float(var.attrs.get("sample_rate") or 1.0 / np.median(np.diff(rec[var.dims[0]].values)))
    x = np.asarray(var.values, float)
    ok = np.isfinite(x) & np.isfinite(rpm)
    if ok.sum() < 0.9 * x.size:
        raise RecordError(f"channel {channel!r}: {x.size - ok.sum()} of {x.size} samples are "
                          "not finite (or outside the speed reference)")
    x, rpm_ok = np.where(ok, x, 0.0), np.where(ok, rpm, np.nanmedian(rpm))
    lo, hi = float(np.nanmin(rpm)), float(np.nanmax(rpm))
    if hi - lo < 0.005 * max(hi, 1.0):
        # a steady run: predict over ±0.5 % so the model's curves exist; no critical is crossed
        # and the comparison says so (inconclusive)
        mid = 0.5 * (lo + hi)
        lo, hi = mid * 0.995, mid * 1.005
    from .autotrack import steady_speed, sweep_rate as _sweep_rate

    # robust to speed noise: a constant-speed record has no sweep (0), not its noise's slope
    steady_run = steady_speed(rpm_ok, fs)
    sweep_rate = 0.0 if steady_run else _sweep_rate(rpm_ok, fs)
    speed_arg = rpm if bool(np.all(ok)) else rpm_ok   # keeps the encoder angle when present
    from .given_excitation import default_orders, given_excitation

    def trackable(qs):
        return [float(o) for o in qs if o <= max_order + 1e-9 and o * hi / 60.0 < 0.4 * fs]

    all_orders = trackable(default_orders(system, max_order))
    requested = None
    if orders is not None:
        requested = trackable(orders)
        # the predicted stress and the limit checks superpose every order of the engine,
        # not only the requested ones (those are tracked; the others are taken as predicted
        # and the checks' basis says so): --orders 4.5 alone had turned a FAIL into a PASS
        all_orders = sorted(set(all_orders) | set(requested))
    if orders is not None and len(requested) < len(orders):  # never drop a requested order
        lost = [float(o) for o in orders if float(o) not in requested]
        raise AnalysisError(f"orders {', '.join(f'{o:g}' for o in lost)} cannot be tracked: "
                            f"above max_order {max_order:g} or above 0.4 × the sample rate "
                            f"({fs:g} Hz) at {hi:.0f} rpm")
    if not all_orders:
        raise AnalysisError(f"no order up to {max_order:g} lies below 0.4 × the sample rate "
                            f"({fs:g} Hz) at {hi:.0f} rpm")
    done("read")

    step("prediction")
    predicted, response_da, grid, pred_stress = _prediction(
        system, all_orders, node, quantity, units, load, lo, hi, base_points,
        fraction=order_fraction, max_fit=max_tracked if orders is None else len(all_orders),
        min_prominence=float((resonance_options or {}).get("min_prominence", 0.05)))
    if orders is None:
        # track the orders whose predicted resonances matter, largest first
        big = predicted["amplitude"].max() if len(predicted) else 0.0
        strong = predicted[predicted["amplitude"] >= order_fraction * big]
        ranked = strong.groupby("order")["amplitude"].max().sort_values(ascending=False)
        orders = sorted(float(o) for o in ranked.index[:max_tracked]) or all_orders
        dropped = [float(o) for o in ranked.index[max_tracked:]]
        if dropped:
            log.debug("tracking the %d strongest orders; not tracked: %s", max_tracked,
                     ", ".join(f"{o:g}" for o in sorted(dropped)))
        # criticals of orders not tracked cannot be found: not expected
        predicted.loc[~predicted["order"].isin(orders), "significant"] = False
    else:
        orders = requested
        predicted.loc[~predicted["order"].isin(orders), "significant"] = False
    given = given_excitation(system)
    if given is not None and given.get("torque") is None:
        # torques not given: criticals are compared by speed only; which are expected in the
        # measurement was judged on the response to 1 N·m per order
        predicted["amplitude"] = np.nan
        response_da.attrs["note"] = ("response to 1 N·m per order: exciting torques not given "
                                     "(criticals expected where that response is >= 5 % of "
                                     "its largest)")
    done("prediction")

    if bandwidth_orders is None:
        bandwidth_orders = float(np.clip(0.25 * np.sqrt(max(sweep_rate, 1e-9) / 25.0),
                                         0.25, 0.5))
    step("order tracking")
    track = _track(x, fs, speed_arg, orders, method=method, bandwidth_orders=bandwidth_orders,
                   revolutions=revolutions)
    if method == "vkf" and track.sizes.get("time", 0) > 100:
        # the filter's ends are not settled: drop one time constant 1/B at each end
        edge = 1.0 / (bandwidth_orders * max(lo, 1.0) / 60.0)
        tt = track["time"].values
        keep = (tt >= tt[0] + edge) & (tt <= tt[-1] - edge)
        if keep.sum() > 0.5 * tt.size:
            track = track.isel(time=keep)
    steady_table = None
    if steady_run:
        from .steady import steady_orders

        try:
            steady_table = steady_orders(x, fs=fs, speed_rpm=speed_arg, orders=orders,
                                         amplitude=track.attrs.get("amplitude_convention",
                                                                   "peak"))
        except AnalysisError as exc:
            log.info("no steady-state order table: %s", exc)
    done("order tracking")

    step("resonances")
    resonances = find_resonances(track, **(resonance_options or {}))
    done("resonances")

    step("comparison")
    predicted, measured = _swept_like_with_like(predicted, resonances, track, quantity, gate)
    from .resonance.detect import detection_limits

    fs_set = resonances.settings
    predicted["detection_limit"], predicted["measured_level"] = detection_limits(
        track, predicted["order"], predicted["speed_rpm"], min_snr=fs_set["min_snr"],
        min_prominence=fs_set["min_prominence"], min_confidence=fs_set["min_confidence"],
        min_amplitude_fraction=fs_set["min_amplitude_fraction"])
    comparison = match_criticals(measured, predicted, gate=gate, tolerance=tolerance,
                                 amplitude_tolerance=amplitude_tolerance,
                                 speed_range_rpm=(lo, hi), amplitudes_not_judged=unstated)
    done("comparison")

    step("measured excitation")                # cylinder pressure, if the record has it
    from .excitation_compare import measured_excitation_prediction

    pressure = measured_excitation_prediction(rec, system, grid, all_orders, node, quantity,
                                              units, load, track, response_da)
    done("measured excitation")

    step("balance")
    vibrograph = _vibrograph(rec, system, None if unstated else load, speed_channel,
                             vibration_tolerance,
                             indicator=None if pressure is None else pressure.indicator)
    done("balance")

    step("limits")
    limits = _limit_checks(rec, system, track, grid, pred_stress, response_da, all_orders,
                           channel, machine_class, operating_range_rpm, load=load,
                           standard=vibration_standard, speed_range=(lo, hi))
    done("limits")

    ppr = next((int(rec[n].attrs["pulses_per_rev"]) for n in rec.data_vars
                if "pulses_per_rev" in rec[n].attrs), None)
    settings = {
        "channel": channel, "node": node, "quantity": quantity, "units": units,
        "speed channel": speed_channel, "tacho pulses per rev": ppr,
        "sample rate (Hz)": fs, "orders predicted": ", ".join(f"{o:g}" for o in all_orders),
        "order tracking": track.attrs.get("method", method),
        "amplitude convention": track.attrs.get("amplitude_convention", "peak"),
        **_tracking_settings(track, method, bandwidth_orders, revolutions),
        "phase reference": track.attrs.get("phase_reference", ""),
        "channel trend": track.attrs.get("trend", ""),
        "speed range (rpm)": f"{lo:.1f} – {hi:.1f}",
        "sweep rate (rpm/s, median)": "steady (no sweep)" if steady_run else sweep_rate,
        "estimated sweep peak loss (max over resonances)": max(
            (r.sweep_peak_loss for r in resonances if np.isfinite(r.sweep_peak_loss)),
            default=0.0),
        "load": f"{load.law}" + (f", imep {load.imep / 1e5:.4g} bar" if load.imep else
                                 ", model imep") +
                (f" at {load.reference_rpm:g} rpm" if load.law == "propeller" else ""),
        "matching gate": gate, "speed tolerance": tolerance,
        "amplitude tolerance": amplitude_tolerance,
        "predicted curves": f"{grid.size} speeds, steady-state harmonic solve at {node}",
        "orders tracked": ", ".join(f"{o:g}" for o in orders),
        "resonance finder": resonances.settings,
    }
    return PipelineResult(
        source=source, record_sha256=source_sha256(rec, missing=""), model_path=model_path,
        channel=channel, node=node, quantity=quantity, units=units, speed_channel=speed_channel,
        speed_range_rpm=(lo, hi), sweep_rate_rpm_per_s=sweep_rate, track=track,
        resonances=resonances, predicted=predicted, response=response_da,
        comparison=comparison, limits=tuple(limits), system=system, record=rec,
        settings=settings, timings=timings, vibrograph=vibrograph,
        pressure=pressure, steady_orders=steady_table)


def _swept_like_with_like(predicted, resonances, track, quantity, gate):
    """Sweep effects before matching (:mod:`analysis.resonance.sweep`): predicted criticals the
    run does not cover with both flanks (and the sweep delay) are not expected; measured
    resonances the finder could not correct for the sweep lose the delay the model predicts
    at the measured rate."""
    from .resonance import correct_sweep_delay, sweep_expectation

    if "time" not in track.coords or track.sizes.get("time", 0) < 4 or not len(predicted):
        return predicted, resonances
    expected = sweep_expectation(
        predicted, time=track["time"].values, speed_rpm=track["rpm"].values,
        response="velocity" if quantity == "angular_velocity" else "displacement")
    edge = expected["significant"] & ~expected["covered"]
    for _, r in expected[edge].iterrows():
        log.info("mode %d order %g: critical at %.0f rpm is not covered by the run with both "
                 "flanks (and the sweep delay); listed, not judged", r["mode"], r["order"],
                 r["speed_rpm"])
    expected.loc[edge, "significant"] = False
    expected["not_judged"] = ""          # why a critical in range is listed but not judged
    expected.loc[edge, "not_judged"] = ("not covered by the run with both flanks (and the "
                                        "sweep delay)")
    measured = correct_sweep_delay(resonances.to_frame(), expected, gate=gate)
    return expected, measured


def _vibrograph(rec, system, load, speed_channel, tolerance, *, indicator=None):
    """The vibrograph comparison of the record's block/mount channels against the shaft line's
    engine on its mounts, with the prediction from the measured excitation beside it when
    ``indicator`` (the indicator results of the record's pressure) is given; None without
    ``[mounts]`` or placeable channels."""
    from .vibrograph import compare_vibrograph

    engine = getattr(system, "engine", None)
    source = getattr(engine, "source", None)
    if engine is None or not source:
        return None
    try:
        return compare_vibrograph(rec, source, load=load, speed_channel=speed_channel,
                                  tolerance=tolerance, indicator=indicator)
    except ConfigError as exc:        # no [mounts] in the engine model
        log.info("no vibrograph comparison: %s", exc)
    except (RecordError, AnalysisError) as exc:   # no channel to place, nothing to compare
        log.info("no vibrograph comparison: %s", exc)
    return None


def _load_basis(load, system, record=None):
    """The load case of the prediction and, when nobody stated it, why amplitudes cannot be
    judged against it.

    Stated: a ``load`` given (the CLI's ``--imep``/``--load-law``, a synthetic record's own
    scene, the API), the record's own attrs (:meth:`LoadCase.from_record`: a channel map's
    ``[source] imep/load_law``), or the model's ``[shaftline] load_law``. Otherwise the prediction runs at
    the model's imep at every speed — an assumption: a run on a propeller curve excites the
    low speeds with a fraction of it, so measured/predicted amplitude ratios say nothing
    about the model there (0.13-0.58 on the 6L32 run-up exported as text).
    """
    engine = getattr(system, "engine", None)
    if load is not None:
        return LoadCase.from_any(load, engine), None
    stated = LoadCase.from_record(record, engine)
    if stated is not None:
        return stated, None
    law = system.operating.get("load_law")
    if law:
        return LoadCase.from_any(dict(law=law, reference_rpm=system.operating.get(
            "load_reference_rpm")), engine), None
    imep = system.operating.get("imep")
    at = f"the model's imep {imep / 1e5:.4g} bar" if imep else "the engine's own load"
    return LoadCase(), (f"the run's load is not stated: the prediction assumes {at} at every "
                        "speed; give --imep and --load-law (or imep/load_law in the channel "
                        "map's [source]), or load_law in the model's [shaftline]")


def load_from_record_file(path):
    """The load case recorded with a synthetic record (its truth's scene ``[load]``), or None.

    Records written by ``crankbench synth`` keep the scene in the truth group; the prediction
    then uses the same load law as the run. Other records return None (the model's imep).
    """
    import json

    from crankbench.measure.io import read_truth

    try:
        truth = read_truth(path)
        scene = json.loads(truth.attrs.get("scene_toml", "{}"))
    except (RecordError, ValueError, OSError, KeyError):
        return None
    load = scene.get("load")
    if not isinstance(load, dict) or not load:
        return None
    from crankbench.predict._toml import Table

    # the scene as written: values may carry units ("22 bar"), read them like the scene did
    t = Table(load, source=str(path), prefix="truth.scene.load", error=ConfigError)
    return LoadCase(imep=t.positive("imep", None, unit="Pa"),
                    law=t.string("law", "constant", options=("constant", "propeller")),
                    reference_rpm=t.positive("reference_rpm", None, unit="rpm"))
