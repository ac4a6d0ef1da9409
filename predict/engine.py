"""The engine model: crank train geometry, masses, layout and firing order for any layout.

One :class:`Engine` describes inline, V (any bank angle, side-by-side rods), W, boxer/opposed
and radial engines (master and articulated rods), 2- or 4-stroke, with arbitrary crank angles
and firing order.  Everything downstream (forces, torque, balance, torsional excitation,
synthetic records) asks the engine for the exact motion of each piston.

Angle convention (engine frame, seen from the front, docs/DESIGN.md): the shaft angle θ and the
cylinder-axis (bank) angles β are measured from the vertical in the direction of rotation; throw
i sits αᵢ ahead of throw 1, so cylinder i is at TDC when θ + αᵢ = βᵢ and its own crank angle
from TDC is ψᵢ = θ + αᵢ − βᵢ.  In-plane vectors are written as complex numbers
``vertical + 1j * horizontal`` (the horizontal axis pointing the way the top of the crank
moves), so a direction at angle φ from the vertical is exp(1j φ).

Articulated rods (radial engines): the rod of cylinder j is pinned to the master rod of
cylinder m at a link pin a distance ``link_radius`` from the crank pin, at ``link_angle_deg``
from the master-rod centre line.  The link pin does not run on a circle, so the articulated
piston's motion differs from a plain slider crank (different stroke, TDC shift, odd orders) —
this is the articulated-rod kinematic correction, computed here exactly from the geometry.

References
----------
Liang Shoupan, *Engine Dynamics* (1948), ch. 3 (V and radial engines, master and articulated
rods, effect of the articulated-rod linkage).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import _linkage
from ._toml import load_toml
from ._validate import check_finite_array, check_int, check_nonnegative, check_positive
from .errors import ModelError
from .kinematics import check_geometry

__all__ = ["Engine", "ArticulatedRod"]

log = logging.getLogger("crankbench")


@dataclass(frozen=True)
class ArticulatedRod:
    """An articulated (link) rod of a radial engine.

    Attributes
    ----------
    master : int
        0-based index of the master cylinder whose rod carries the link pin.
    link_radius : float
        Distance crank-pin centre → link-pin centre on the master rod, m.
    link_angle_deg : float
        Angle of the link pin from the master-rod centre line, deg, measured like the bank
        angles (usually equal to the bank-angle difference to the master cylinder).
    rod_length : float
        Link-pin → piston-pin length of the articulated rod, m.
    """

    master: int
    link_radius: float
    link_angle_deg: float
    rod_length: float


def _optional_per_cylinder(values, name: str, n: int) -> np.ndarray:
    """A per-cylinder list (one finite value per cylinder) or zeros when None."""
    if values is None:
        return np.zeros(n)
    arr = check_finite_array(values, name, ndim=1, error=ModelError)
    if arr.size != n:
        raise ModelError(f"{name} has {arr.size} values, expected {n} "
                         "(one per cylinder, like crank_angles_deg)")
    return arr


class Engine:
    """A reciprocating engine's crank train: geometry, masses, layout, cycle and firing order.

    Parameters
    ----------
    crank_angles_deg : sequence of float
        Angle of each cylinder's throw ahead of throw 1, deg (cylinders sharing a crank pin
        repeat its angle).
    crank_radius : float
        Crank radius r (half the stroke), m.
    rod_length : float
        Connecting-rod length l, centre to centre, m (master rod for radials).
    reciprocating_mass : float or sequence of float
        Reciprocating mass per cylinder (piston group + small-end share of the rod), kg.
    rotating_mass : float or sequence of float
        Rotating mass per cylinder reduced to the crank radius (big-end share of the rod + the
        unbalanced throw share), kg; 0 allowed.
    cylinder_positions : sequence of float, optional
        Axial position of each cylinder along the crankshaft, m (None: all in one plane).
    bank_angles_deg : sequence of float, optional
        Cylinder-axis angle from the vertical in the direction of rotation, deg (None: all 0).
    cycle : {2, 4}
        Strokes per cycle.
    firing_order : sequence of int, optional
        Cylinder numbers (1-based) in firing order. Checked to be a permutation consistent with
        the crank and bank angles; each cylinder fires at whichever of its TDCs gives the most
        even firing in that order (beyond 16 cylinders: the earliest one). None picks the most
        even firing consistent with the geometry (up to 16 cylinders).
    bore : float, optional
        Cylinder bore, m (needed for gas forces).
    name : str
        Engine name for tables and plots.
    pin_offset : float
        Piston-pin offset (désaxé), m, same for every cylinder.
    firing_angles_deg : sequence of float, optional
        Explicit firing angles (deg, relative to cylinder 1) for uneven-firing engines where a
        firing order alone is ambiguous (each must be a TDC of its cylinder).
    articulated : sequence of ArticulatedRod or None, optional
        Per cylinder: None for a plain rod, or the articulated-rod geometry.
    compression_ratio : float, optional
        Geometric compression ratio (used by the synthetic pressure model).
    rated_speed_rpm : float, optional
        Rated speed, rpm (default operating point of the CLI).
    combustion : dict, optional
        Keyword arguments for :func:`predict.pressure.synthetic_pressure` (from the
        ``[engine.combustion]`` TOML table).
    rod_inertia_correction : float or sequence of float
        J_G − m h k l² of each plain rod (kg·m², usually negative), the inertia through which
        the residual couple of the two-point rod acts (:meth:`predict.masses.Rod.two_point`);
        adds −ΔJ ω² φ' φ'' to the crank torque. 0 (default) keeps the classical two-point
        (2-mass) rod model, a lower fidelity whose torque error is this residual couple.
    rotary : bool
        Rotary engine (Gnome, Le Rhône): the crankshaft stands still and the cylinders,
        crankcase and propeller turn; θ is then the angle of the cylinder block relative to
        the fixed crank. The reciprocating masses also move round the axis at radius x, so
        their inertia torque gains −m ω² x x' (kinetic energy ½ m ω² (x'² + x²), Liang 1948
        ch. 10); the gas torque is unchanged (kinematic inversion).
    double_acting : bool
        Double-acting cylinders: combustion on both sides of the piston, the lower chamber
        firing half a working cycle after the upper one with the same pressure trace. The
        net gas force towards the crank is ``(p_top − p_cc) A − (p_bottom − p_cc)(A − A_rod)``
        (p_cc: the pressure outside, acting on the rod's cross-section).
    piston_rod_diameter : float
        Piston-rod diameter through the lower chamber, m (double-acting only). 0 is the
        textbook lower fidelity that neglects the rod area; its error in the gas force is
        p_bottom·A_rod.
    series_order, lambda_terms : int, optional
        Textbook lower fidelity of the piston motion: None (default) is the exact slider
        crank; ``series_order=N`` truncates its harmonic series after order N and
        ``lambda_terms=k`` keeps only k powers of λ per coefficient (``series_order=2,
        lambda_terms=1`` is x = r cos θ + l − (λr/4)(1 − cos 2θ), a = rω²(cos θ + λ cos 2θ)).
        Its acceleration error relative to r ω² is
        :func:`predict.kinematics.series_error`. Plain rods with a centred pin only.

    References
    ----------
    Liang 1948, ch. 2-3; Zhao (ed.) *Engine Design* ch. 3 (crank arrangement and firing).

    Examples
    --------
    >>> e = Engine(crank_angles_deg=[0, 180, 180, 0], crank_radius=0.04, rod_length=0.14,
    ...            reciprocating_mass=0.5, cylinder_positions=[0, 0.09, 0.18, 0.27],
    ...            firing_order=[1, 3, 4, 2], bore=0.08)
    >>> e.n_cylinders, round(e.lam, 4), e.firing_angles_deg().tolist()
    (4, 0.2857, [0.0, 540.0, 180.0, 360.0])
    """

    def __init__(self, *, crank_angles_deg, crank_radius, rod_length, reciprocating_mass,
                 rotating_mass=0.0, cylinder_positions=None, bank_angles_deg=None, cycle=4,
                 firing_order=None, bore=None, name="engine", pin_offset=0.0,
                 firing_angles_deg=None, articulated=None, compression_ratio=None,
                 rated_speed_rpm=None, combustion=None, rod_inertia_correction=0.0,
                 source=None, series_order=None, lambda_terms=None, rotary=False,
                 double_acting=False, piston_rod_diameter=0.0):
        alpha = check_finite_array(crank_angles_deg, "crank_angles_deg", ndim=1, min_length=1,
                                   error=ModelError)
        n = alpha.size
        self._n = n
        self.name = str(name)
        self.source = source
        self.crank_radius, self.rod_length, self.pin_offset = check_geometry(
            crank_radius, rod_length, pin_offset)
        self._alpha_deg = _readonly(alpha)
        self._recip = _readonly(self._per_cylinder(reciprocating_mass, "reciprocating_mass"))
        self._rot = _readonly(self._per_cylinder(rotating_mass, "rotating_mass"))
        self._pos = _readonly(_optional_per_cylinder(cylinder_positions, "cylinder_positions", n))
        self._beta_deg = _readonly(_optional_per_cylinder(bank_angles_deg, "bank_angles_deg", n))
        self.cycle = check_int(cycle, "cycle", error=ModelError)
        if self.cycle not in (2, 4):
            raise ModelError(f"cycle={cycle!r} must be 2 or 4 (strokes per cycle)")
        self.bore = None if bore is None else check_positive(bore, "bore", error=ModelError)
        self.compression_ratio = None if compression_ratio is None else check_positive(
            compression_ratio, "compression_ratio", error=ModelError)
        if self.compression_ratio is not None and self.compression_ratio <= 1:
            raise ModelError(f"compression_ratio={compression_ratio!r} must be > 1")
        self.rated_speed_rpm = None if rated_speed_rpm is None else check_positive(
            rated_speed_rpm, "rated_speed_rpm", error=ModelError)
        self.combustion = dict(combustion or {})
        self._articulated = self._check_articulated(articulated)
        corr = np.asarray(rod_inertia_correction, dtype=float)
        if corr.ndim == 0:
            corr = np.full(n, float(corr))
        corr = check_finite_array(corr, "rod_inertia_correction", ndim=1, error=ModelError)
        if corr.size != n:
            raise ModelError(f"rod_inertia_correction has {corr.size} values, expected {n}")
        bad = [i for i in range(n) if corr[i] != 0.0 and self._articulated[i] is not None]
        if bad:
            raise ModelError(f"rod_inertia_correction[{bad[0]}] must be 0: the residual couple "
                             "is modelled for plain rods only")
        self._rod_corr = _readonly(corr)
        if not isinstance(rotary, (bool, np.bool_)):
            raise ModelError(f"rotary={rotary!r} must be true or false")
        self.rotary = bool(rotary)
        if not isinstance(double_acting, (bool, np.bool_)):
            raise ModelError(f"double_acting={double_acting!r} must be true or false")
        self.double_acting = bool(double_acting)
        self.piston_rod_diameter = check_nonnegative(piston_rod_diameter, "piston_rod_diameter",
                                                     error=ModelError)
        if self.piston_rod_diameter > 0 and not self.double_acting:
            raise ModelError("piston_rod_diameter needs double_acting=True (a trunk piston "
                             "has no piston rod through the lower chamber)")
        if self.double_acting and self.bore is not None \
                and self.piston_rod_diameter >= self.bore:
            raise ModelError(f"piston_rod_diameter={piston_rod_diameter!r} must be smaller than "
                             f"bore={self.bore!r}")
        self._firing_order, self._firing = self._resolve_firing(firing_order, firing_angles_deg)
        self.series_order = None if series_order is None else check_int(
            series_order, "series_order", error=ModelError)
        if self.series_order is not None and self.series_order < 1:
            raise ModelError(f"series_order={series_order!r} must be >= 1")
        if lambda_terms is not None and self.series_order is None:
            raise ModelError("lambda_terms needs series_order (the harmonic series it truncates)")
        if self.series_order is not None and (self.pin_offset != 0 or any(
                a is not None for a in self._articulated)):
            raise ModelError("series_order (textbook piston series) needs plain rods and a "
                             "centred piston pin")
        self.lambda_terms = lambda_terms
        self._series = None
        if self.series_order is not None:
            from .kinematics import displacement_coefficients

            c = displacement_coefficients(self.crank_radius / self.rod_length,
                                          self.series_order, lambda_terms=lambda_terms)
            self._series = c

    # ------------------------------------------------------------------ validation helpers
    def _per_cylinder(self, value, name):
        if np.ndim(value) == 0:
            return np.full(self._n, check_nonnegative(value, name, error=ModelError))
        arr = check_finite_array(value, name, ndim=1, error=ModelError)
        if arr.size != self._n:
            raise ModelError(f"{name} has {arr.size} values, expected {self._n} "
                             "(one per cylinder) or a single number")
        if (arr < 0).any():
            i = int(np.flatnonzero(arr < 0)[0])
            raise ModelError(f"{name}[{i}]={float(arr[i])!r} must be >= 0 (kg)")
        return arr

    def _check_articulated(self, articulated):
        if articulated is None:
            return (None,) * self._n
        arts = list(articulated)
        if len(arts) != self._n:
            raise ModelError(f"articulated has {len(arts)} entries, expected {self._n} "
                             "(None for a plain rod)")
        for j, a in enumerate(arts):
            if a is None:
                continue
            if not isinstance(a, ArticulatedRod):
                raise ModelError(f"articulated[{j}] must be an ArticulatedRod or None")
            m = a.master
            if not (0 <= m < self._n) or m == j or arts[m] is not None:
                raise ModelError(f"articulated[{j}].master={m!r} must index a cylinder with a "
                                 "plain (master) rod other than itself")
            if self._alpha_deg[m] != self._alpha_deg[j]:
                raise ModelError(f"cylinder {j + 1} is articulated on cylinder {m + 1} but their "
                                 "crank_angles_deg differ (they must share a crank pin)")
            check_positive(a.link_radius, f"articulated[{j}].link_radius", error=ModelError)
            check_positive(a.rod_length, f"articulated[{j}].rod_length", error=ModelError)
            if a.rod_length <= self.crank_radius + a.link_radius:
                raise ModelError(f"articulated[{j}].rod_length={a.rod_length!r} must exceed "
                                 "crank_radius + link_radius")
        return tuple(arts)

    def _tdc_offsets_deg(self) -> np.ndarray:
        """Shaft angle (deg, 0..360) after cylinder 1's TDC at which each cylinder is at TDC."""
        d = (self._beta_deg - self._alpha_deg) - (self._beta_deg[0] - self._alpha_deg[0])
        return np.mod(d, 360.0)

    def _resolve_firing(self, firing_order, firing_angles_deg):
        n = self._n
        period = 180.0 * self.cycle
        d = self._tdc_offsets_deg()
        if firing_angles_deg is not None:
            f = check_finite_array(firing_angles_deg, "firing_angles_deg", ndim=1,
                                   error=ModelError)
            if f.size != n:
                raise ModelError(f"firing_angles_deg has {f.size} values, expected {n}")
            f = np.mod(f - f[0], period)
            bad = np.abs(((f - d) + 180.0) % 360.0 - 180.0) > 1e-6
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                raise ModelError(
                    f"firing_angles_deg[{i}]={firing_angles_deg[i]!r} is not a TDC of cylinder "
                    f"{i + 1}: its TDCs are at {d[i]:g} deg (+360k) after cylinder 1's")
            order = tuple(int(i) + 1 for i in np.argsort(f, kind="stable"))
            if firing_order is not None and tuple(self._check_order(firing_order)) != order:
                raise ModelError(f"firing_order={list(firing_order)} disagrees with "
                                 f"firing_angles_deg (which give {list(order)})")
            return order, _readonly(f)
        if firing_order is not None:
            order = self._check_order(firing_order)
            f = self._assign_firing(order, d, period)
            if f is None:
                raise ModelError(
                    f"firing_order={list(firing_order)} is not consistent with the crank and "
                    f"bank angles: no choice of TDCs makes the cylinders fire in this order "
                    f"within one {self.cycle}-stroke cycle of {period:g} deg (each cylinder's "
                    f"TDCs after cylinder 1's: {', '.join(f'{v:g}' for v in d)} deg, +360k)")
            gaps = np.diff(np.concatenate([np.sort(f), [period]]))
            best_gaps = gaps
            if n <= 16:
                best = self._assign_firing(None, d, period)
                best_gaps = np.diff(np.concatenate([np.sort(best), [period]]))
            if gaps.max() > best_gaps.max() + 1e-6:
                log.warning("engine %r: firing order %s gives uneven intervals %s deg; the "
                            "geometry allows intervals no larger than %g deg", self.name,
                            "-".join(map(str, order)), np.round(gaps, 3).tolist(),
                            best_gaps.max())
            return tuple(order), _readonly(f)
        # no firing order: the most even firing consistent with the TDCs
        f = self._assign_firing(None, d, period)
        order = tuple(int(i) + 1 for i in np.argsort(f, kind="stable"))
        return order, _readonly(f)

    def _assign_firing(self, order, d, period):
        """Firing angles (deg) choosing one TDC per cylinder: the most even assignment (smallest
        largest interval, then earliest) that fires in ``order`` (None: any order)."""
        n = self._n
        if self.cycle == 2 or n == 1:
            f = d.copy()
            if order is not None and np.any(np.diff(f[np.asarray(order) - 1]) <= 0):
                return None
            return f
        if n > 16:
            if order is None:
                raise ModelError(f"an engine with {n} cylinders needs an explicit firing_order")
            f = np.zeros(n)
            prev = 0.0
            for cyl in order[1:]:
                cands = d[cyl - 1] + np.array([0.0, 360.0])
                later = cands[cands > prev + 1e-9]
                if later.size == 0:
                    return None
                prev = f[cyl - 1] = later[0]
            return f if prev < period - 1e-9 else None
        bits = (np.arange(2 ** (n - 1))[:, None] >> np.arange(n - 1)[None, :]) & 1
        cand = np.concatenate([np.zeros((bits.shape[0], 1)), d[1:] + 360.0 * bits], axis=1)
        if order is not None:
            seq = cand[:, np.asarray(order) - 1]
            ok = np.all(np.diff(seq, axis=1) > 1e-9, axis=1)
            if not ok.any():
                return None
            cand = cand[ok]
        s = np.sort(cand, axis=1)
        gaps = np.diff(np.concatenate([s, np.full((s.shape[0], 1), period)], axis=1), axis=1)
        worst = gaps.max(axis=1)
        k = int(np.flatnonzero(worst <= worst.min() + 1e-9)[0])
        return cand[k].copy()

    def _check_order(self, firing_order):
        try:
            order = [int(v) for v in firing_order]
        except (TypeError, ValueError):
            raise ModelError(f"firing_order={firing_order!r} must be a list of cylinder "
                             "numbers") from None
        if sorted(order) != list(range(1, self._n + 1)):
            raise ModelError(f"firing_order={list(firing_order)} must list each cylinder "
                             f"1..{self._n} exactly once")
        k = order.index(1)
        return order[k:] + order[:k]

    # ------------------------------------------------------------------ properties
    @property
    def n_cylinders(self) -> int:
        """Number of cylinders."""
        return self._n

    @property
    def lam(self) -> float:
        """λ = crank_radius / rod_length."""
        return self.crank_radius / self.rod_length

    @property
    def stroke(self) -> float:
        """Stroke of a plain-rod cylinder, m (2r for a centred pin)."""
        r, l, e = self.crank_radius, self.rod_length, self.pin_offset
        return float(np.sqrt((l + r) ** 2 - e * e) - np.sqrt((l - r) ** 2 - e * e))

    def net_gas_force(self, trace, crank_angle, crankcase_pressure=1.0e5):
        """Gas force on one piston towards the crank, N, at ``crank_angle`` from that
        cylinder's firing TDC (rad): ``(p − p_cc) A`` for a trunk piston; for double-acting
        cylinders minus the lower chamber's ``(p(ψ − cycle/2) − p_cc)(A − A_rod)``.

        Examples
        --------
        >>> from crankbench.predict.pressure import PressureTrace
        >>> e = Engine(crank_angles_deg=[0], crank_radius=0.1, rod_length=0.4,
        ...            reciprocating_mass=1.0, bore=0.2, cycle=2, double_acting=True,
        ...            piston_rod_diameter=0.05)
        >>> tr = PressureTrace.from_measured(np.linspace(0, 2 * np.pi, 5)[:-1],
        ...                                  [5e6, 1e5, 1e5, 1e5], cycle=2)
        >>> round(float(e.net_gas_force(tr, np.pi)))   # lower chamber firing: −(5e6 − 1e5)(A − a)
        -144317
        """
        ang = np.asarray(crank_angle, float)
        area = self.piston_area
        force = (trace.at(ang) - crankcase_pressure) * area
        if self.double_acting:
            lower = area - np.pi * self.piston_rod_diameter ** 2 / 4
            force = force - (trace.at(ang - self.cycle_angle / 2) - crankcase_pressure) * lower
        return force

    @property
    def piston_area(self) -> float:
        """Piston crown area π bore²/4, m² (needs ``bore``)."""
        if self.bore is None:
            raise ModelError(f"engine {self.name!r} has no bore; piston_area needs it")
        return float(np.pi * self.bore**2 / 4)

    @property
    def swept_volume(self) -> float:
        """Swept volume of one cylinder, m³."""
        return self.piston_area * self.stroke

    @property
    def crank_angles_deg(self) -> np.ndarray:
        """Per-cylinder throw angle ahead of throw 1, deg (read-only)."""
        return self._alpha_deg

    @property
    def bank_angles_deg(self) -> np.ndarray:
        """Per-cylinder axis angle from the vertical in the direction of rotation, deg."""
        return self._beta_deg

    @property
    def cylinder_positions(self) -> np.ndarray:
        """Per-cylinder axial position along the crankshaft, m."""
        return self._pos

    @property
    def reciprocating_mass(self) -> np.ndarray:
        """Per-cylinder reciprocating mass, kg."""
        return self._recip

    @property
    def rotating_mass(self) -> np.ndarray:
        """Per-cylinder rotating mass at crank radius, kg."""
        return self._rot

    @property
    def rod_inertia_correction(self) -> np.ndarray:
        """Per-cylinder residual-couple inertia J_G − m h k l², kg·m²."""
        return self._rod_corr

    def rod_motion(self, theta):
        """Rod angle derivatives of every plain-rod cylinder at shaft angle θ.

        Returns
        -------
        dphi, d2phi : ndarray, shape (n_cylinders, len(theta))
            dφ/dθ and d²φ/dθ² (rad/rad, rad/rad²); zero rows for articulated cylinders.

        Examples
        --------
        >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
        ...            reciprocating_mass=1.0)
        >>> d1, d2 = e.rod_motion([0.0])
        >>> float(d1[0, 0])   # λ at TDC
        0.25
        """
        th = check_finite_array(theta, "theta", error=ModelError).reshape(-1)
        r, l, e = self.crank_radius, self.rod_length, self.pin_offset
        alpha = np.deg2rad(self._alpha_deg)
        beta = np.deg2rad(self._beta_deg)
        d1 = np.zeros((self._n, th.size))
        d2 = np.zeros_like(d1)
        for i in range(self._n):
            if self._articulated[i] is not None:
                continue
            psi = th + alpha[i] - beta[i]
            s = (r * np.sin(psi) - e) / l
            c = np.sqrt(1.0 - s * s)
            d1[i] = r * np.cos(psi) / (l * c)
            d2[i] = (l * s * d1[i] ** 2 - r * np.sin(psi)) / (l * c)
        return d1, d2

    @property
    def articulated(self) -> tuple:
        """Per cylinder: None (plain rod) or its :class:`ArticulatedRod`."""
        return self._articulated

    @property
    def firing_order(self) -> tuple[int, ...]:
        """Cylinder numbers (1-based) in firing order, starting with 1."""
        return self._firing_order

    @property
    def reference_position(self) -> float:
        """Axial reference point for moments: midpoint between the first and last cylinder
        along the shaft (the extreme cylinder positions), m."""
        return float(0.5 * (self._pos.min() + self._pos.max()))

    @property
    def cycle_angle(self) -> float:
        """Crank angle of one working cycle, rad (4π for 4-stroke, 2π for 2-stroke)."""
        return float(np.pi * self.cycle)

    @property
    def firing_tdc_shaft_angle(self) -> float:
        """Shaft angle θ (rad) at which cylinder 1 is at its TDC (β₁ − α₁)."""
        return float(np.deg2rad(self._beta_deg[0] - self._alpha_deg[0]))

    def firing_angles_deg(self) -> np.ndarray:
        """Crank angle (deg, 0..180·cycle) at which each cylinder fires, after cylinder 1.

        Derived from the crank and bank angles and the firing order: each cylinder fires at
        one of its TDCs, and the firing order fixes which one.

        Returns
        -------
        ndarray
            Per cylinder (in cylinder order), deg.

        Examples
        --------
        >>> e = Engine(crank_angles_deg=[0, 120, 240], crank_radius=0.04, rod_length=0.13,
        ...            reciprocating_mass=0.4, firing_order=[1, 2, 3])
        >>> e.firing_angles_deg().tolist()
        [0.0, 240.0, 480.0]
        """
        return self._firing.copy()

    def firing_intervals_deg(self) -> np.ndarray:
        """Crank angle between successive firings in firing order, deg."""
        f = np.sort(self._firing)
        return np.diff(np.concatenate([f, [180.0 * self.cycle]]))

    # ------------------------------------------------------------------ kinematics
    def piston_motion(self, theta):
        """Exact piston position and its θ-derivatives for every cylinder.

        Parameters
        ----------
        theta : array_like
            Shaft angle θ (rad, engine convention: from the vertical in the direction of
            rotation to throw 1).

        Returns
        -------
        x, dx, d2x : ndarray, shape (n_cylinders, len(theta))
            Piston-pin distance from the crank axis along each cylinder axis (m, positive
            towards the head) and its first and second derivatives with respect to θ (m/rad,
            m/rad²). At constant ω the velocity is ω·dx and the acceleration ω²·d2x.

        Examples
        --------
        >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
        ...            reciprocating_mass=1.0)
        >>> x, dx, d2x = e.piston_motion([0.0])
        >>> float(x[0, 0]), float(d2x[0, 0])
        (0.25, -0.0625)
        """
        th = check_finite_array(theta, "theta", error=ModelError).reshape(-1)
        r, l, e = self.crank_radius, self.rod_length, self.pin_offset
        x = np.empty((self._n, th.size))
        dx = np.empty_like(x)
        d2x = np.empty_like(x)
        alpha = np.deg2rad(self._alpha_deg)
        beta = np.deg2rad(self._beta_deg)
        for i in range(self._n):
            art = self._articulated[i]
            if art is None and self._series is not None:
                jet = _linkage.series_jet(th + alpha[i] - beta[i], r, l, self._series)
            elif art is None:
                jet = _linkage.plain_jet(th + alpha[i] - beta[i], r, l, e)
            else:
                m = art.master
                psi_m = th + alpha[m] - beta[m]
                jet = _linkage.articulated_jet(psi_m, art, beta[i] - beta[m], r, l, e)
            x[i], dx[i], d2x[i] = jet
        return x, dx, d2x

    def cylinder_volume(self, theta, *, compression_ratio=None):
        """Cylinder volume (m³) of every cylinder at shaft angle θ (rad).

        V = V_c + A (x_top − x) with V_c = V_s / (ε − 1), x_top the highest piston position.

        Returns
        -------
        ndarray, shape (n_cylinders, len(theta))

        Examples
        --------
        >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
        ...            reciprocating_mass=1.0, bore=0.1, compression_ratio=11.0)
        >>> v = e.cylinder_volume([0.0, np.pi])[0] * 1e6     # cm³
        >>> [round(float(x), 3) for x in v]
        [78.54, 863.938]
        """
        eps = compression_ratio if compression_ratio is not None else self.compression_ratio
        if eps is None:
            raise ModelError(f"engine {self.name!r}: cylinder_volume needs compression_ratio")
        eps = check_positive(eps, "compression_ratio", error=ModelError)
        x, _, _ = self.piston_motion(theta)
        top = self._x_top()[:, None]
        vc = self.swept_volume / (eps - 1.0)
        return vc + self.piston_area * (top - x)

    def _x_top(self):
        grid = np.linspace(0, 2 * np.pi, 4097)[:-1]
        x, _, _ = self.piston_motion(grid)
        return x.max(axis=1)

    def shaft_angle(self, crank_angle_from_firing):
        """Shaft angle θ (rad) for a crank angle measured from cylinder 1's firing TDC (rad)."""
        return np.asarray(crank_angle_from_firing, dtype=float) + self.firing_tdc_shaft_angle

    # ------------------------------------------------------------------ I/O
    def to_frame(self):
        """Per-cylinder table (angles in deg, positions in m, masses in kg)."""
        import pandas as pd

        return pd.DataFrame({
            "cylinder": np.arange(1, self._n + 1),
            "crank_angle_deg": self._alpha_deg,
            "bank_angle_deg": self._beta_deg,
            "position_m": self._pos,
            "reciprocating_mass_kg": self._recip,
            "rotating_mass_kg": self._rot,
            "firing_angle_deg": self._firing,
            "articulated_on": [0 if a is None else a.master + 1 for a in self._articulated],
            "rod_inertia_correction_kgm2": self._rod_corr,
        })

    def plot(self, ax=None):
        """Crank star (throws) and cylinder axes seen from the front; returns the figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots(figsize=(4, 4))
        else:
            fig = ax.figure
        for i in range(self._n):
            a = np.deg2rad(self._alpha_deg[i])
            b = np.deg2rad(self._beta_deg[i])
            ax.plot([0, np.sin(a)], [0, np.cos(a)], "k-", lw=2)
            ax.annotate(str(i + 1), (1.1 * np.sin(a), 1.1 * np.cos(a)))
            ax.plot([0, 2 * np.sin(b)], [0, 2 * np.cos(b)], "C0--", lw=0.8)
        ax.set_aspect("equal")
        ax.set_title(f"{self.name}: throws (black), cylinder axes (dashed)")
        return fig

    def __repr__(self) -> str:
        return (f"Engine(name={self.name!r}, n_cylinders={self._n}, cycle={self.cycle}, "
                f"crank_radius={self.crank_radius}, rod_length={self.rod_length})")

    @classmethod
    def from_toml(cls, path):
        """Load the top-level ``[engine]`` table of a model TOML file.

        Keys (SI unless named): ``name``, ``crank_angles_deg``, ``crank_radius`` (or
        ``stroke``), ``rod_length``, ``reciprocating_mass``, ``rotating_mass``,
        ``cylinder_positions`` (or ``cylinder_spacing`` for one row), ``bank_angles_deg``,
        ``cycle``, ``firing_order``, ``firing_angles_deg``, ``bore``, ``pin_offset``,
        ``compression_ratio``, ``rated_speed_rpm``, ``rod_inertia_correction``,
        ``[engine.combustion]`` and
        ``[[engine.articulated]]`` (``cylinder``, ``master``, ``link_radius``,
        ``link_angle_deg``, ``rod_length``; cylinders 1-based). Other top-level tables
        (``[shaftline]``, ``[mounts]``…) are left to their own loaders.

        Raises
        ------
        ModelError
            Naming the file and key, for a missing/invalid/unknown key.

        Examples
        --------
        >>> import tempfile, os
        >>> text = '[engine]\\ncrank_angles_deg = [0]\\ncrank_radius = 0.05\\n' \\
        ...        'rod_length = 0.2\\nreciprocating_mass = 1.2\\n'
        >>> with tempfile.TemporaryDirectory() as d:
        ...     p = os.path.join(d, "single.toml")
        ...     _ = open(p, "w").write(text)
        ...     Engine.from_toml(p).n_cylinders
        1
        """
        doc = load_toml(path)
        t = doc.table("engine", default=None)
        if t is None:
            raise ModelError(f"{path}: has no [engine] table")
        angles = t.numbers("crank_angles_deg", unit="deg", plausible=(1e-3, 720.0))
        n = angles.size
        if n == 0:
            t.fail("crank_angles_deg", "must list at least one cylinder")
        if "stroke" in t and "crank_radius" in t:
            t.fail("stroke", "give either stroke or crank_radius, not both")
        radius = (t.positive("stroke", unit="m", plausible=(2e-3, 6.0)) / 2 if "stroke" in t else
                  t.positive("crank_radius", unit="m", plausible=(1e-3, 3.0)))

        def masses(key, default, low=0.0, unit="kg", plausible=(1e-3, 1e5)):
            value = t.raw(key, default)
            if isinstance(value, list):
                return t.numbers(key, length=n, low=low, unit=unit, plausible=plausible)
            return t.number(key, default, low=low, unit=unit, plausible=plausible)

        if "cylinder_positions" in t and "cylinder_spacing" in t:
            t.fail("cylinder_spacing", "give either cylinder_positions or cylinder_spacing")
        if "cylinder_spacing" in t:
            positions = np.arange(n) * t.positive("cylinder_spacing", unit="m",
                                                  plausible=(5e-3, 10.0))
        else:
            positions = t.numbers("cylinder_positions", None, length=n, unit="m",
                                  plausible=(1e-3, 100.0))
        firing = t.raw("firing_order", None)
        if firing is not None and (not isinstance(firing, list) or not all(
                isinstance(v, int) and not isinstance(v, bool) for v in firing)):
            t.fail("firing_order", f"= {firing!r} must be an array of cylinder numbers")
        arts = None
        art_tables = t.tables("articulated", None)
        if art_tables:
            arts = [None] * n
            for a in art_tables:
                cyl = a.integer("cylinder", minimum=1)
                master = a.integer("master", minimum=1)
                if cyl > n or master > n:
                    a.fail("cylinder" if cyl > n else "master", f"must be <= {n}")
                arts[cyl - 1] = ArticulatedRod(
                    master=master - 1,
                    link_radius=a.positive("link_radius", unit="m", plausible=(1e-3, 2.0)),
                    link_angle_deg=a.number("link_angle_deg", unit="deg", plausible=(1e-3, 360.0)),
                    rod_length=a.positive("rod_length", unit="m", plausible=(5e-3, 10.0)))
                a.check_unknown()
        combustion = None
        ct = t.table("combustion", None)
        if ct is not None:
            from .pressure import combustion_from_table

            combustion = combustion_from_table(ct)
        kwargs = dict(
            name=t.string("name", Path(path).stem),
            crank_angles_deg=angles,
            crank_radius=radius,
            rod_length=t.positive("rod_length", unit="m", plausible=(5e-3, 10.0)),
            reciprocating_mass=masses("reciprocating_mass", ...),
            rotating_mass=masses("rotating_mass", 0.0),
            cylinder_positions=positions,
            bank_angles_deg=t.numbers("bank_angles_deg", None, length=n, unit="deg",
                                      plausible=(1e-3, 360.0)),
            cycle=t.integer("cycle", 4),
            firing_order=firing,
            firing_angles_deg=t.numbers("firing_angles_deg", None, length=n, unit="deg",
                                        plausible=(1e-3, 720.0)),
            bore=t.positive("bore", None, unit="m", plausible=(5e-3, 1.5)),
            pin_offset=t.number("pin_offset", 0.0, unit="m", plausible=(1e-5, 0.1)),
            compression_ratio=t.number("compression_ratio", None, low=1.0, strict_low=True, unit="1",
                                       plausible=(1.5, 40.0)),
            rated_speed_rpm=t.positive("rated_speed_rpm", None, unit="rpm", plausible=(10.0, 5e4)),
            combustion=combustion,
            rod_inertia_correction=masses("rod_inertia_correction", 0.0, low=None, unit="kg*m^2",
                                          plausible=(1e-9, 1e5)),
            series_order=t.integer("series_order", None, minimum=1),
            rotary=t.raw("rotary", False),
            double_acting=t.raw("double_acting", False),
            piston_rod_diameter=t.number("piston_rod_diameter", 0.0, low=0.0, unit="m",
                                         plausible=(1e-3, 1.0)),
            lambda_terms=t.integer("lambda_terms", None, minimum=1),
            articulated=arts,
            source=str(path),
        )
        t.check_unknown(["description"])
        try:
            return cls(**kwargs)
        except ModelError as exc:
            raise ModelError(f"{path}: [engine] {exc}") from None


def _readonly(arr) -> np.ndarray:
    arr = np.array(arr, dtype=float)
    arr.flags.writeable = False
    return arr
