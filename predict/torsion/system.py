"""The assembled torsional system: lumped inertias joined by springs (a chain or a tree).

A :class:`TorsionalSystem` holds every quantity *referred to the engine crankshaft speed*
(a part turning at ``ratio`` times crankshaft speed contributes ``J·ratio²`` and ``k·ratio²``;
its real angle is ``ratio·θ`` and its real torque ``T/ratio``), so the equations of motion are

``J θ̈ + C θ̇ + K θ = T(t)``,  J diagonal, K and C weighted graph Laplacians plus ground terms.

References
----------
.. [1] W. Ker Wilson, *Practical Solution of Torsional Vibration Problems*, vol. 1, 3rd ed.,
   Chapman & Hall, 1956, ch. 1-3 (equivalent systems, geared systems referred by ratio²).
.. [2] 交通大学内燃机教研组, 内燃机动力学、构造与计算 (上册), 机械工业出版社, 1958,
   第二篇 第二章 (代替系统, 多质量振动系统) and 第四章 §1 (临界转速).
"""

from __future__ import annotations

import functools
import numpy as np

from crankbench.predict._deprecate import renamed

from .._validate import check_finite_array
from ..errors import ModelError
from . import eigen, subset
from .layout import classify
from .modes import Modes

__all__ = ["TorsionalSystem", "Modes", "chain"]

TWO_PI = 2.0 * np.pi
_UNIT_SCALE = {"hz": 1.0 / TWO_PI, "rad/s": 1.0, "cpm": 60.0 / TWO_PI}


@functools.lru_cache(maxsize=64)
def _constant(size: int, value) -> np.ndarray:
    """A read-only array of ``size`` copies of ``value`` (float, or bool for True/False),
    shared between systems: the default per-node and per-spring data."""
    arr = np.full(size, value, bool if isinstance(value, bool) else float)
    arr.setflags(write=False)
    return arr


def _as_index_array(values, name, n, *, allow_ground=False):
    arr = np.asarray(values)
    if arr.size and not np.issubdtype(arr.dtype, np.integer):
        raise ModelError(f"{name} must hold integer node indices, got {arr.dtype}")
    low = -1 if allow_ground else 0
    if arr.size and (arr.min() < low or arr.max() >= n):
        raise ModelError(f"{name} holds node index out of range [{low}, {n - 1}]: {arr.tolist()}")
    return arr.astype(int)


class TorsionalSystem:
    """Lumped torsional system (chain or tree), all values referred to crankshaft speed.

    Parameters
    ----------
    inertias : array_like (n,)
        Mass moments of inertia, kg·m² (> 0).
    edges : array_like (m, 2) of int
        Spring ends ``(a, b)``; ``a = -1`` ties node ``b`` to ground.
    stiffnesses : array_like (m,)
        Torsional stiffness of each spring, N·m/rad (>= 0; 0 = damping-only link).
    node_names, edge_names : sequence of str, optional
    node_damping : array_like (n,), optional
        Absolute viscous damping of each node to ground, N·m·s/rad.
    edge_damping : array_like (m,), optional
        Relative viscous damping across each spring, N·m·s/rad.
    edge_loss_factor : array_like (m,), optional
        Hysteretic loss factor η of each spring (complex stiffness ``k(1 + iη)``).
    edge_stiffness_omega2 : array_like (m,), optional
        Speed-proportional stiffness coefficient, N·m·s²/rad (centrifugal pendulums):
        the spring stiffness is ``stiffness + coeff·Ω²`` at crankshaft speed Ω.
    node_ratio, edge_ratio : array_like, optional
        Speed of each node/spring relative to the crankshaft (1 by default); real angle =
        ratio·θ, real torque = T/ratio.
    edge_outer_diameter, edge_inner_diameter : array_like (m,), optional
        Shaft section diameters, m (NaN where unknown), for shear stress.
    eigen_nodes : array_like of bool (n,), optional
        Nodes included in the undamped eigen-analysis (default all); rings of viscous dampers
        and pendulum masses, attached without a static spring, are left out.
    cylinder_nodes : sequence of int, optional
        Node carrying each engine cylinder, in cylinder order 1..z.
    firing_angles_deg : array_like, optional
        Firing angle of each cylinder after cylinder 1, crank degrees.
    cycle : int
        Strokes per cycle (4 or 2); sets the order grid (0.5 steps for 4-stroke).
    engine : object, optional
        The :class:`predict.engine.Engine` the system belongs to.
    limits : object, optional
        Stress limit curves (:class:`predict.torsion.stress.StressLimits`).
    name : str
    operating : dict, optional
        Operating data from the model file: ``speed_range_rpm`` (low, high), ``imep`` (Pa).
    friction_dampers : sequence of FrictionDamper, optional
        Lanchester friction rings kept as non-linear elements
        (:class:`predict.torsion.friction.FrictionDamper`): not in the linear matrices nor
        the eigen-analysis (a slipping ring carries no stiffness); the forced response then
        goes through :func:`predict.torsion.friction_line.friction_forced_response`
        (harmonic balance of the exact stick-slip torque, each order alone).

    Notes
    -----
    Equations of motion for time integration: ``J θ̈ + C θ̇ + K(Ω) θ = T(t)`` with
    ``inertia_matrix()``, ``damping_matrix(omega)`` (hysteretic damping needs the vibration
    frequency ω; ``omega=None`` leaves it out) and ``stiffness_matrix(speed)`` (Ω for
    pendulums). Angles and torques are referred to crankshaft speed: multiply node angles by
    ``node_ratio`` and divide spring torques by ``edge_ratio`` for real values; shear stress per
    real torque is ``predict.torsion.forced.stress_factor(system)`` from ``section_diameters``.
    Undamped eigen-solvers: bidiagonal dqds for chains (O(n²), ≲10⁻² s for 1000 masses),
    tree bisection for branched systems (O(n) Python-level sweeps × ~35 iterations, about
    1 s per 1000 masses), dense ``eigh`` for systems with closed spring loops.

    Examples
    --------
    >>> from crankbench.predict.torsion import TorsionalSystem
    >>> s = TorsionalSystem([1.0, 2.0], [(0, 1)], [1e4])
    >>> print(round(float(s.natural_frequencies()[1]), 4))
    19.4924
    """

    @renamed(edge_stiffness_speed2="edge_stiffness_omega2")
    def __init__(self, inertias, edges, stiffnesses, *, node_names=None, edge_names=None,
                 node_damping=None, edge_damping=None, edge_loss_factor=None,
                 edge_stiffness_omega2=None, node_ratio=None, edge_ratio=None,
                 edge_outer_diameter=None, edge_inner_diameter=None, eigen_nodes=None,
                 cylinder_nodes=(), firing_angles_deg=None, cycle=4, engine=None, limits=None,
                 name="", operating=None, friction_dampers=()):
        # own copies: the system is immutable and must not freeze or alias the caller's arrays
        j = np.array(check_finite_array(inertias, "inertias", ndim=1, min_length=1,
                                        error=ModelError))
        if np.any(j <= 0):
            i = int(np.flatnonzero(j <= 0)[0])
            raise ModelError(f"inertias[{i}]={float(j[i])!r} must be > 0 (kg·m²)")
        n = j.size
        e = np.asarray(edges).reshape(-1, 2) if np.size(edges) else np.zeros((0, 2), int)
        e = _as_index_array(e, "edges", n, allow_ground=True)
        if np.any(e[:, 1] < 0):
            raise ModelError("edges: ground (-1) may appear only as the first end of a spring")
        if np.any(e[:, 0] == e[:, 1]):
            raise ModelError("edges: a spring must join two different nodes")
        m = e.shape[0]
        k = np.array(check_finite_array(stiffnesses, "stiffnesses", ndim=1, error=ModelError))
        if k.size != m:
            raise ModelError(f"stiffnesses has {k.size} values, expected one per edge ({m})")
        if np.any(k < 0):
            i = int(np.flatnonzero(k < 0)[0])
            raise ModelError(f"stiffnesses[{i}]={float(k[i])!r} must be >= 0 (N·m/rad)")

        def per(values, name, size, default, low=0.0, allow_nan=False):
            if values is None:
                return _constant(size, default)
            try:
                arr = np.array(np.broadcast_to(np.asarray(values, float), (size,))
                               if np.ndim(values) == 0 else values, dtype=float)
            except (TypeError, ValueError):
                raise ModelError(f"{name} must be numeric") from None
            if arr.shape != (size,):
                raise ModelError(f"{name} has {arr.size} values, expected {size}")
            bad = np.isinf(arr) | (np.isnan(arr) & (not allow_nan))
            if bad.any():
                raise ModelError(f"{name} contains NaN/inf, first at index "
                                 f"{int(np.flatnonzero(bad)[0])}")
            if low is not None and np.any(arr[np.isfinite(arr)] < low):
                raise ModelError(f"{name} must be >= {low:g}, got {arr.tolist()}")
            arr.setflags(write=False)
            return arr

        self._j = j
        self._edges = e
        self._k = k
        self._node_damping = per(node_damping, "node_damping", n, 0.0)
        self._edge_damping = per(edge_damping, "edge_damping", m, 0.0)
        self._edge_eta = per(edge_loss_factor, "edge_loss_factor", m, 0.0)
        self._k_speed2 = per(edge_stiffness_omega2, "edge_stiffness_omega2", m, 0.0)
        self._node_ratio = per(node_ratio, "node_ratio", n, 1.0, low=None)
        self._edge_ratio = per(edge_ratio, "edge_ratio", m, 1.0, low=None)
        self._d_out = per(edge_outer_diameter, "edge_outer_diameter", m, np.nan,
                          allow_nan=True)
        self._d_in = per(edge_inner_diameter, "edge_inner_diameter", m, np.nan,
                         allow_nan=True)
        for arr in (self._j, self._edges, self._k):
            arr.setflags(write=False)
        # default names are generated on first access (a 10 000-mass chain built only for its
        # frequencies never needs 20 000 strings)
        self._node_names = None if node_names is None else tuple(node_names)
        self._edge_names = None if edge_names is None else tuple(edge_names)
        if ((self._node_names is not None and len(self._node_names) != n)
                or (self._edge_names is not None and len(self._edge_names) != m)):
            raise ModelError("node_names/edge_names must have one entry per node/edge")
        mask = np.ones(n, bool) if eigen_nodes is None else np.asarray(eigen_nodes, bool)
        if mask.shape != (n,):
            raise ModelError(f"eigen_nodes must have {n} booleans")
        self._eigen_nodes = mask
        self._layout_cache = None
        self.cylinder_nodes = tuple(int(c) for c in _as_index_array(
            list(cylinder_nodes), "cylinder_nodes", n))
        if firing_angles_deg is None:
            fa = None
        else:
            fa = check_finite_array(firing_angles_deg, "firing_angles_deg", ndim=1,
                                    error=ModelError)
            if fa.size != len(self.cylinder_nodes):
                raise ModelError(f"firing_angles_deg has {fa.size} values, expected one per "
                                 f"cylinder node ({len(self.cylinder_nodes)})")
        self.firing_angles_deg = fa
        if cycle not in (2, 4):
            raise ModelError(f"cycle={cycle!r} must be 2 or 4 (strokes per cycle)")
        self.cycle = int(cycle)
        self.engine = engine
        self.limits = limits
        self.name = str(name)
        self.operating = dict(operating or {})
        from .friction import FrictionDamper

        fd = tuple(friction_dampers or ())
        for d in fd:
            if not isinstance(d, FrictionDamper):
                raise ModelError(f"friction_dampers must hold FrictionDamper, got "
                                 f"{type(d).__name__}")
            if not 0 <= d.node < n:
                raise ModelError(f"friction damper {d.name!r}: node {d.node} out of range "
                                 f"0..{n - 1}")
            if not np.isclose(self._node_ratio[d.node], 1.0):
                raise ModelError(f"friction damper {d.name!r}: its node must turn at "
                                 "crankshaft speed (ratio 1)")
        self.friction_dampers = fd

    # ----------------------------------------------------------------- properties -------
    @property
    def node_names(self) -> tuple:
        """Name of each node (default ``J1``, ``J2``, ...)."""
        if self._node_names is None:
            self._node_names = tuple(f"J{i + 1}" for i in range(self.n_nodes))
        return self._node_names

    @property
    def edge_names(self) -> tuple:
        """Name of each spring (default ``<node a>-<node b>``, ``ground-<node>``)."""
        if self._edge_names is None:
            names = self.node_names
            self._edge_names = tuple(f"{'ground' if a < 0 else names[a]}-{names[b]}"
                                     for a, b in self._edges.tolist())
        return self._edge_names

    @property
    def n_nodes(self) -> int:
        """Number of lumped inertias."""
        return self._j.size

    @property
    def inertias(self) -> np.ndarray:
        """Referred inertias, kg·m² (read-only)."""
        return self._j

    @property
    def edges(self) -> np.ndarray:
        """(m, 2) spring ends, -1 = ground (read-only)."""
        return self._edges

    @property
    def stiffnesses(self) -> np.ndarray:
        """Referred static spring stiffnesses, N·m/rad (read-only)."""
        return self._k

    @property
    def node_ratio(self) -> np.ndarray:
        """Speed ratio of each node to the crankshaft."""
        return self._node_ratio

    @property
    def edge_ratio(self) -> np.ndarray:
        """Speed ratio of each spring to the crankshaft."""
        return self._edge_ratio

    @property
    def edge_damping(self) -> np.ndarray:
        """Relative viscous damping, N·m·s/rad (referred)."""
        return self._edge_damping

    @property
    def node_damping(self) -> np.ndarray:
        """Absolute viscous damping, N·m·s/rad (referred)."""
        return self._node_damping

    @property
    def edge_loss_factor(self) -> np.ndarray:
        """Hysteretic loss factors η."""
        return self._edge_eta

    @property
    def edge_stiffness_omega2(self) -> np.ndarray:
        """Speed-proportional stiffness coefficients, N·m·s²/rad."""
        return self._k_speed2

    @property
    def section_diameters(self) -> np.ndarray:
        """(m, 2) outer and inner (bore) diameter of each shaft section, m (NaN = unknown)."""
        return np.stack([self._d_out, self._d_in], axis=1)

    @property
    def eigen_nodes(self) -> np.ndarray:
        """Boolean mask of the nodes in the undamped eigen-analysis."""
        return self._eigen_nodes.copy()

    @property
    def is_free(self) -> bool:
        """True when no spring ties the system to ground (a rigid-body mode exists)."""
        return not np.any(self._edges[:, 0] < 0)

    def replace(self, **changes) -> "TorsionalSystem":
        """Copy with some constructor arguments changed (e.g. ``engine=..., limits=...``)."""
        args = dict(inertias=self._j, edges=self._edges, stiffnesses=self._k,
                    node_names=self._node_names, edge_names=self._edge_names,
                    node_damping=self._node_damping, edge_damping=self._edge_damping,
                    edge_loss_factor=self._edge_eta, edge_stiffness_omega2=self._k_speed2,
                    node_ratio=self._node_ratio, edge_ratio=self._edge_ratio,
                    edge_outer_diameter=self._d_out, edge_inner_diameter=self._d_in,
                    eigen_nodes=self._eigen_nodes, cylinder_nodes=self.cylinder_nodes,
                    firing_angles_deg=self.firing_angles_deg, cycle=self.cycle,
                    engine=self.engine, limits=self.limits, name=self.name,
                    operating=self.operating, friction_dampers=self.friction_dampers)
        unknown = set(changes) - set(args)
        if unknown:
            raise ModelError(f"replace(): unknown argument(s) {sorted(unknown)}")
        args.update(changes)
        return TorsionalSystem(**args)

    @classmethod
    def _chain_of(cls, j: np.ndarray, k: np.ndarray, node_names=None) -> "TorsionalSystem":
        """A chain from float64 arrays :func:`chain` has checked and copied (J > 0, k > 0,
        ``k.size`` = n−1 or n): what ``__init__`` would build, without re-validating."""
        self = cls.__new__(cls)
        n, m = j.size, k.size
        e = np.empty((m, 2), int)
        e[:, 0] = np.arange(n - 1 - m, n - 1)
        e[:, 1] = e[:, 0] + 1
        for arr in (j, e, k):
            arr.setflags(write=False)
        self._j, self._edges, self._k = j, e, k
        self._node_damping = _constant(n, 0.0)
        self._node_ratio = _constant(n, 1.0)
        self._edge_damping = self._edge_eta = self._k_speed2 = _constant(m, 0.0)
        self._edge_ratio = _constant(m, 1.0)
        self._d_out = self._d_in = _constant(m, np.nan)
        self._node_names = None if node_names is None else tuple(node_names)
        if self._node_names is not None and len(self._node_names) != n:
            raise ModelError("node_names/edge_names must have one entry per node/edge")
        self._edge_names = None
        self._eigen_nodes = _constant(n, True)
        self._layout_cache = None
        self.cylinder_nodes = ()
        self.firing_angles_deg = None
        self.cycle = 4
        self.engine = self.limits = None
        self.name = ""
        self.operating = {}
        self.friction_dampers = ()
        return self

    def __repr__(self) -> str:
        kind = "free" if self.is_free else "grounded"
        return (f"TorsionalSystem({self.name!r}, {self.n_nodes} nodes, {len(self._k)} springs, "
                f"{kind}, {len(self.cylinder_nodes)} cylinders)")

    # ----------------------------------------------------------------- matrices ---------
    def _laplacian(self, weights) -> np.ndarray:
        n = self.n_nodes
        out = np.zeros((n, n), dtype=np.result_type(weights, float))
        a, b = self._edges[:, 0], self._edges[:, 1]
        np.add.at(out, (b, b), weights)
        inner = a >= 0
        np.add.at(out, (a[inner], a[inner]), weights[inner])
        np.add.at(out, (a[inner], b[inner]), -weights[inner])
        np.add.at(out, (b[inner], a[inner]), -weights[inner])
        return out

    def inertia_matrix(self) -> np.ndarray:
        """Diagonal inertia matrix J, kg·m² (dense (n, n) ndarray)."""
        return np.diag(self._j)

    @renamed(speed="omega")
    def stiffness_matrix(self, omega: float | None = None) -> np.ndarray:
        """Stiffness matrix K, N·m/rad (dense, symmetric (n, n)).

        Parameters
        ----------
        omega : float, optional
            Crankshaft speed Ω, rad/s, for speed-dependent springs (centrifugal pendulums);
            None leaves them out.
        """
        k = self._k if omega is None else self._k + self._k_speed2 * float(omega) ** 2
        return self._laplacian(k)

    def damping_matrix(self, omega: float | None = None) -> np.ndarray:
        """Equivalent viscous damping matrix C, N·m·s/rad (dense, symmetric (n, n)).

        Absolute (node) and relative (spring) viscous dampers, plus hysteretic damping turned
        into its equivalent viscous value ``η k / ω`` at vibration frequency ``omega`` (rad/s);
        with ``omega=None`` hysteretic damping is left out.
        """
        c = self._edge_damping.copy()
        if omega is not None and np.any(self._edge_eta):
            if omega <= 0:
                raise ModelError(f"omega={omega!r} must be > 0 for hysteretic damping")
            c = c + self._edge_eta * self._k / float(omega)
        return self._laplacian(c) + np.diag(self._node_damping)

    # ----------------------------------------------------------------- eigen ------------
    def _layout(self):
        """Classify the undamped spring graph: ('chain', order, grounded) | ('tree',) |
        ('dense',). Cached: the system is immutable."""
        if self._layout_cache is None:
            self._layout_cache = classify(self._j.size, self._edges, self._k,
                                          self._eigen_nodes)
        return self._layout_cache

    def _check_dense(self, n_values: float, what: str) -> None:
        """ModelError naming the model size when ``n_values`` float64 cannot fit in memory."""
        from .._memory import check_allocation

        check_allocation(8.0 * n_values, error=ModelError,
                         what=f"{self.name or 'shaft line'}: {self.n_nodes} masses, {what}",
                         hint="lump the shaft line into fewer masses")

    def _sub_stiffness(self, info):
        nodes = info["nodes"]
        sub = np.zeros((nodes.size, nodes.size))
        a, b, k = info["a"], info["b"], info["k"]
        np.add.at(sub, (b, b), k)
        inner = a >= 0
        np.add.at(sub, (a[inner], a[inner]), k[inner])
        np.add.at(sub, (a[inner], b[inner]), -k[inner])
        np.add.at(sub, (b[inner], a[inner]), -k[inner])
        return sub

    @functools.cached_property
    def _values(self):
        """(ω rad/s, mode numbers, method, bound, layout kind, layout info): values only."""
        kind, info = self._layout()
        nodes = info["nodes"]
        jn = self._j[nodes]
        if kind != "chain":  # dense eigh: the scaled stiffness, its copy and the workspace
            self._check_dense(3.0 * nodes.size**2, "a dense eigen-solve")
        if kind == "chain":
            omega = eigen.chain_frequencies(jn[info["order"]], info["chain_k"],
                                            grounded=info["grounded"])
            method, bound = "bidiagonal dqds", 8 * nodes.size * eigen.EPS
        else:
            import scipy.linalg as sl

            rj = 1.0 / np.sqrt(jn)
            lam = sl.eigh(self._sub_stiffness(info) * rj[:, None] * rj[None, :],
                          eigvals_only=True)
            omega_d = np.sqrt(np.clip(lam, 0.0, None))
            if kind == "tree":
                omega = eigen.tree_frequencies(jn, info["a"], info["b"], info["k"],
                                               estimate=omega_d)
                method, bound = "tree bisection", 8 * nodes.size * eigen.EPS
            else:
                omega = omega_d
                method = "dense eigh"
                positive = omega[omega > 0]
                bound = float(nodes.size * eigen.EPS * (omega.max() / positive.min()) ** 2
                              if positive.size else nodes.size * eigen.EPS)
        n_zero = int(np.sum(omega == 0.0))
        numbers = np.concatenate([np.zeros(n_zero, int), np.arange(1, omega.size - n_zero + 1)])
        return omega, numbers, method, bound, kind, info

    @functools.cached_property
    def _eigen(self):
        """(ω rad/s, mass-normalised shapes (n_nodes, n_modes), numbers, method, bound)."""
        # every mode shape at every node, twice (solver output and the placed copy): refuse
        # before the frequencies are even computed when that cannot fit
        self._check_dense(2.0 * self.n_nodes * self._layout()[1]["nodes"].size,
                          "dense mode shapes")
        omega, numbers, method, bound, kind, info = self._values
        nodes = info["nodes"]
        jn = self._j[nodes]
        shapes = np.zeros((self.n_nodes, nodes.size))
        if kind == "chain":
            order = info["order"]
            vec = eigen.chain_modes(jn[order], info["chain_k"], grounded=info["grounded"],
                                    omega=omega)
            shapes[nodes[order]] = vec
        else:
            _, vec = eigen.dense_modes(jn, self._sub_stiffness(info))
            shapes[nodes] = vec
        return omega, shapes, numbers, method, bound

    def natural_frequencies(self, units: str = "hz", *, speed_rpm=None,
                            n_modes: int | None = None) -> np.ndarray:
        """Undamped natural frequencies, ascending; rigid-body modes exactly 0.

        Parameters
        ----------
        units : {'hz', 'rad/s', 'cpm'}
            Hz (default), rad/s or cycles per minute.
        speed_rpm : float, optional
            Crankshaft speed, rpm, for systems with speed-dependent springs (centrifugal
            pendulums): their modes are included at that speed
            (:func:`predict.torsion.campbell.system_at_speed`). Without it such springs and
            their pendulum nodes are left out (a pendulum has no stiffness at standstill).
        n_modes : int, optional
            Only the lowest ``n_modes`` (the first entries of the full list, rigid-body modes
            included). A long chain then solves for those alone by bisection, in O(n·k) time
            and O(n) memory (:mod:`predict.torsion.subset`), with the same relative accuracy;
            other systems compute every mode and return the lowest.

        Returns
        -------
        ndarray

        References
        ----------
        Demmel & Kahan (1990) and Fernando & Parlett (1994) for the bidiagonal algorithm;
        see :mod:`predict.torsion.eigen`.

        Examples
        --------
        >>> from crankbench.predict.torsion import chain
        >>> print(chain([1.0, 1.0, 1.0], [1e4, 1e4]).natural_frequencies().round(3))
        [ 0.    15.915 27.566]
        >>> low = chain([1.0] * 1000, [1e4] * 999).natural_frequencies(n_modes=2)
        >>> print(low[0], f"{low[1]:.10f}")   # exact: (100/π) sin(π/2000)
        0.0 0.0499999794
        """
        scale = _UNIT_SCALE.get(units)
        if scale is None:
            from .._validate import check_option

            check_option(units, "units", tuple(_UNIT_SCALE), error=ModelError)
        if speed_rpm is not None:
            from .campbell import system_at_speed

            return system_at_speed(self, speed_rpm).natural_frequencies(units, n_modes=n_modes)
        if n_modes is None:
            omega = self._values[0]
        else:
            omega = subset.lowest(self, self._n_modes(n_modes))[0]
        return omega * scale if scale != 1.0 else omega.copy()

    def mode_shapes(self, *, speed_rpm=None, n_modes: int | None = None) -> Modes:
        """Natural frequencies and mass-normalised mode shapes (:class:`Modes`); ``speed_rpm``
        as in :meth:`natural_frequencies`.

        Parameters
        ----------
        n_modes : int, optional
            Only the lowest ``n_modes``: a long chain computes just those shapes (memory
            linear in its length, :func:`eigen_memory_bytes`), instead of the n×n matrix of
            all of them.

        Examples
        --------
        >>> from crankbench.predict.torsion import chain
        >>> m = chain([1.0, 1.0], [1e4]).mode_shapes()
        >>> print(m.relative()[:, 1].round(3))
        [ 1. -1.]
        >>> print(chain([1.0] * 5000, [1e4] * 4999).mode_shapes(n_modes=3).shapes.shape)
        (5000, 3)
        """
        if speed_rpm is not None:
            from .campbell import system_at_speed

            return system_at_speed(self, speed_rpm).mode_shapes(n_modes=n_modes)
        if n_modes is None:
            omega, shapes, numbers, method, bound = self._eigen
        else:
            omega, numbers, method, bound, shapes = subset.lowest(
                self, self._n_modes(n_modes), shapes=True)
        return Modes(frequencies_hz=omega / TWO_PI, shapes=shapes.copy(),
                     mode_numbers=numbers.copy(), node_names=self.node_names, method=method,
                     relative_error_bound=bound)

    def eigen_memory_bytes(self, *, n_modes: int | None = None, shapes: bool = False) -> int:
        """Estimated working memory (bytes) of :meth:`natural_frequencies` (``shapes=False``)
        or :meth:`mode_shapes` with the same ``n_modes``.

        Examples
        --------
        >>> from crankbench.predict.torsion import chain
        >>> s = chain([1.0] * 20_000, [1e4] * 19_999)
        >>> print(s.eigen_memory_bytes(shapes=True) // 2**30, "GiB for all shapes;",
        ...       s.eigen_memory_bytes(n_modes=10, shapes=True) // 2**20, "MiB for 10")
        8 GiB for all shapes; 9 MiB for 10
        """
        n_modes = None if n_modes is None else self._n_modes(n_modes)
        return subset.memory_estimate(self, n_modes, shapes=shapes)

    def _n_modes(self, n_modes) -> int:
        from .._validate import check_int

        k = check_int(n_modes, "n_modes", minimum=1, error=ModelError)
        total = int(np.count_nonzero(self._eigen_nodes))
        if k > total:
            raise ModelError(f"n_modes={k} exceeds the {total} modes of the system")
        return k

    # ----------------------------------------------------------------- orders -----------
    def default_orders(self, max_order: float = 12.0) -> np.ndarray:
        """Orders 0.5, 1, 1.5, ... (4-stroke) or 1, 2, ... (2-stroke) up to ``max_order``."""
        step = 0.5 if self.cycle == 4 else 1.0
        return np.arange(step, max_order + step / 2, step)

    def major_orders(self, orders) -> np.ndarray:
        """Boolean per order: True where all cylinders' excitations are in phase (q·φ_c ≡ 0
        mod 360°), i.e. multiples of z/2 (4-stroke) or z (2-stroke) for even firing."""
        orders = np.atleast_1d(np.asarray(orders, float))
        if self.firing_angles_deg is None:
            return np.zeros(orders.shape, bool)
        ph = np.mod(np.outer(orders, self.firing_angles_deg), 360.0)
        ph = np.minimum(ph, 360.0 - ph)
        return np.all(ph < 1e-6, axis=1)

    def vector_sums(self, orders) -> np.ndarray:
        """Relative phase-vector sums ``|Σ_c a_c e^{-i q φ_c}|`` per (mode, order).

        ``a_c`` is the mode's amplitude at cylinder c, scaled so the largest |a_c| over the
        cylinders is 1 (Holzer/Wilson convention). NaN when the firing angles are unknown.

        Returns
        -------
        ndarray (n_modes, n_orders)
        """
        return self._vector_sums(np.atleast_1d(np.asarray(orders, float)), self._eigen[1])

    def _vector_sums(self, orders, shapes) -> np.ndarray:
        if self.firing_angles_deg is None or not self.cylinder_nodes:
            return np.full((shapes.shape[1], orders.size), np.nan)
        a = shapes[list(self.cylinder_nodes), :]
        peak = np.max(np.abs(a), axis=0)
        a = a / np.where(peak == 0, 1.0, peak)
        phase = np.exp(-1j * np.deg2rad(np.outer(self.firing_angles_deg, orders)))
        return np.abs(a.T @ phase)

    def critical_speeds(self, orders=None, speed_range_rpm=None):
        """Critical speeds: every (elastic mode, order) crossing, the Campbell-diagram data.

        Parameters
        ----------
        orders : array_like, optional
            Excitation orders (per crankshaft revolution); default 0.5..12 (4-stroke) or 1..12.
        speed_range_rpm : (float, float), optional
            Keep crossings within this crankshaft speed range, rpm (inclusive).

        Returns
        -------
        pandas.DataFrame
            Columns ``mode`` (1 = first elastic mode), ``order``, ``speed_rpm``,
            ``frequency_hz``, ``vector_sum`` (relative, NaN without firing angles),
            ``major`` (bool), sorted by speed. With centrifugal pendulums the modes move with
            speed and a critical speed is a root of ω_m(Ω) = qΩ
            (:mod:`predict.torsion.campbell`); ``frequency_hz`` is then the mode's frequency
            at that speed.

        References
        ----------
        内燃机动力学 (1958), 第二篇 第四章 §1 临界转速: n_c = 60 f / q.

        Examples
        --------
        >>> from crankbench.predict.torsion import chain
        >>> s = chain([1.0, 1.0], [(2 * 3.141592653589793 * 50) ** 2 / 2])
        >>> print(s.critical_speeds([1, 2], (0, 5000))[["mode", "order", "speed_rpm"]])
           mode  order  speed_rpm
        0     1    2.0     1500.0
        1     1    1.0     3000.0
        """
        import pandas as pd

        orders = self.default_orders() if orders is None else np.atleast_1d(
            check_finite_array(orders, "orders", error=ModelError))
        if np.any(orders <= 0):
            raise ModelError(f"orders must be > 0, got {np.asarray(orders).tolist()}")
        lo, hi = (0.0, np.inf) if speed_range_rpm is None else map(float, speed_range_rpm)
        if not lo <= hi:
            raise ModelError(f"speed_range_rpm={speed_range_rpm!r} must be (low, high), low<=high")
        from .campbell import has_speed_dependence, speed_dependent_criticals

        if has_speed_dependence(self):
            rows = speed_dependent_criticals(self, orders, lo, hi)
            frame = pd.DataFrame(rows, columns=["mode", "order", "speed_rpm", "frequency_hz",
                                                "vector_sum", "major"])
            return frame.sort_values(["speed_rpm", "mode"], ignore_index=True)
        if np.isfinite(hi):  # only modes that can cross an order below the top speed
            omega, numbers, shapes = subset.below(self, TWO_PI * float(np.max(orders)) * hi
                                                  / 60.0 * (1 + 1e-9))
        else:
            omega, shapes, numbers = self._eigen[:3]
        f = omega / TWO_PI
        vs = self._vector_sums(orders, shapes)
        major = self.major_orders(orders)
        rows = []
        for i in np.flatnonzero(numbers > 0):
            for j, q in enumerate(orders):
                rpm = 60.0 * f[i] / q
                if lo <= rpm <= hi:
                    rows.append((int(numbers[i]), float(q), rpm, f[i], vs[i, j], bool(major[j])))
        frame = pd.DataFrame(rows, columns=["mode", "order", "speed_rpm", "frequency_hz",
                                            "vector_sum", "major"])
        return frame.sort_values(["speed_rpm", "mode"], ignore_index=True)

    def plot_campbell(self, orders=None, speed_range_rpm=None, *, ax=None, modes=None):
        """Campbell diagram (speed in rpm on x, frequency in Hz on y); see
        :func:`predict.torsion.campbell.plot_campbell`. Returns the figure."""
        from .campbell import plot_campbell

        return plot_campbell(self, orders, speed_range_rpm, ax=ax, modes=modes)

    # ----------------------------------------------------------------- Holzer -----------
    def holzer_table(self, frequency_hz: float):
        """Classical Holzer table at a trial frequency, Hz (chains only); see
        :func:`predict.torsion.holzer.holzer_table` (columns, residual, references)."""
        from .holzer import holzer_table

        return holzer_table(self, frequency_hz)

    # ----------------------------------------------------------------- forced -----------
    def forced_response(self, speed_rpm, **kwargs):
        """Steady-state forced response over speed; see :func:`predict.torsion.forced.forced_response`."""
        from .forced import forced_response

        return forced_response(self, speed_rpm, **kwargs)


def chain(inertias, stiffnesses, *, names=None) -> TorsionalSystem:
    """A chain of lumped inertias joined by springs.

    Parameters
    ----------
    inertias : array_like (n,)
        Mass moments of inertia, kg·m².
    stiffnesses : array_like
        Torsional stiffnesses, N·m/rad: n−1 values for a chain free at both ends; n values when
        the first stiffness ties the first inertia to ground.
    names : sequence of str, optional
        Node names.

    Returns
    -------
    TorsionalSystem

    Examples
    --------
    >>> from crankbench.predict.torsion import chain
    >>> print(chain([2.0], [800.0]).natural_frequencies("rad/s"))
    [20.]
    """
    j, k = _checked_copy(inertias, "inertias", 1), _checked_copy(stiffnesses, "stiffnesses", 0)
    n = j.size
    if k.size not in (n - 1, n):
        raise ModelError(f"stiffnesses has {k.size} values; a chain of {n} inertias needs "
                         f"{n - 1} (free-free) or {n} (first inertia grounded)")
    if not j.min() > 0:
        i = int(np.flatnonzero(j <= 0)[0])
        raise ModelError(f"inertias[{i}]={float(j[i])!r} must be > 0 (kg·m²)")
    if k.size and not k.min() > 0:
        i = int(np.flatnonzero(k <= 0)[0])
        raise ModelError(f"stiffnesses[{i}]={float(k[i])!r} must be > 0 (N·m/rad)")
    return TorsionalSystem._chain_of(j, k, names)


def _checked_copy(values, name: str, min_length: int) -> np.ndarray:
    """A float64 copy of a 1-D finite array; the error (of :func:`check_finite_array`) names
    ``name`` and what is wrong. One pass over the data when it is clean."""
    try:
        arr = np.array(values, dtype=np.float64)
    except (TypeError, ValueError):
        arr = None
    if arr is None or arr.ndim != 1 or arr.size < min_length or not np.isfinite(arr).all():
        check_finite_array(values, name, ndim=1, min_length=min_length, error=ModelError)
    return arr
