"""Shaft-line elements assembled into a :class:`~predict.torsion.system.TorsionalSystem`.

A :class:`ShaftLine` is built by ``add_*`` calls naming the nodes: masses (disks, crank throws,
flywheel, propeller), shafts (stiffness given, or from length/diameter/bore/shear modulus,
stepped shafts by equivalent length), flexible couplings, gear meshes (the driven side turns at
``ratio`` times the driver; its inertias and stiffnesses are referred to crankshaft speed by
ratio²), grounded springs and dampers (:mod:`predict.torsion.dampers`). Every value is given in
SI at the part's own speed; the builder refers it.

References
----------
.. [1] W. Ker Wilson, *Practical Solution of Torsional Vibration Problems*, vol. 1, 3rd ed.,
   1956, ch. 2-5 (equivalent lengths, crank throws, geared systems).
.. [2] 交通大学内燃机教研组, 内燃机动力学、构造与计算 (上册), 1958, 第二篇 第二章 §1 代替系统.
.. [3] 应用力学 下册 引擎动力学, §22 Equivalent shaft and equivalent inertia, §23 联动之轴
   (geared shafts).
"""

from __future__ import annotations

import numpy as np

from crankbench.predict._deprecate import renamed

from .._validate import check_nonnegative, check_positive
from ..errors import ModelError
from .system import TorsionalSystem

__all__ = ["ShaftLine", "shaft_stiffness", "stepped_shaft", "crank_throw_inertia",
           "STEEL_SHEAR_MODULUS"]

#: shear modulus of steel, Pa
STEEL_SHEAR_MODULUS = 80.0e9


def shaft_stiffness(length, diameter, *, bore=0.0, shear_modulus=STEEL_SHEAR_MODULUS) -> float:
    """Torsional stiffness of a uniform round shaft, k = G·π(D⁴ − d⁴)/(32 L), N·m/rad.

    Parameters
    ----------
    length : float
        m.
    diameter : float
        Outer diameter D, m.
    bore : float
        Inner diameter d, m (0 = solid).
    shear_modulus : float
        G, Pa.

    Examples
    --------
    >>> print(round(shaft_stiffness(1.0, 0.1), 1))
    785398.2
    """
    length = check_positive(length, "length", error=ModelError)
    diameter = check_positive(diameter, "diameter", error=ModelError)
    bore = check_nonnegative(bore, "bore", error=ModelError)
    if bore >= diameter:
        raise ModelError(f"bore={bore!r} must be smaller than diameter={diameter!r}")
    g = check_positive(shear_modulus, "shear_modulus", error=ModelError)
    return g * np.pi * (diameter ** 4 - bore ** 4) / (32.0 * length)


def stepped_shaft(segments, *, reference_diameter=None, shear_modulus=STEEL_SHEAR_MODULUS):
    """Equivalent length and stiffness of a stepped shaft (segments in series).

    ``L_e = Σ L_i · D_ref⁴ / (D_i⁴ − d_i⁴)`` and ``k = G π D_ref⁴ / (32 L_e)`` (= 1/Σ 1/k_i).

    Parameters
    ----------
    segments : sequence of (length, diameter[, bore])
        m.
    reference_diameter : float, optional
        D_ref, m (default: the smallest outer diameter).
    shear_modulus : float
        Pa.

    Returns
    -------
    dict
        ``equivalent_length`` (m), ``reference_diameter`` (m), ``stiffness`` (N·m/rad),
        ``min_diameter`` and its ``bore`` (the section used for stress).

    Examples
    --------
    >>> r = stepped_shaft([(0.5, 0.1), (0.5, 0.2)])
    >>> print(round(r["equivalent_length"], 4))
    0.5312
    """
    segs = [tuple(s) + (0.0,) * (3 - len(s)) for s in segments]
    if not segs:
        raise ModelError("segments must list at least one (length, diameter[, bore])")
    ks = [shaft_stiffness(L, D, bore=d, shear_modulus=shear_modulus) for L, D, d in segs]
    i_min = int(np.argmin([s[1] for s in segs]))
    dref = segs[i_min][1] if reference_diameter is None else check_positive(
        reference_diameter, "reference_diameter", error=ModelError)
    le = sum(L * dref ** 4 / (D ** 4 - d ** 4) for L, D, d in segs)
    return dict(equivalent_length=le, reference_diameter=dref,
                stiffness=1.0 / sum(1.0 / k for k in ks),
                min_diameter=segs[i_min][1], bore=segs[i_min][2])


def crank_throw_inertia(engine, cylinder: int, throw_inertia: float = 0.0, *,
                        exact: bool = True) -> float:
    """Equivalent inertia of one crank throw with its crank-train masses, kg·m².

    ``J = J_throw + m_rot r² + m_rec ⟨x'(ψ)²⟩ + ΔJ ⟨φ'(ψ)²⟩``: the rotating mass at the crank
    radius plus the mean over a revolution of the kinetic-energy factors of the reciprocating
    mass (x the piston position, ' = d/dψ) and of the rod's residual inertia ΔJ
    (``Engine.rod_inertia_correction``, 0 for the two-point rod; φ the rod angle) — the
    inertia that carries the same mean kinetic energy at constant speed.

    The mean is taken exactly (rectangle rule over 720 equal steps of the exact, smooth and
    periodic motion: exponentially convergent, round-off here). ``exact=False`` gives the
    classical truncated form ``m_rec r² (1/2 + λ²/8)`` (Ker Wilson): its series continues
    ``+ λ⁴/16 + 5λ⁶/128 + …``, so it is low by ≈ λ⁴/8 relative (5.0·10⁻⁴ at λ = 1/4,
    3.4·10⁻³ at λ = 0.4: ``textbook`` bench rows); it ignores ΔJ and the pin offset.

    Parameters
    ----------
    engine : predict.engine.Engine
    cylinder : int
        Cylinder number, 1-based.
    throw_inertia : float
        Inertia of the throw itself (webs, pin, journal share), kg·m².
    exact : bool
        Exact mean (default) or the textbook truncated factor (plain rods only).

    References
    ----------
    Ker Wilson vol. 1 (1956) ch. 3; 内燃机动力学 (1958) 第二篇 第二章 §1 (往复质量的当量转动惯量).

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.1, rod_length=0.4,
    ...            reciprocating_mass=10.0, rotating_mass=5.0)
    >>> print(round(crank_throw_inertia(e, 1, 1.0), 6))   # ⟨x'²⟩ = r²(1/2 + λ²/8 + λ⁴/16 …)
    1.100807
    >>> print(round(crank_throw_inertia(e, 1, 1.0, exact=False), 6))
    1.100781
    """
    z = engine.n_cylinders
    if not 1 <= int(cylinder) <= z:
        raise ModelError(f"cylinder={cylinder!r} must be in 1..{z}")
    c = int(cylinder) - 1
    r = engine.crank_radius
    j0 = check_nonnegative(throw_inertia, "throw_inertia", error=ModelError)
    special = engine.articulated[c] is not None or getattr(engine, "rotary", False)
    if not exact:
        if special:
            raise ModelError("exact=False (the truncated 1/2 + λ²/8 factor) is for plain rods "
                             "only; articulated rods and rotary engines need exact=True")
        lam = r / engine.rod_length
        return (j0 + float(engine.rotating_mass[c]) * r * r
                + float(engine.reciprocating_mass[c]) * r * r * (0.5 + lam * lam / 8.0))
    th = np.arange(720) * 2 * np.pi / 720
    x, dx, _ = engine.piston_motion(th)
    # articulated link rod: x'²; rotary engine: the piston also circles the axis (x'² + x²)
    factor = np.mean(dx[c] ** 2 + (x[c] ** 2 if getattr(engine, "rotary", False) else 0.0))
    out = j0 + float(engine.rotating_mass[c]) * r * r + float(
        engine.reciprocating_mass[c]) * float(factor)
    corr = float(engine.rod_inertia_correction[c])
    if corr != 0.0:
        d1, _ = engine.rod_motion(th)
        out += corr * float(np.mean(d1[c] ** 2))
    return out


class ShaftLine:
    """Builder of a torsional system from named elements (values at each part's own speed).

    Parameters
    ----------
    name : str
    engine : predict.engine.Engine, optional
        Needed for crank throws with crank-train masses and for the excitation.
    shear_modulus : float
        Default G for shafts, Pa.

    Examples
    --------
    >>> line = ShaftLine("demo")
    >>> line.add_mass("engine", 2.0)
    >>> line.add_mass("gear", 0.5, ratio=3.0)
    >>> line.add_gear("engine", "gear", ratio=3.0)
    >>> line.add_mass("load", 0.1, ratio=3.0)
    >>> line.add_shaft("gear", "load", stiffness=1e4)
    >>> s = line.build()
    >>> print(s.inertias.tolist(), s.stiffnesses.tolist())
    [6.5, 0.9] [90000.0]
    """

    def __init__(self, name: str = "", *, engine=None, shear_modulus=STEEL_SHEAR_MODULUS):
        self.name = name
        self.engine = engine
        self.shear_modulus = check_positive(shear_modulus, "shear_modulus", error=ModelError)
        self._nodes: list[dict] = []
        self._alias: dict[str, tuple[int, float]] = {}
        self._edges: list[dict] = []
        self._cylinders: dict[int, int] = {}
        self._friction: list[dict] = []

    # ---------------------------------------------------------------- nodes -------------
    def _port(self, name: str) -> tuple[int, float]:
        if name not in self._alias:
            from .._validate import suggest

            raise ModelError(f"{self.name}: unknown node {name!r}"
                             f"{suggest(name, self._alias)}; defined: {', '.join(self._alias)}")
        return self._alias[name]

    def add_mass(self, name: str, inertia: float, *, ratio: float = 1.0, damping: float = 0.0,
                 cylinder: int | None = None, throw_inertia: float | None = None,
                 eigen: bool = True) -> None:
        """Add a lumped inertia (disk, flywheel, propeller, crank throw).

        Parameters
        ----------
        name : str
        inertia : float
            kg·m² at the part's own speed (for a crank throw with ``throw_inertia`` given this
            may be None: the crank-train masses are added to ``throw_inertia``).
        ratio : float
            Speed of the part relative to the crankshaft.
        damping : float
            Absolute viscous damping to ground, N·m·s/rad (propeller, engine).
        cylinder : int or sequence of int, optional
            1-based cylinder(s) whose tangential torque acts on this node (several for a V
            throw or a radial row on one crank pin).
        throw_inertia : float, optional
            With ``cylinder``: the throw's own inertia; the node inertia is
            :func:`crank_throw_inertia`.
        eigen : bool
            Include in the undamped eigen-analysis.
        """
        if name in self._alias:
            raise ModelError(f"{self.name}: node {name!r} defined twice")
        ratio = float(ratio)
        if ratio == 0 or not np.isfinite(ratio):
            raise ModelError(f"{name}: ratio={ratio!r} must be a finite non-zero speed ratio")
        cylinders = [] if cylinder is None else (
            [int(c) for c in cylinder] if np.ndim(cylinder) else [int(cylinder)])
        if throw_inertia is not None:
            if not cylinders or self.engine is None:
                raise ModelError(f"{name}: throw_inertia needs cylinder= and an engine")
            # one throw carrying several cylinders (V, radial row): its own inertia once, the
            # crank-train masses of every cylinder on it
            inertia = throw_inertia + sum(
                crank_throw_inertia(self.engine, c, 0.0) for c in cylinders)
        inertia = check_positive(inertia, f"{name}: inertia", error=ModelError)
        damping = check_nonnegative(damping, f"{name}: damping", error=ModelError)
        self._alias[name] = (len(self._nodes), ratio)
        self._nodes.append(dict(name=name, inertia=inertia * ratio ** 2, ratio=ratio,
                                damping=damping * ratio ** 2, eigen=bool(eigen)))
        for c in cylinders:
            if c in self._cylinders:
                raise ModelError(f"{name}: cylinder {c} already sits on another node")
            self._cylinders[c] = len(self._nodes) - 1

    def add_damping(self, name: str, damping: float) -> None:
        """Add absolute viscous damping (N·m·s/rad, at the node's speed) to a node."""
        idx, ratio = self._port(name)
        self._nodes[idx]["damping"] += check_nonnegative(damping, "damping",
                                                         error=ModelError) * ratio ** 2

    # ---------------------------------------------------------------- springs -----------
    def _spring(self, a, b, *, stiffness, damping=0.0, loss_factor=0.0, speed2=0.0,
                diameter=np.nan, bore=np.nan, name=None, ground=False):
        ib, rb = self._port(b)
        if ground:
            ia, ra = -1, rb
        else:
            ia, ra = self._port(a)
            if not np.isclose(ra, rb, rtol=1e-12):
                raise ModelError(f"{self.name}: {a!r} turns at ratio {ra:g} and {b!r} at "
                                 f"{rb:g}; join different speeds with add_gear")
            if ia == ib:
                raise ModelError(f"{self.name}: {a!r} and {b!r} are the same node")
        self._edges.append(dict(a=ia, b=ib, k=stiffness * rb ** 2, c=damping * rb ** 2,
                                eta=loss_factor, k2=speed2 * rb ** 2, ratio=rb,
                                d_out=diameter, d_in=bore,
                                name=name or f"{a if not ground else 'ground'}-{b}"))

    def add_shaft(self, a: str, b: str, *, stiffness=None, length=None, diameter=None,
                  bore=0.0, segments=None, shear_modulus=None, damping=0.0, loss_factor=0.0,
                  name=None, throw=None, throw_method="wilson", density=None, inertia=None,
                  elements=None) -> None:
        """Add a shaft section between nodes ``a`` and ``b`` (same speed).

        Give ``stiffness`` (N·m/rad) — optionally with ``diameter``/``bore`` for stress — or
        ``length``/``diameter``/``bore`` (m), or ``segments`` [(L, D, d), ...] for a stepped
        shaft (stress at its smallest section), or ``throw`` (a
        :class:`~predict.torsion.throws.CrankThrow`, stiffness by ``throw_method`` "wilson",
        "carter" or "fe", see :func:`~predict.torsion.throws.throw_stiffness`; stress at the
        smaller of journal and pin). ``damping`` is relative viscous
        (N·m·s/rad), ``loss_factor`` hysteretic η.

        Distributed inertia: with ``density`` (kg/m³, needs ``length``/``diameter`` or
        ``segments``) or ``inertia`` (the shaft's own polar inertia, kg·m²) the shaft is split
        into ``elements`` equal-stiffness pieces (default: enough for its first own free-free
        mode to be within 0.1 %, see :func:`predict.torsion.throws.lumping_error`), half an
        element's inertia at each end, internal nodes named ``"<name> [i]"``.
        """
        g = self.shear_modulus if shear_modulus is None else shear_modulus
        own_inertia = None
        if throw is not None:
            from .throws import throw_stiffness

            if stiffness is not None or length is not None or segments is not None:
                raise ModelError(f"shaft {a}-{b}: give throw or stiffness/length/segments, "
                                 "not both")
            stiffness = throw_stiffness(throw, method=throw_method, shear_modulus=g).stiffness
            small = min((throw.journal_diameter, throw.journal_bore),
                        (throw.pin_diameter, throw.pin_bore))
            diameter, bore = small
        if density is not None:
            rho = check_positive(density, f"shaft {a}-{b}: density", error=ModelError)
            if segments is not None:
                own_inertia = sum(rho * np.pi * (s[1] ** 4 - (s[2] if len(s) > 2 else 0.0) ** 4)
                                  / 32.0 * s[0] for s in segments)
            elif length is not None and diameter is not None:
                own_inertia = rho * np.pi * (diameter ** 4 - bore ** 4) / 32.0 * length
            else:
                raise ModelError(f"shaft {a}-{b}: density needs length+diameter or segments")
        if inertia is not None:
            if own_inertia is not None:
                raise ModelError(f"shaft {a}-{b}: give density or inertia, not both")
            own_inertia = check_positive(inertia, f"shaft {a}-{b}: inertia", error=ModelError)
        if segments is not None:
            r = stepped_shaft(segments, shear_modulus=g)
            k_geo, d_out, d_in = r["stiffness"], r["min_diameter"], r["bore"]
        elif length is not None:
            if diameter is None:
                raise ModelError(f"shaft {a}-{b}: length needs diameter")
            k_geo = shaft_stiffness(length, diameter, bore=bore, shear_modulus=g)
            d_out, d_in = diameter, bore
        else:
            k_geo = None
            d_out = np.nan if diameter is None else diameter
            d_in = bore if diameter is not None else np.nan
        if stiffness is None and k_geo is None:
            raise ModelError(f"shaft {a}-{b}: give stiffness, length+diameter or segments")
        k = k_geo if stiffness is None else check_positive(stiffness, f"shaft {a}-{b}: "
                                                           "stiffness", error=ModelError)
        if own_inertia is None:
            if elements is not None:
                raise ModelError(f"shaft {a}-{b}: elements needs density or inertia")
            self._spring(a, b, stiffness=k, damping=damping, loss_factor=loss_factor,
                         diameter=d_out, bore=d_in, name=name)
            return
        self._distributed(a, b, k, own_inertia, elements, damping=damping,
                          loss_factor=loss_factor, d_out=d_out, d_in=d_in, name=name)

    def _distributed(self, a, b, k, inertia, elements, *, damping, loss_factor, d_out, d_in,
                     name):
        """Split a shaft of stiffness k and own inertia into equal lumped elements."""
        from .._validate import check_int

        label = name or f"{a}-{b}"
        if elements is None:
            # first own free-free mode ω = π√(k_total/J_total)·... of the uniform shaft:
            # x = π/(2N) for it; 1 − sin x/x <= 1e-3 needs N >= 21
            elements = 21
        n = check_int(elements, f"shaft {label}: elements", minimum=1, error=ModelError)
        ia, ra = self._port(a)
        ib, rb = self._port(b)
        if not np.isclose(ra, rb, rtol=1e-12):
            raise ModelError(f"{self.name}: {a!r} turns at ratio {ra:g} and {b!r} at {rb:g}; "
                             "join different speeds with add_gear")
        piece = inertia / n
        self._nodes[ia]["inertia"] += 0.5 * piece * ra ** 2
        self._nodes[ib]["inertia"] += 0.5 * piece * rb ** 2
        names = [a] + [f"{label} [{i}]" for i in range(1, n)] + [b]
        for nm in names[1:-1]:
            self.add_mass(nm, piece, ratio=ra)
        for i, (u, v) in enumerate(zip(names[:-1], names[1:])):
            self._spring(u, v, stiffness=k * n, damping=damping * n, loss_factor=loss_factor,
                         diameter=d_out, bore=d_in,
                         name=label if n == 1 else f"{label} ({i + 1}/{n})")

    def add_coupling(self, a: str, b: str, *, stiffness: float, damping: float = 0.0,
                     loss_factor: float = 0.0, name=None) -> None:
        """Flexible coupling: torsional stiffness (N·m/rad), relative viscous damping
        (N·m·s/rad) and/or hysteretic loss factor (rubber: η = ψ/2π with ψ the relative
        damping of the coupling's data sheet)."""
        k = check_positive(stiffness, f"coupling {a}-{b}: stiffness", error=ModelError)
        self._spring(a, b, stiffness=k, damping=damping, loss_factor=loss_factor,
                     name=name or f"coupling {a}-{b}")

    def add_ground(self, node: str, *, stiffness: float, damping: float = 0.0,
                   name=None) -> None:
        """Grounded spring (N·m/rad) with optional viscous damping, tying ``node`` to ground."""
        k = check_positive(stiffness, f"ground {node}: stiffness", error=ModelError)
        self._spring(None, node, stiffness=k, damping=damping, ground=True,
                     name=name or f"ground-{node}")

    def add_gear(self, driver: str, driven: str, *, ratio: float, mesh_stiffness=None,
                 name=None) -> None:
        """Gear mesh: ``driven`` turns at ``ratio`` × ``driver`` speed (sign ignored).

        With ``mesh_stiffness`` None the mesh is rigid: the driven gear's (referred) inertia
        joins the driver node. Otherwise ``mesh_stiffness`` is the torsional mesh stiffness at
        the *driven* gear's speed, N·m/rad (k_mesh·r_b², r_b the driven base radius).
        """
        ia, ra = self._port(driver)
        ib, rb = self._port(driven)
        ratio = abs(float(ratio))
        if not np.isclose(rb, ra * ratio, rtol=1e-9):
            raise ModelError(f"gear {driver}->{driven}: driven node ratio {rb:g} must equal "
                             f"driver ratio {ra:g} × gear ratio {ratio:g} = {ra * ratio:g}")
        if mesh_stiffness is None:
            node = self._nodes[ib]
            self._nodes[ia]["inertia"] += node["inertia"]
            self._nodes[ia]["damping"] += node["damping"]
            node["merged_into"] = ia
            for name_, (idx, r) in list(self._alias.items()):
                if idx == ib:
                    self._alias[name_] = (ia, r)
            for c, idx in self._cylinders.items():
                if idx == ib:
                    self._cylinders[c] = ia
            for e in self._edges:
                e["a"] = ia if e["a"] == ib else e["a"]
                e["b"] = ia if e["b"] == ib else e["b"]
        else:
            k = check_positive(mesh_stiffness, f"gear {driver}->{driven}: mesh_stiffness",
                               error=ModelError)
            ib_, _ = self._port(driven)
            self._edges.append(dict(a=ia, b=ib_, k=k * rb ** 2, c=0.0, eta=0.0, k2=0.0,
                                    ratio=rb, d_out=np.nan, d_in=np.nan,
                                    name=name or f"mesh {driver}-{driven}"))

    @renamed(speed2="stiffness_omega2")
    def add_spring(self, a: str, b: str, *, stiffness: float = 0.0, damping: float = 0.0,
                   loss_factor: float = 0.0, stiffness_omega2: float = 0.0, name=None) -> None:
        """Generic link (used by dampers): stiffness N·m/rad (0 allowed), relative viscous
        damping N·m·s/rad, hysteretic η, speed-proportional stiffness N·m·s²/rad."""
        k = check_nonnegative(stiffness, "stiffness", error=ModelError)
        self._spring(a, b, stiffness=k, damping=damping, loss_factor=loss_factor,
                     speed2=stiffness_omega2, name=name)

    # ---------------------------------------------------------------- build -------------
    def _check_connected(self, nodes, edges) -> None:
        """Refuse a shaft line in several pieces (ground not counted as a joint): each piece
        would be a separate machine with its own rigid-body mode, almost always a missing
        shaft or coupling in the model."""
        parent = list(range(len(nodes)))

        def root(i):
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        for a, b in edges:
            if a >= 0:
                parent[root(a)] = root(b)
        pieces: dict[int, list[str]] = {}
        for i, node in enumerate(nodes):
            pieces.setdefault(root(i), []).append(node["name"])
        if len(pieces) > 1:
            shown = " and ".join(
                "{" + (repr(p[0]) if len(p) == 1 else f"{p[0]!r} … {p[-1]!r}") + "}"
                for p in pieces.values())
            raise ModelError(f"{self.name}: the shaft line is not connected: it falls into "
                             f"{len(pieces)} pieces, {shown}; join them with a shaft, coupling "
                             "or gear")

    def build(self, *, limits=None) -> TorsionalSystem:
        """Assemble the :class:`TorsionalSystem` (merged gear nodes removed)."""
        keep = [i for i, n in enumerate(self._nodes) if "merged_into" not in n]
        if not keep:
            raise ModelError(f"{self.name}: the shaft line has no masses")
        new = -np.ones(len(self._nodes), int)
        new[keep] = np.arange(len(keep))
        nodes = [self._nodes[i] for i in keep]
        edges = self._edges
        e = np.array([[(-1 if d["a"] < 0 else new[d["a"]]), new[d["b"]]] for d in edges],
                     int).reshape(-1, 2)
        self._check_connected(nodes, e)
        cylinders = [new[self._cylinders[c]] for c in sorted(self._cylinders)]
        firing = None
        cycle = 4
        if self.engine is not None:
            cycle = self.engine.cycle
            if cylinders:
                if sorted(self._cylinders) != list(range(1, self.engine.n_cylinders + 1)):
                    raise ModelError(f"{self.name}: cylinders {sorted(self._cylinders)} on the "
                                     f"shaft line, engine has 1..{self.engine.n_cylinders}")
                firing = self.engine.firing_angles_deg()
        from .friction import FrictionDamper

        friction = []
        for fr in self._friction:
            idx, ratio = self._port(fr["node"])
            if not np.isclose(ratio, 1.0):
                raise ModelError(f"{self.name}: friction damper {fr['name']!r} on "
                                 f"{fr['node']!r} (speed ratio {ratio:g}): the non-linear "
                                 "friction ring must sit on a node at crankshaft speed")
            friction.append(FrictionDamper(int(new[idx]), fr["ring_inertia"],
                                           fr["slip_torque"], fr["name"]))
        return TorsionalSystem(
            [n["inertia"] for n in nodes], e, [d["k"] for d in edges],
            node_names=[n["name"] for n in nodes], edge_names=[d["name"] for d in edges],
            node_damping=[n["damping"] for n in nodes],
            edge_damping=[d["c"] for d in edges], edge_loss_factor=[d["eta"] for d in edges],
            edge_stiffness_omega2=[d["k2"] for d in edges],
            node_ratio=[n["ratio"] for n in nodes], edge_ratio=[d["ratio"] for d in edges],
            edge_outer_diameter=[d["d_out"] for d in edges],
            edge_inner_diameter=[d["d_in"] for d in edges],
            eigen_nodes=[n["eigen"] for n in nodes], cylinder_nodes=cylinders,
            firing_angles_deg=firing, cycle=cycle, engine=self.engine, limits=limits,
            name=self.name, friction_dampers=friction)
