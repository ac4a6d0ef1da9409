"""Limit checks of the end-to-end chain (:func:`analysis.pipeline.analyse`, step 6).

Measured torsional stress (measured order amplitude × the model's stress per unit node
amplitude of that order, superposed over one engine cycle with the model's phases) and the
predicted one-cylinder-misfire stress against the rule limits
(:func:`analysis.torsional_limits.check_torsional_stress`, IACS UR M68), and the vibration
severity of vibrograph channels (:func:`analysis.limits.check_vibration_severity`).
"""

from __future__ import annotations

import logging

import numpy as np

from crankbench.predict.errors import AnalysisError, ModelError, RecordError

__all__: list[str] = []     # helpers of analysis.pipeline

log = logging.getLogger("crankbench")


def _superpose(stress, orders):
    """Peak superposed stress over one engine cycle, (n_s, n_o, n_sec) complex → (n_s, n_sec).

    32 samples per period of the highest order: the peak is under-estimated by at most
    1 − cos(π/32) = 0.5 %.
    """
    q = np.asarray(orders, float)
    cycle = 4.0 * np.pi if np.any(np.abs(q - np.round(q)) > 1e-9) else 2.0 * np.pi
    theta = np.linspace(0.0, cycle, int(32 * q.max() * cycle / (2 * np.pi)), endpoint=False)
    basis = np.exp(1j * np.outer(q, theta))  # (n_o, n_theta)
    out = np.empty((stress.shape[0], stress.shape[2]))
    for c in range(stress.shape[2]):
        out[:, c] = np.max(np.abs(np.real(stress[:, :, c] @ basis)), axis=1)
    return out


def _predicted_share(ratio, measured, at, total, orders) -> str:
    """What of the "measured" stress is the prediction: the orders taken as predicted
    (ratio 1: not tracked, or tracked only where the prediction is below 5 % of its
    maximum) and their share of the stress at its worst speed and section, as basis text
    (empty when every order's ratio is measured wherever it matters)."""
    taken = [q for j, q in enumerate(orders) if not measured[:, j].any()]
    if not taken:
        return ""
    i, c = np.unravel_index(int(np.argmax(total)), total.shape)
    only = np.where(measured, ratio, 0.0)[i:i + 1, :, None] * at[i:i + 1, :, c:c + 1]
    share = 1.0 - float(_superpose(only, orders)[0, 0]) / float(total[i, c]) \
        if total[i, c] > 0 else 0.0
    listed = ", ".join(f"{q:g}" for q in taken) if len(taken) <= 8 else \
        f"{len(taken)} orders ({taken[0]:g}–{taken[-1]:g}) of"
    return (f"; {'' if len(taken) > 8 else 'orders '}{listed} not measured, taken as predicted: "
            f"{100.0 * max(share, 0.0):.0f} % of the worst stress")


def _misfire_stress(system, speed_rpm, orders, load, sections):
    """Predicted superposed stress with one cylinder misfiring: the worst over the cylinders.

    The misfiring cylinder keeps its inertia torque and loses its gas torque (motored
    pressure neglected: a slight over-estimate of the unbalance between cylinders).
    Returns (n_s, n_sections) Pa and the worst cylinder per speed.
    """
    from crankbench.predict.torsion.excitation import engine_excitation
    from crankbench.predict.torsion.forced import stress_factor

    imep = load.imep if load.imep is not None else system.operating.get("imep")
    exc = engine_excitation(system, imep=imep, orders=orders)
    omega = np.asarray(speed_rpm, float) * np.pi / 30.0
    scale = load.scale(speed_rpm)
    names = list(system.edge_names)
    cols = [names.index(n) for n in sections]
    factor = stress_factor(system)[cols]
    worst = np.zeros((omega.size, len(cols)))
    which = np.zeros(omega.size, int)
    for cyl in range(1, exc.n_cylinders + 1):
        gas = np.repeat(exc.gas[None, :, None] * scale[:, None, None], exc.n_cylinders, axis=2)
        gas[:, :, cyl - 1] = 0.0
        torque = gas + (omega**2)[:, None, None] * exc.inertia[None, :, None]
        res = system.forced_response(speed_rpm, torque=torque, orders=orders, superpose=False)
        tau = _superpose(res.torque[:, :, cols] * factor[None, None, :], orders)
        better = tau.max(axis=1) > worst.max(axis=1)
        which[better] = cyl
        worst = np.maximum(worst, tau)
    return worst, which


def _limit_checks(rec, system, track, grid, pred_stress, response, orders, channel, machine_class,
                  operating_range_rpm, *, load=None, standard=None, speed_range=None):
    """Torsional stress against the rule limits (measured; predicted with a cylinder
    misfiring); vibration severity of vibrograph channels.

    Measured stress: the predicted complex stress of each order in each section, scaled by the
    ratio of measured to predicted amplitude of that order at the measured node (ratio 1 for
    orders not tracked, or where the prediction is below 5 % of its maximum over speed;
    clipped to [0, 10]), superposed over one engine cycle with the model's phases
    (:func:`_superpose`). The basis names the orders taken as predicted and their share of
    the worst stress (:func:`_predicted_share`).
    """
    from .torsional_limits import check_torsional_stress, not_assessed

    checks = []
    limits = getattr(system, "limits", None)
    rpm = np.asarray(track["rpm"].values, float)
    lo, hi = (float(rpm.min()), float(rpm.max())) if speed_range is None else speed_range
    if limits is None or not getattr(limits, "has_rule_data", True):
        checks.append(not_assessed(
            f"measured torsional stress ({channel})",
            "the model has no stress limit data ([limits] with IACS UR M68 shafting data "
            "[[limits.shafting]] or the engine maker's crankshaft figure [limits.crankshaft])",
            basis=f"model {system.operating.get('source', '')}"))
    else:
        names = list(system.edge_names)
        lim_secs = list(limits.sections)
        cols = [names.index(s) for s in lim_secs] if lim_secs else \
            [i for i in range(len(names)) if np.isfinite(pred_stress[:, :, i]).all()]
        pred_amp = np.asarray(response.values, float).T  # (n_s, n_o)
        edges = np.linspace(lo, hi, 301)
        centre = 0.5 * (edges[1:] + edges[:-1])
        idx = np.clip(np.searchsorted(edges, rpm) - 1, 0, 299)
        ratio = np.ones((centre.size, len(orders)))
        measured = np.zeros((centre.size, len(orders)), bool)   # ratio from the record
        tracked = np.asarray(track["amplitude"].values, float)  # (order, time)
        for jt, q in enumerate(np.asarray(track["order"].values, float)):
            j = int(np.argmin(np.abs(np.asarray(orders) - q)))
            meas = np.full(centre.size, -np.inf)
            fin = np.isfinite(tracked[jt])          # unsettled filter ends are NaN
            np.maximum.at(meas, idx[fin], tracked[jt][fin])
            meas[~np.isfinite(meas)] = np.nan
            pred = np.interp(centre, grid, pred_amp[:, j])
            ok = np.isfinite(meas) & (pred >= 0.05 * pred_amp[:, j].max()) & (pred > 0)
            ratio[ok, j] = np.clip(meas[ok] / pred[ok], 0.0, 10.0)
            measured[ok, j] = True
        at = np.empty((centre.size, len(orders), len(cols)), complex)
        for k, c in enumerate(cols):
            for j in range(len(orders)):
                sc = pred_stress[:, j, c]
                at[:, j, k] = np.interp(centre, grid, sc.real) + 1j * np.interp(centre, grid,
                                                                                 sc.imag)
        total = _superpose(ratio[:, :, None] * at, orders)
        basis = (f"record channel {channel} at {response.attrs.get('node', '')}, "
                 f"{lo:.0f}–{hi:.0f} rpm: measured/predicted order amplitude × model stress "
                 "per section, superposed over the cycle"
                 + _predicted_share(ratio, measured, at, total, orders))
        checks.extend(check_torsional_stress(
            centre, total, limits, sections=[names[c] for c in cols],
            operating_range_rpm=operating_range_rpm, name="measured torsional stress",
            basis=basis, covered_rpm=(lo, hi)))
        if getattr(system, "engine", None) is not None and load is not None and \
                hasattr(limits, "misfire_operation"):
            try:
                sgrid = np.linspace(lo, hi, 240)
                mis, _ = _misfire_stress(system, sgrid, orders, load, [names[c] for c in cols])
                checks.extend(check_torsional_stress(
                    sgrid, mis, limits, sections=[names[c] for c in cols], misfire=True,
                    operating_range_rpm=operating_range_rpm,
                    name="predicted torsional stress, one cylinder misfiring",
                    basis=(f"model, worst single misfiring cylinder (gas torque removed), "
                           f"{lo:.0f}–{hi:.0f} rpm, run's load law"),
                    required=bool(limits.misfire_operation), covered_rpm=(lo, hi),
                    predicted=True))
            except (ModelError, AnalysisError) as exc:
                # never dropped silently: a stated case that could not be computed is listed
                # as not assessed (inconclusive; counts only when the model requires it)
                log.warning("misfire case not computed: %s", exc)
                checks.append(not_assessed(
                    "predicted torsional stress, one cylinder misfiring",
                    f"the misfire case could not be computed ({exc})",
                    basis=f"model, {lo:.0f}–{hi:.0f} rpm",
                    required=bool(limits.misfire_operation)))
    checks.extend(_severity_checks(rec, system, machine_class, standard))
    return checks


def _engine_power_and_mounting(system, vib=None):
    """What the ISO 10816-6 class is chosen by, each with where it came from.

    Returns a dict: ``power_w`` (W or None) and ``power_note``; ``resilient`` (bool or None)
    and ``mounting_note``; ``rated_speed_rpm``. Power: the rated power of ``[limits.vibration]
    rated_power_kw`` (the standard classes machines by rated power), else the indicated power at
    rated speed from the model's imep (an over-estimate of the rated brake power by the
    mechanical losses, stated as such). Mounting: ``[limits.vibration] mounting``, else
    resilient when the engine model has a ``[mounts]`` table, else unknown (no class chosen).
    """
    vib = vib or {}
    engine = getattr(system, "engine", None)
    rated = getattr(engine, "rated_speed_rpm", None) if engine is not None else None
    power, power_note = None, "no rated power in the model ([limits.vibration] rated_power_kw)"
    if vib.get("rated_power_kw") is not None:
        power = float(vib["rated_power_kw"]) * 1e3
        power_note = (f"rated power {power / 1e3:.0f} kW from [limits.vibration] rated_power_kw "
                      "(ISO 10816-6 classes by rated power)")
    elif engine is not None:
        comb = getattr(engine, "combustion", None) or {}
        imep = comb.get("imep") if isinstance(comb, dict) else getattr(comb, "imep", None)
        bore, stroke = getattr(engine, "bore", None), getattr(engine, "stroke", None)
        if stroke is None and getattr(engine, "crank_radius", None) is not None:
            stroke = 2.0 * engine.crank_radius
        if None not in (imep, bore, stroke, rated):
            # P_i = p_mi V_d n / (60 i), i = 2 revolutions per cycle for a 4-stroke
            swept = np.pi / 4.0 * bore**2 * stroke * engine.n_cylinders
            power = imep * swept * rated / 60.0 / (getattr(engine, "cycle", 4) / 2.0)
            power_note = (f"indicated power {power / 1e3:.0f} kW at the rated {rated:.0f} rpm "
                          "from the engine's imep (no rated power in the model: give "
                          "[limits.vibration] rated_power_kw; indicated exceeds brake power by "
                          "the mechanical losses)")
    resilient, mounting_note = None, ("mounting unknown: give [limits.vibration] mounting = "
                                      "\"rigid\" or \"resilient\"")
    if vib.get("mounting") is not None:
        resilient = vib["mounting"] == "resilient"
        mounting_note = f"{vib['mounting']} mounting from [limits.vibration] mounting"
    elif engine is not None and getattr(engine, "source", None):
        try:
            import tomllib

            with open(engine.source, "rb") as fh:
                has_mounts = "mounts" in tomllib.load(fh)
        except (OSError, ValueError):
            has_mounts = False
        if has_mounts:
            resilient = True
            mounting_note = "resilient mounting: the engine model has [mounts]"
    return {"power_w": power, "power_note": power_note, "resilient": resilient,
            "mounting_note": mounting_note, "rated_speed_rpm": rated}


def _severity_checks(rec, system, machine_class, standard):
    """Vibration severity of each vibrograph channel: ISO 10816-6 (class from the model's
    power and mounting) by default for engines, ISO 10816-1 on request."""
    from .limits import check_vibration_severity, reciprocating_class, vibration_severity

    out = []
    reason = ""
    std = standard
    vib = getattr(getattr(system, "limits", None), "vibration", None) or {}
    cls = machine_class
    if std is None:
        std = vib.get("standard", "ISO 10816-6")
    if cls is None:
        cls = vib.get("machine_class")
    chosen_by = ""
    if std == "ISO 10816-6" and cls is None:
        why = _engine_power_and_mounting(system, vib)
        cls, reason = reciprocating_class(power_w=why["power_w"],
                                          rated_speed_rpm=why["rated_speed_rpm"],
                                          resilient=why["resilient"])
        chosen_by = f"; class chosen by {why['power_note']}; {why['mounting_note']}"
        reason = f"{reason}{chosen_by}"
    elif std == "ISO 10816-1" and cls is None:
        cls, reason = "III", "class III (default)"
    for name in rec.data_vars:
        v = rec[name]
        q = v.attrs.get("quantity")
        if q in ("velocity", "acceleration") and v.ndim == 1 and "sample_rate" in v.attrs:
            from .speedref import speed_reference

            try:
                rpm = speed_reference(rec, str(name))
            except (AnalysisError, RecordError):
                rpm = None
            fs = float(v.attrs["sample_rate"])
            # ISO 10816-6: 2–1000 Hz; ISO 10816-1: 10–1000 Hz (2 Hz at 600 rpm or below)
            low = 2.0 if std == "ISO 10816-6" or (rpm is not None and np.nanmax(rpm) <= 600) \
                else 10.0
            band = (low, min(1000.0, 0.45 * fs))
            window = min(1.0, v.size / fs)
            sev = vibration_severity(np.asarray(v.values, float), fs=fs, speed_rpm=rpm, quantity=q,
                                     band_hz=band, window_s=window)
            loc = f" ({v.attrs['location']})" if v.attrs.get("location") else ""
            basis = (f"channel {name}{loc}, {q}, velocity rms {band[0]:g}–{band[1]:g} Hz in "
                     f"{window:g} s windows{chosen_by}")
            bounds = None
            if vib.get("boundaries_mm_s") is not None:
                from .limits import ZoneBoundaries

                b = [float(x) * 1e-3 for x in vib["boundaries_mm_s"]]
                bounds = ZoneBoundaries(*b, machine_class=str(cls or ""),
                                        source=vib.get("source", "model [limits.vibration]"))
            out.append(check_vibration_severity(
                sev, machine_class=cls, boundaries=bounds, standard=std,
                name=f"vibration severity {name}{loc}", basis=basis, class_reason=reason))
    return out
