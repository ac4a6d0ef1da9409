"""Prediction inside the end-to-end chain (:func:`analysis.pipeline.analyse`, step 4): the
model's steady-state order response at the measured node (and the stress of each section), and
its critical speeds identified on that response as the measurement is.
"""

from __future__ import annotations

import logging

import numpy as np

__all__ = ["predicted_response"]

log = logging.getLogger("crankbench")


def predicted_response(system, speed_rpm, orders, node, *, load, quantity="angle",
                       excitation=None):
    """Steady-state order amplitudes at ``node`` and the complex stress of each section.

    ``excitation`` (an :class:`predict.torsion.excitation.Excitation`, e.g. from measured
    pressure) replaces the model's parametric one; its gas part is scaled by the load law —
    except for a :class:`predict.gas_torque.SpeedExcitation`, measured at each speed.
    Returns (amplitude (n_s, n_o), stress (n_s, n_o, n_edges) complex Pa — NaN where a
    section has no diameter —, the ForcedResponse).
    """
    from crankbench.predict.torsion.forced import stress_factor

    from crankbench.predict.torsion.excitation import engine_excitation

    from .given_excitation import given_excitation, given_forcing

    omega = np.asarray(speed_rpm, float) * np.pi / 30.0
    if excitation is None and given_excitation(system) is not None:  # a bench without an engine
        forced, torque = given_forcing(system, speed_rpm, orders)
        res = forced.forced_response(speed_rpm, torque=torque, orders=orders, superpose=False)
    else:
        if excitation is None:
            imep = load.imep if load.imep is not None else system.operating.get("imep")
            excitation = engine_excitation(system, imep=imep, orders=orders)
        if getattr(excitation, "speed_dependent", False):   # measured per speed: no load law
            torque = excitation.harmonics(omega, orders)
        else:
            scale = load.scale(speed_rpm)
            gas = excitation.harmonics(np.zeros(1), orders)[0]                 # (n_o, z)
            inertia = excitation.harmonics(np.ones(1), orders)[0] - gas
            torque = gas[None] * scale[:, None, None] \
                + (omega**2)[:, None, None] * inertia[None]
        res = system.forced_response(speed_rpm, torque=torque, orders=orders, superpose=False)
    i = system.node_names.index(node)
    amp = np.abs(res.angle[:, :, i])
    if quantity == "angular_velocity":
        amp = amp * omega[:, None] * np.asarray(orders)[None, :]
    stress = res.torque * stress_factor(system)[None, None, :]
    return amp, stress, res


def _prediction(system, orders, node, quantity, units, load, lo, hi, base_points, *,
                fraction=0.05, max_fit=8, min_prominence=0.05):
    """Critical speeds in range, identified on the predicted response like the measurement.

    The predicted steady-state order response at ``node`` is passed through the same
    resonance finder as the measured track (SDOF modal fit), so measured and predicted
    critical speeds, damping and amplitudes are estimated the same way; each predicted
    resonance is assigned the mode of the nearest undamped critical of its order. A critical
    is *significant* (expected in the measurement) when the finder identifies it on the
    predicted curve with the prominence the measured finder demands (``min_prominence``) and
    its amplitude is at least 5 % of the largest: a bump of a few per cent on a large
    background cannot be identified in a measured track either.
    """
    import xarray as xr

    from .resonance import find_resonances

    crit = system.critical_speeds(orders, (lo, hi))
    grid = np.linspace(lo, hi, int(base_points))
    amp, pred_stress, res = predicted_response(system, grid, orders, node, load=load,
                                           quantity=quantity)
    i = system.node_names.index(node)
    comp = res.angle[:, :, i].T  # (order, rpm)
    if quantity == "angular_velocity":
        comp = comp * 1j * (grid * np.pi / 30.0)[None, :] * np.asarray(orders)[:, None]
    track = xr.Dataset({"amplitude": (("order", "rpm"), np.abs(comp), {"units": units}),
                        "phase": (("order", "rpm"), np.angle(comp), {"units": "rad"})},
                       coords={"order": orders, "rpm": grid})
    # identify (fit) only the strongest orders: those whose raw peak near a critical is at
    # least ``fraction`` of the largest, at most ``max_fit`` orders
    raw = []
    for _, c in crit.iterrows():
        near = np.abs(grid - c.speed_rpm) <= 0.06 * c.speed_rpm
        raw.append(float(amp[near, orders.index(float(c.order))].max()) if near.any() else 0.0)
    raw = np.asarray(raw)
    fit_orders = []
    if raw.size:
        best = {}
        for q, a in zip(crit.order, raw):
            if a >= fraction * raw.max():
                best[float(q)] = max(best.get(float(q), 0.0), a)
        fit_orders = sorted(sorted(best, key=best.get, reverse=True)[:max_fit])
    import pandas as pd

    found = find_resonances(track, orders=fit_orders, response="velocity"
                            if quantity == "angular_velocity" else "displacement",
                            min_amplitude_fraction=0.0, min_snr=1e-6,
                            min_prominence=min_prominence,
                            sweep_correction=False).to_frame() if fit_orders else \
        pd.DataFrame(columns=["order", "speed_rpm", "frequency_hz", "amplitude",
                              "damping_ratio"])
    rows = []
    for _, c in crit.iterrows():
        cand = found[np.isclose(found["order"], c.order)] if len(found) else found
        row = dict(mode=int(c["mode"]), order=float(c.order),
                   speed_rpm_undamped=float(c.speed_rpm),
                   frequency_hz_undamped=float(c.frequency_hz),
                   vector_sum=float(c.vector_sum), major=bool(c.major))
        j = orders.index(float(c.order))
        if len(cand):
            k = int(np.argmin(np.abs(cand["speed_rpm"].to_numpy() - c.speed_rpm)))
            r = cand.iloc[k]
            # the resonance belongs to this critical if no other critical of the order is closer
            others = crit[np.isclose(crit.order, c.order)]["speed_rpm"].to_numpy()
            if np.argmin(np.abs(others - r.speed_rpm)) == np.argmin(np.abs(others - c.speed_rpm)) \
                    and abs(r.speed_rpm / c.speed_rpm - 1) < 0.15:
                row.update(speed_rpm=float(r.speed_rpm), frequency_hz=float(r.frequency_hz),
                           amplitude=float(r.amplitude), damping_ratio=float(r.damping_ratio),
                           identified=True)
                rows.append(row)
                continue
        near = np.abs(grid - c.speed_rpm) <= 0.03 * c.speed_rpm
        row.update(speed_rpm=float(c.speed_rpm), frequency_hz=float(c.frequency_hz),
                   amplitude=float(amp[near, j].max()) if near.any() else float("nan"),
                   damping_ratio=float("nan"), identified=False)
        rows.append(row)
    cols = ["mode", "order", "speed_rpm", "frequency_hz", "amplitude", "damping_ratio",
            "speed_rpm_undamped", "frequency_hz_undamped", "vector_sum", "major", "identified"]
    predicted = pd.DataFrame(rows, columns=cols)
    # a critical is expected in the measurement when its resonance shows in the prediction
    big = predicted["amplitude"].max() if len(predicted) else 0.0
    predicted["significant"] = predicted["identified"] & (predicted["amplitude"] >= 0.05 * big)
    response_da = xr.DataArray(amp.T, dims=("order", "rpm"), coords={"order": orders, "rpm": grid},
                               attrs={"units": units, "amplitude": "peak", "node": node})
    return predicted, response_da, grid, pred_stress
