"""Exciting torque of a bench without an engine: orders and torques given in the model file.

A motor-driven shaft line (a test rig, a pump or fan drive) has no cylinders and no gas
pressure; what excites it is stated in the shaft-line TOML's ``[excitation]`` table (node,
orders, optionally their torque amplitudes and phases, a constant or speed-squared law; see
:func:`predict.torsion.from_toml`). :func:`given_forcing` turns it into the node torques the
forced response needs. Without torques the response is computed for 1 N·m per order: the
critical speeds, mode shapes and the stress per unit of measured amplitude are right, the
absolute amplitudes are not predicted (the pipeline then compares speeds only).
"""

from __future__ import annotations

import numpy as np

from crankbench.predict.errors import ModelError

__all__ = ["given_excitation", "given_forcing", "default_orders"]


def given_excitation(system) -> dict | None:
    """The model's ``[excitation]`` settings (None for an engine-driven model or none given).

    Examples
    --------
    >>> from pathlib import Path
    >>> from crankbench.predict.torsion import from_toml
    >>> root = Path(__file__).resolve().parents[1]
    >>> exc = given_excitation(from_toml(root / "sample_data/shaftlines/motor_bench.toml"))
    >>> exc["node"], exc["orders"]
    ('motor', [1.0, 2.0, 4.0])
    """
    exc = (getattr(system, "operating", None) or {}).get("excitation")
    if exc is None or getattr(system, "engine", None) is not None:
        return None
    return exc


def default_orders(system, max_order=12.0):
    """The orders to predict: the given excitation's, else the engine's (system default)."""
    exc = given_excitation(system)
    if exc is None:
        return system.default_orders()
    return np.asarray([q for q in exc["orders"] if q <= max_order + 1e-9], float)


def given_forcing(system, speed_rpm, orders, *, load=None):
    """The system with the excitation node as its only forced node, and its torques.

    Parameters
    ----------
    system : TorsionalSystem
        With ``operating["excitation"]``.
    speed_rpm : array_like
        Speeds, rpm.
    orders : sequence of float
        Orders wanted; those the excitation does not name get no torque.
    load : LoadCase, optional
        Not used for a given excitation (its own ``law`` applies); accepted for symmetry.

    Returns
    -------
    (TorsionalSystem, ndarray (n_s, n_o) complex)
        The system to solve and the torque harmonics, N·m.

    Examples
    --------
    >>> from pathlib import Path
    >>> from crankbench.predict.torsion import from_toml
    >>> root = Path(__file__).resolve().parents[1]
    >>> s = from_toml(root / "sample_data/shaftlines/motor_bench.toml")
    >>> forced, torque = given_forcing(s, [750.0, 1500.0], [1.0, 2.0, 3.0])
    >>> np.abs(torque).round(3).tolist()                 # orders 1 and 2 at law speed_squared
    [[0.5, 0.25, 0.0], [2.0, 1.0, 0.0]]
    """
    exc = given_excitation(system)
    if exc is None:
        raise ModelError("the model has no [excitation] table (a bench without an engine "
                         "needs one: node, orders, optionally torque)")
    speed_rpm = np.asarray(speed_rpm, float)
    node = exc.get("node") or system.node_names[0]
    i = system.node_names.index(node)
    given = {float(q): k for k, q in enumerate(exc["orders"])}
    torque = exc.get("torque")
    phase = exc.get("phase_deg")
    h = np.zeros((speed_rpm.size, len(orders)), complex)
    for j, q in enumerate(orders):
        k = given.get(float(q))
        if k is None:
            continue
        amp = 1.0 if torque is None else float(torque[k])
        h[:, j] = amp * np.exp(1j * np.radians(0.0 if phase is None else float(phase[k])))
    if exc.get("law") == "speed_squared":
        h *= ((speed_rpm / float(exc["reference_rpm"])) ** 2)[:, None]
    forced = system.replace(cylinder_nodes=[i], firing_angles_deg=[0.0])
    return forced, h
