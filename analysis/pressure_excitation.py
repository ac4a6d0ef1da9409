"""Torque excitation from indicator results: gas-torque harmonics of the measured cycles.

Helpers of :mod:`analysis.pressure` (importable from there too): the mean cycles of each
measured cylinder as an :class:`predict.torsion.excitation.Excitation`
(:func:`measured_excitation`), the harmonics of every cycle (:func:`cycle_gas_harmonics`) and,
on a run-up, the gas torque per speed bin as a :class:`predict.gas_torque.SpeedExcitation`
(:func:`measured_speed_excitation`). The reciprocating inertia torque comes from the engine
model; cylinders not measured take the mean of the measured ones (stated).
"""

from __future__ import annotations

import numpy as np

from crankbench.predict.errors import AnalysisError

__all__ = ["measured_excitation", "measured_speed_excitation", "cycle_gas_harmonics"]


def _results_list(results):
    from .pressure import IndicatorResult

    if isinstance(results, IndicatorResult):
        return [results]
    if isinstance(results, dict):
        return list(results.values())
    return list(results)


def _load_engine(engine):
    from .pressure import _load_engine as load

    return load(engine)


def measured_excitation(results, engine, *, orders=None, points=1440):
    """Torque excitation from the measured pressure (mean cycles) and the model's inertia.

    Parameters
    ----------
    results : IndicatorResult, list of them, or dict
        One per measured cylinder (:func:`indicator_analyses`).
    engine : predict.engine.Engine or path-like
    orders : array_like, optional
    points : int
        Quadrature samples per cycle.

    Returns
    -------
    predict.torsion.excitation.Excitation
        Per-cylinder gas harmonics where measured; unmeasured cylinders take the mean of the
        measured ones (the assumption is stated in ``source``).
    """
    from crankbench.predict.gas_torque import excitation_from_pressure

    engine = _load_engine(engine)
    results = _results_list(results)
    traces = {}
    for r in results:
        traces.setdefault(r.cylinder, r.trace())
    speed = np.mean([np.mean(r.speed_rpm) for r in results])
    src = f"measured pressure (mean cycles at {speed:.0f} rpm)"
    if len(traces) == 1 and engine.n_cylinders > 1 and 1 in traces:
        return excitation_from_pressure(engine, traces[1], orders=orders, points=points,
                                        source=src)
    return excitation_from_pressure(engine, traces, orders=orders, points=points, source=src)


def cycle_gas_harmonics(result, engine, orders):
    """Gas-torque harmonics of every analysed cycle of one cylinder, N·m.

    ``T(ψ) = −x'(ψ) A (p(ψ) − p_cc)`` on the cycle's grid (cylinder 1's geometry and
    ``p_cc`` = 1 bar, as :func:`predict.torsion.excitation.tangential_torque`), then
    ``G_q = (2/N) Σ T e^{−iqψ}`` (the rectangle rule of predict's excitation).

    Returns
    -------
    ndarray (n_cycles, n_o), complex

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> from crankbench.predict.pressure import synthetic_pressure
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.045, rod_length=0.15,
    ...            reciprocating_mass=0.6, bore=0.085, compression_ratio=10.0)
    >>> tr = synthetic_pressure(e, imep=1.0e6, points_per_cycle=7200)
    >>> psi = np.linspace(-2 * np.pi, 2 * np.pi, 7200, endpoint=False)
    >>> class R:                                        # a stand-in with the two fields used
    ...     crank_angle, pressure = psi, tr.at(psi)[None]
    >>> round(float(abs(cycle_gas_harmonics(R, e, [1.0])[0, 0])), 2)   # predict: 94.756
    94.75
    """
    from crankbench.predict.torsion.excitation import tangential_torque

    engine = _load_engine(engine)
    orders = np.atleast_1d(np.asarray(orders, float))
    psi = np.asarray(result.crank_angle, float)
    per_pa = tangential_torque(engine, psi, omega=0.0, pressure=1.0e5 + 1.0)
    torque = (np.atleast_2d(result.pressure) - 1.0e5) * per_pa[None, :]
    basis = np.exp(-1j * np.outer(psi, orders))
    return torque @ basis * (2.0 / psi.size)


def measured_speed_excitation(results, engine, *, orders=None, bin_rpm=None):
    """Gas torque measured per speed bin (run-ups), the model's inertia beside it.

    The cycles of each pressure channel are grouped by their mean speed into bins of
    ``bin_rpm`` (default the larger of 25 rpm and 2.5 % of the mean speed); each bin's gas
    harmonics are the mean over its cycles (:func:`cycle_gas_harmonics`). Cylinders not
    measured take the mean of the measured ones (stated).

    Returns
    -------
    predict.gas_torque.SpeedExcitation
    """
    from crankbench.predict.gas_torque import SpeedExcitation, excitation_from_pressure

    engine = _load_engine(engine)
    results = _results_list(results)
    step = 0.5 if engine.cycle == 4 else 1.0
    orders = np.arange(step, 24 + step / 2, step) if orders is None else np.asarray(
        orders, float)
    speeds = np.concatenate([r.speed_rpm for r in results])
    width = float(bin_rpm) if bin_rpm is not None else max(25.0, 0.025 * speeds.mean())
    if not width > 0:
        raise AnalysisError(f"bin_rpm={bin_rpm!r} must be > 0")
    edges = np.arange(speeds.min(), speeds.max() + width, width)
    if edges.size < 2:
        edges = np.array([speeds.min(), speeds.min() + width])
    z = engine.n_cylinders
    per_cyl = {}
    for r in results:
        per_cyl.setdefault(r.cylinder, []).append(r)
    first = next(iter(per_cyl.values()))[0]
    nb = edges.size - 1
    gas = np.full((nb, orders.size, z), np.nan, complex)
    counts = np.zeros(nb, int)
    centres = np.full(nb, np.nan)
    for c, rs in per_cyl.items():
        h = np.concatenate([cycle_gas_harmonics(r, engine, orders) for r in rs])
        v = np.concatenate([r.speed_rpm for r in rs])
        b = np.clip(np.searchsorted(edges, v, side="right") - 1, 0, nb - 1)
        for k in range(nb):
            sel = b == k
            if sel.any():
                gas[k, :, c - 1] = h[sel].mean(axis=0)
                counts[k] = max(counts[k], int(sel.sum()))
                centres[k] = v[sel].mean() if np.isnan(centres[k]) else centres[k]
    keep = counts > 0
    gas, counts, centres = gas[keep], counts[keep], centres[keep]
    measured = sorted(per_cyl)
    mean = np.nanmean(gas[:, :, [c - 1 for c in measured]], axis=2)
    for c in range(1, z + 1):
        if c not in per_cyl:
            gas[:, :, c - 1] = mean
    inertia = excitation_from_pressure(engine, first.trace(), orders=orders).inertia
    missing = [c for c in range(1, z + 1) if c not in per_cyl]
    src = (f"measured pressure of cylinder(s) {', '.join(map(str, measured))} in "
           f"{centres.size} speed bins of {width:.0f} rpm ({centres.min():.0f}-"
           f"{centres.max():.0f} rpm, held outside)")
    if missing and len(measured) == 1:
        src += f"; taken for all {z} cylinders with their firing offsets (assumption: equal " \
               "cylinders)"
    elif missing:
        src += (f"; cylinder(s) {', '.join(map(str, missing))} not measured: the mean of the "
                "measured ones with their firing offsets (assumption)")
    return SpeedExcitation(speed_rpm=centres, orders=orders, gas=gas, inertia=inertia,
                           n_cylinders=z, source=src + "; inertia torque from the model",
                           cycles=counts)
