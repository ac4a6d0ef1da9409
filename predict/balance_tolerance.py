"""What an engine's balance may leave behind: masses fixed to the crankshaft and manufacturing
tolerances, from the model file's ``[balance]`` table, and the residual shaking forces and
moments they allow per order.

A balanced engine's nominal residual is zero at some orders (the primary force and couple of
an in-line four, the first order of a six); what a real one shakes there comes from its
manufacturing tolerances — pistons and rods within their weight classes, the crankshaft within
its balancing grade. The model states them::

    [balance]
    reciprocating_mass_tolerance = 0.004   # kg, ± per cylinder (piston/rod weight class)
    rotating_mass_tolerance = 0.004        # kg, ± per throw at crank radius (big-end class)
    crankshaft_unbalance = 3.0e-5          # kg·m, residual unbalance per end plane
    relative_tolerance = 0.10              # of each non-zero nominal residual (mass data, model)

    [[balance.mass]]                       # masses fixed to the crankshaft (counterweights,
    mass = 0.02                            # trial or added masses), kg
    radius = 0.05                          # m from the crankshaft axis
    angle_deg = 90.0                       # ahead of throw 1 in the direction of rotation
    position = 0.0                         # m along the crankshaft (cylinder-position axis)

A crankshaft balanced to ISO 21940-11 grade G (mm/s) at its highest service speed Ω has a
permissible residual ``U = G · m_crank / Ω`` (shared by the two planes).

The allowed residual of an order is the worst case of the tolerances (each at its limit, all
in the phase that adds up — a bound, never exceeded by a part inside its tolerances), computed
per rotating component (forward P, backward Q; :mod:`predict.balance`) of force and moment
from the exact per-cylinder coefficients of the balance model, plus ``relative_tolerance`` of
the nominal value.

References
----------
Zhao (ed.), *Engine Design* ch. 3 §2 (forward and backward rotating vectors per cylinder);
ISO 21940-11:2016 (balance quality grades G, permissible residual unbalance).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._toml import load_toml
from .errors import ModelError

__all__ = ["BalanceSpec", "allowed_residuals"]


@dataclass(frozen=True)
class BalanceSpec:
    """Masses fixed to the crankshaft and manufacturing tolerances of an engine's balance.

    Attributes
    ----------
    masses : tuple of predict.balance.Counterweight
        Counterweights, trial or added masses (``mass_radius`` kg·m, ``angle_deg`` ahead of
        throw 1, ``position`` m).
    reciprocating_mass_tolerance : float
        ± kg per cylinder.
    rotating_mass_tolerance : float
        ± kg per throw, at crank radius.
    crankshaft_unbalance : float
        kg·m of residual unbalance in each of the two end planes (first and last cylinder).
    relative_tolerance : float
        Fraction of each non-zero nominal residual allowed on top (mass data, model).
    stated : bool
        Whether the model states any tolerance (else a nominally balanced order cannot be
        judged).
    source : str

    Examples
    --------
    >>> BalanceSpec().stated, BalanceSpec(crankshaft_unbalance=1e-5).stated
    (False, True)
    """

    masses: tuple = ()
    reciprocating_mass_tolerance: float = 0.0
    rotating_mass_tolerance: float = 0.0
    crankshaft_unbalance: float = 0.0
    relative_tolerance: float = 0.1
    source: str = ""

    def __post_init__(self):
        for name in ("reciprocating_mass_tolerance", "rotating_mass_tolerance",
                     "crankshaft_unbalance", "relative_tolerance"):
            value = getattr(self, name)
            if not np.isfinite(value) or value < 0:
                raise ModelError(f"{name}={value!r} must be a finite number >= 0")

    @property
    def stated(self) -> bool:
        return bool(self.reciprocating_mass_tolerance or self.rotating_mass_tolerance
                    or self.crankshaft_unbalance)

    @classmethod
    def from_toml(cls, path):
        """Read the ``[balance]`` table of a model file (absent: no masses, no tolerances).

        Raises
        ------
        ModelError
            Naming the file and key of a bad or unknown entry.

        Examples
        --------
        >>> import tempfile, os
        >>> text = ('[balance]\\ncrankshaft_unbalance = 2e-5\\n[[balance.mass]]\\n'
        ...         'mass = 0.01\\nradius = 0.05\\nangle_deg = 90\\nposition = 0.1\\n')
        >>> with tempfile.TemporaryDirectory() as d:
        ...     p = os.path.join(d, "e.toml")
        ...     _ = open(p, "w").write(text)
        ...     spec = BalanceSpec.from_toml(p)
        >>> spec.stated, round(spec.masses[0].mass_radius, 6), spec.masses[0].angle_deg
        (True, 0.0005, 90.0)
        """
        from .balance import Counterweight

        doc = load_toml(path)
        t = doc.table("balance", default=None)
        if t is None:
            return cls(source=str(path))
        masses = []
        for m in t.tables("mass", None):
            masses.append(Counterweight(
                mass_radius=(m.number("mass", low=0.0, unit="kg", plausible=(1e-4, 1e4))
                             * m.number("radius", low=0.0, unit="m", plausible=(1e-3, 5.0))),
                angle_deg=m.number("angle_deg", unit="deg", plausible=(1e-3, 360.0)),
                position=m.number("position", 0.0, unit="m", plausible=(1e-4, 100.0))))
            m.check_unknown(["description", "name"])
        spec = cls(masses=tuple(masses),
                   reciprocating_mass_tolerance=t.number("reciprocating_mass_tolerance", 0.0,
                                                         low=0.0, unit="kg",
                                                         plausible=(1e-6, 100.0)),
                   rotating_mass_tolerance=t.number("rotating_mass_tolerance", 0.0, low=0.0,
                                                    unit="kg", plausible=(1e-6, 100.0)),
                   crankshaft_unbalance=t.number("crankshaft_unbalance", 0.0, low=0.0,
                                                 unit="kg*m", plausible=(1e-9, 10.0)),
                   relative_tolerance=t.number("relative_tolerance", 0.1, low=0.0, unit="1",
                                               plausible=(1e-4, 1.0)),
                   source=str(path))
        t.check_unknown(["description"])
        return spec


def allowed_residuals(engine, spec, *, omega, orders=(1, 2, 4, 6, 8)):
    """Nominal residual and its tolerance per order and rotating component.

    Parameters
    ----------
    engine : predict.engine.Engine
    spec : BalanceSpec
    omega : float
        Crank speed, rad/s.
    orders : sequence of int

    Returns
    -------
    dict
        ``orders``; ``nominal`` — the :func:`predict.balance.unbalance` dataset with the
        spec's masses; ``tolerance`` — a dict of arrays (per order) ``force_forward``,
        ``force_backward`` (N), ``moment_forward``, ``moment_backward`` (N·m): worst-case
        manufacturing deviation of each component plus ``relative_tolerance`` of its nominal
        magnitude (exactly zero for a balanced order without stated tolerances); ``round_off``
        — ``force`` (N) and ``moment`` (N·m) levels below which a nominal value is zero.

    Examples
    --------
    A single cylinder whose piston may be 10 g heavy or light: its primary forward and
    backward components may each move by ``0.5 · 0.01 · r · ω²``, the rotating tolerance adds
    ``0.01 · r · ω²`` to the forward one:

    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
    ...            reciprocating_mass=1.0, rotating_mass=0.5)
    >>> spec = BalanceSpec(reciprocating_mass_tolerance=0.01, rotating_mass_tolerance=0.01,
    ...                    relative_tolerance=0.0)
    >>> tol = allowed_residuals(e, spec, omega=100.0, orders=[1])["tolerance"]
    >>> round(float(tol["force_forward"][0]), 3), round(float(tol["force_backward"][0]), 3)
    (7.5, 2.5)
    """
    from .balance import _axial_harmonics, _orders, unbalance

    orders = _orders(orders)
    omega = float(omega)
    w2 = omega * omega
    nominal = unbalance(engine, omega=omega, orders=orders, counterweights=spec.masses)
    dz = np.abs(engine.cylinder_positions - engine.reference_position)
    tol = {k: np.zeros(orders.size) for k in ("force_forward", "force_backward",
                                              "moment_forward", "moment_backward")}
    # reciprocating masses: each cylinder's forward and backward vectors are ½ H_i,n ω², linear
    # in its mass (exact coefficients of the balance model)
    if spec.reciprocating_mass_tolerance:
        h = _axial_harmonics(engine, int(orders.max()))[:, orders]
        m = engine.reciprocating_mass
        per_kg = np.zeros_like(h, dtype=float)
        ok = m > 0
        per_kg[ok] = np.abs(h[ok]) / m[ok, None]
        if (~ok).any():   # a massless cylinder: the same kinematics as a unit-mass plain one
            from .kinematics import series_coefficients

            a = np.abs(series_coefficients(engine.lam, int(orders.max())))[orders]
            per_kg[~ok] = engine.crank_radius * a[None, :]
        dev = 0.5 * spec.reciprocating_mass_tolerance * per_kg * w2       # (cyl, order)
        for part in ("forward", "backward"):
            tol[f"force_{part}"] += dev.sum(axis=0)
            tol[f"moment_{part}"] += (dev * dz[:, None]).sum(axis=0)
    one = orders == 1
    if one.any():
        # rotating masses at crank radius, crankshaft residual unbalance in the end planes:
        # forward vectors at order 1
        if spec.rotating_mass_tolerance:
            f = spec.rotating_mass_tolerance * engine.crank_radius * w2
            tol["force_forward"][one] += f * engine.n_cylinders
            tol["moment_forward"][one] += f * dz.sum()
        if spec.crankshaft_unbalance:
            planes = np.unique([engine.cylinder_positions.min(),
                                engine.cylinder_positions.max()])
            f = spec.crankshaft_unbalance * w2
            tol["force_forward"][one] += f * planes.size
            tol["moment_forward"][one] += f * np.abs(planes - engine.reference_position).sum()
    # nominal values below the round-off of the sums (1e-11 of the engine's total centrifugal
    # force, times its length for moments) are zero: a balanced order has no relative part
    masses = np.sum(engine.reciprocating_mass + engine.rotating_mass) * engine.crank_radius + \
        sum(cw.mass_radius for cw in spec.masses)
    round_force = 1e-11 * float(masses) * w2 * float(max(orders.max(), 1)) ** 2
    span = max(float(np.ptp(engine.cylinder_positions)), engine.crank_radius)
    round_moment = round_force * span
    for part in ("forward", "backward"):
        for name, level in (("force", round_force), ("moment", round_moment)):
            value = nominal[f"{name}_{part}"].values
            tol[f"{name}_{part}"] += spec.relative_tolerance * np.where(value > level, value,
                                                                        0.0)
    return {"orders": orders, "nominal": nominal, "tolerance": tol,
            "round_off": {"force": round_force, "moment": round_moment}}
