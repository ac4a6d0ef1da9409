"""Beam finite-element rotor model: critical speeds, Campbell diagram, unbalance response.

A rotor is a line of shaft sections (hollow or solid circular, each of its own material), rigid
disks (mass, diametral and polar inertia) and bearings (linear springs and dampers to ground,
cross-coupling allowed; an infinite stiffness makes the support rigid). Each node carries four
degrees of freedom: the lateral displacements u (x), v (y) and the slopes φu = ∂u/∂z,
φv = ∂v/∂z. Spin is about +z (x towards y); forward whirl turns the same way.

Shaft elements are two-node Hermite beams, Euler-Bernoulli or Timoshenko (shear deformation
with Cowper's shear coefficient and rotary inertia, interdependent interpolation). Their
frequencies converge to the continuum as O(h⁴) in the element length h for Euler-Bernoulli and
as O(h²) for Timoshenko (the element's shear strain is constant per element; measured rates
2.00 and 4.00, see tests); each result carries a Richardson estimate of that discretisation
error from a mesh twice as coarse.

Eigen-solves are symmetric wherever the physics allows: eigh(K, M) at rest, and for an undamped
gyroscopic rotor the Hermitian pencil ω diag(M, K) x = −i [[−ΩG, −K], [K, 0]] x; only damped or
cross-coupled rotors use the general (non-symmetric) solver.

Equations of motion: M q̈ + (C + Ω G) q̇ + K q = f, with G skew-symmetric (gyroscopic
coupling of the two bending planes by the polar inertia of disks and shaft).

References
----------
.. [1] M. I. Friswell, J. E. T. Penny, S. D. Garvey, A. W. Lees, *Dynamics of Rotating
   Machines*, Cambridge University Press (2010), ch. 5 (finite-element rotor models, element
   matrices eq. 5.x, Campbell diagrams, critical speeds §5.9) and ch. 3 (Jeffcott rotor).
.. [2] J. S. Przemieniecki, *Theory of Matrix Structural Analysis*, McGraw-Hill (1968),
   §5.6 and §11.6 (beam element with shear deformation and rotary inertia).
.. [3] G. R. Cowper, "The shear coefficient in Timoshenko's beam theory", J. Appl. Mech. 33
   (1966) 335-340.
.. [4] Shi Zhiqing, *Engine Dynamics*, ch. 4 §27 (critical speeds of shafts), §28.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.linalg

from .._validate import (check_finite_array, check_int, check_nonnegative, check_option,
                         check_positive)
from ..errors import ModelError
from .results import CampbellDiagram, CriticalSpeeds, LateralModes, UnbalanceResponse

__all__ = ["Material", "STEEL", "ShaftSection", "Disk", "Bearing", "Rotor", "THEORIES"]

log = logging.getLogger("crankbench")

THEORIES = ("timoshenko", "euler-bernoulli")
_TOL = 1e-9  # m: positions closer than this are the same node


@dataclass(frozen=True)
class Material:
    """Isotropic linear-elastic material.

    Parameters
    ----------
    youngs_modulus : float
        E, Pa.
    density : float
        ρ, kg/m³.
    poisson_ratio : float, optional
        ν; with ``shear_modulus`` omitted, G = E / (2 (1 + ν)).
    shear_modulus : float, optional
        G, Pa (takes precedence; then ν = E/(2G) − 1).

    Examples
    --------
    >>> round(Material(2.0e11, 7800.0, poisson_ratio=0.25).shear_modulus / 1e9, 3)
    80.0
    """

    youngs_modulus: float
    density: float
    poisson_ratio: float | None = 0.3
    shear_modulus: float | None = None

    def __post_init__(self):
        put = object.__setattr__
        put(self, "youngs_modulus", check_positive(self.youngs_modulus, "youngs_modulus",
                                                   error=ModelError))
        put(self, "density", check_positive(self.density, "density", error=ModelError))
        if self.shear_modulus is not None:
            g = check_positive(self.shear_modulus, "shear_modulus", error=ModelError)
            put(self, "shear_modulus", g)
            put(self, "poisson_ratio", self.youngs_modulus / (2 * g) - 1)
        else:
            if self.poisson_ratio is None:
                raise ModelError("give poisson_ratio or shear_modulus")
            nu = float(self.poisson_ratio)
            if not -1.0 < nu < 0.5:
                raise ModelError(f"poisson_ratio={nu!r} must lie in (-1, 0.5)")
            put(self, "poisson_ratio", nu)
            put(self, "shear_modulus", self.youngs_modulus / (2 * (1 + nu)))


#: structural steel used when a section names no material
STEEL = Material(youngs_modulus=2.11e11, density=7810.0, poisson_ratio=0.3)


@dataclass(frozen=True)
class ShaftSection:
    """A uniform length of circular shaft.

    Parameters
    ----------
    length : float
        m.
    outer_diameter : float
        m.
    inner_diameter : float
        Bore, m (0 = solid).
    material : Material
    n_elements : int, optional
        Elements in this section (before splitting at disks/bearings); default from the
        rotor's ``max_element_length``.

    Examples
    --------
    >>> s = ShaftSection(length=1.0, outer_diameter=0.1)
    >>> round(s.shear_coefficient, 4)  # Cowper, solid, nu = 0.3
    0.8864
    """

    length: float
    outer_diameter: float
    inner_diameter: float = 0.0
    material: Material = STEEL
    n_elements: int | None = None

    def __post_init__(self):
        put = object.__setattr__
        put(self, "length", check_positive(self.length, "length", error=ModelError))
        put(self, "outer_diameter", check_positive(self.outer_diameter, "outer_diameter",
                                                   error=ModelError))
        inner = check_nonnegative(self.inner_diameter, "inner_diameter", error=ModelError)
        if inner >= self.outer_diameter:
            raise ModelError(f"inner_diameter={inner!r} must be < outer_diameter="
                             f"{self.outer_diameter!r}")
        put(self, "inner_diameter", inner)
        if not isinstance(self.material, Material):
            raise ModelError(f"material must be a Material, got {type(self.material).__name__}")
        if self.n_elements is not None:
            put(self, "n_elements", check_int(self.n_elements, "n_elements", minimum=1,
                                              error=ModelError))

    @property
    def area(self) -> float:
        """Cross-section area, m²."""
        return math.pi * (self.outer_diameter**2 - self.inner_diameter**2) / 4

    @property
    def area_moment(self) -> float:
        """Second moment of area about a diameter, m⁴."""
        return math.pi * (self.outer_diameter**4 - self.inner_diameter**4) / 64

    @property
    def shear_coefficient(self) -> float:
        """Cowper's shear coefficient κ of a (hollow) circular section."""
        nu = self.material.poisson_ratio
        m2 = (self.inner_diameter / self.outer_diameter) ** 2
        return 6 * (1 + nu) * (1 + m2) ** 2 / ((7 + 6 * nu) * (1 + m2) ** 2 + (20 + 12 * nu) * m2)


@dataclass(frozen=True)
class Disk:
    """A rigid disk at a position along the shaft.

    Parameters
    ----------
    position : float
        Axial position, m from the shaft's left end.
    mass : float
        kg.
    diametral_inertia : float
        Moment of inertia about a diameter through its centre, kg·m².
    polar_inertia : float
        Moment of inertia about the spin axis, kg·m².

    Examples
    --------
    >>> d = Disk.from_geometry(position=0.5, outer_diameter=0.4, width=0.05, density=7810.0)
    >>> round(d.mass, 3), round(d.polar_inertia / d.diametral_inertia, 3)
    (49.072, 1.959)
    """

    position: float
    mass: float
    diametral_inertia: float = 0.0
    polar_inertia: float = 0.0

    def __post_init__(self):
        put = object.__setattr__
        put(self, "position", check_nonnegative(self.position, "position", error=ModelError))
        put(self, "mass", check_positive(self.mass, "mass", error=ModelError))
        put(self, "diametral_inertia", check_nonnegative(self.diametral_inertia,
                                                         "diametral_inertia", error=ModelError))
        put(self, "polar_inertia", check_nonnegative(self.polar_inertia, "polar_inertia",
                                                     error=ModelError))

    @classmethod
    def from_geometry(cls, *, position, outer_diameter, width, inner_diameter=0.0,
                      density=7810.0) -> "Disk":
        """Disk of uniform density: m = ρ π (D² − d²) w / 4, I_p = m (D² + d²)/8,
        I_d = I_p/2 + m w²/12."""
        outer = check_positive(outer_diameter, "outer_diameter", error=ModelError)
        width = check_positive(width, "width", error=ModelError)
        inner = check_nonnegative(inner_diameter, "inner_diameter", error=ModelError)
        if inner >= outer:
            raise ModelError(f"inner_diameter={inner!r} must be < outer_diameter={outer!r}")
        mass = check_positive(density, "density", error=ModelError) * math.pi * (
            outer**2 - inner**2) * width / 4
        ip = mass * (outer**2 + inner**2) / 8
        return cls(position=position, mass=mass, polar_inertia=ip,
                   diametral_inertia=ip / 2 + mass * width**2 / 12)


@dataclass(frozen=True)
class Bearing:
    """Linear bearing (spring + damper to ground) at a position along the shaft.

    Parameters
    ----------
    position : float
        m from the left end.
    kxx, kyy, kxy, kyx : float
        Stiffness coefficients, N/m (``kyy`` defaults to ``kxx``). ``inf`` makes that
        direction rigid (the degree of freedom is removed; no cross-coupling then).
    cxx, cyy, cxy, cyx : float
        Damping coefficients, N·s/m (``cyy`` defaults to ``cxx``).
    clamp : bool
        Also fix the slopes (a built-in end, e.g. for a cantilever).

    Examples
    --------
    >>> Bearing(position=0.0, kxx=float("inf")).rigid
    (True, True)
    """

    position: float
    kxx: float
    kyy: float | None = None
    kxy: float = 0.0
    kyx: float = 0.0
    cxx: float = 0.0
    cyy: float | None = None
    cxy: float = 0.0
    cyx: float = 0.0
    clamp: bool = False

    def __post_init__(self):
        put = object.__setattr__
        put(self, "position", check_nonnegative(self.position, "position", error=ModelError))
        for name in ("kxx", "kyy"):
            value = self.kxx if (name == "kyy" and self.kyy is None) else getattr(self, name)
            value = float(value)
            if not (value == math.inf or (math.isfinite(value) and value >= 0)):
                raise ModelError(f"{name}={value!r} must be >= 0 N/m (or inf for rigid)")
            put(self, name, value)
        if self.cyy is None:
            put(self, "cyy", self.cxx)
        for name in ("kxy", "kyx", "cxy", "cyx"):
            value = float(getattr(self, name))
            if not math.isfinite(value):
                raise ModelError(f"{name}={value!r} must be finite")
            put(self, name, value)
        for name in ("cxx", "cyy"):
            put(self, name, check_nonnegative(getattr(self, name), name, error=ModelError))
        if any(self.rigid) and (self.kxy or self.kyx or self.cxy or self.cyx):
            raise ModelError("a rigid bearing direction cannot carry cross-coupling terms")

    @property
    def rigid(self) -> tuple[bool, bool]:
        """Whether the x and y directions are rigid."""
        return (self.kxx == math.inf, self.kyy == math.inf)


# -- element matrices (one bending plane, dofs w1, θ1, w2, θ2) --------------------------------

def _element(length, ei, rho_a, rho_i, phi):
    """Stiffness, translational mass and rotary mass of a Timoshenko beam element.

    φ = 12 EI / (κ G A L²) (0 = Euler-Bernoulli). Przemieniecki §5.6, §11.6; Friswell et al.
    (2010) eq. 5.66-5.69.
    """
    L, p = length, phi
    k = ei / ((1 + p) * L**3) * np.array([
        [12, 6 * L, -12, 6 * L],
        [6 * L, (4 + p) * L**2, -6 * L, (2 - p) * L**2],
        [-12, -6 * L, 12, -6 * L],
        [6 * L, (2 - p) * L**2, -6 * L, (4 + p) * L**2]])
    a = 13 / 35 + 7 * p / 10 + p**2 / 3
    b = (11 / 210 + 11 * p / 120 + p**2 / 24) * L
    c = 9 / 70 + 3 * p / 10 + p**2 / 6
    d = (13 / 420 + 3 * p / 40 + p**2 / 24) * L
    e = (1 / 105 + p / 60 + p**2 / 120) * L**2
    f = (1 / 140 + p / 60 + p**2 / 120) * L**2
    mt = rho_a * L / (1 + p) ** 2 * np.array([
        [a, b, c, -d], [b, e, d, -f], [c, d, a, -b], [-d, -f, -b, e]])
    g = (1 / 10 - p / 2) * L
    h = (2 / 15 + p / 6 + p**2 / 3) * L**2
    j = (-1 / 30 - p / 6 + p**2 / 6) * L**2
    mr = rho_i / (L * (1 + p) ** 2) * np.array([
        [6 / 5, g, -6 / 5, g], [g, h, -g, j], [-6 / 5, -g, 6 / 5, -g], [g, j, -g, h]])
    return k, mt, mr


@dataclass(frozen=True)
class _Model:
    """Assembled matrices with the rigid dofs removed."""

    positions: np.ndarray
    n_elements: int
    K: np.ndarray
    M: np.ndarray
    C: np.ndarray
    G: np.ndarray
    free: np.ndarray  # indices of kept dofs in the full 4·n_nodes vector


@dataclass(frozen=True)
class Rotor:
    """Rotor model built from shaft sections, disks and bearings.

    Parameters
    ----------
    shaft : sequence of ShaftSection
        Sections from left to right; the shaft starts at z = 0.
    disks : sequence of Disk
    bearings : sequence of Bearing
    theory : {"timoshenko", "euler-bernoulli"}
        Shaft element theory. Timoshenko adds shear deformation; both include rotary inertia
        unless ``rotary_inertia=False`` (classical Euler-Bernoulli beam).
    max_element_length : float, optional
        Fidelity: longest shaft element, m (default: total length / 20). A section's own
        ``n_elements`` takes precedence.
    rotary_inertia : bool
        Include the shaft's rotary inertia (and its gyroscopic effect).
    name : str

    Examples
    --------
    >>> r = Rotor(shaft=[ShaftSection(length=1.0, outer_diameter=0.05)],
    ...           bearings=[Bearing(0.0, float("inf")), Bearing(1.0, float("inf"))],
    ...           theory="euler-bernoulli", rotary_inertia=False)
    >>> round(float(r.natural_frequencies(n_modes=1).frequency_hz[0]), 2)  # closed form 102.06
    102.06
    """

    shaft: tuple
    disks: tuple = ()
    bearings: tuple = ()
    theory: str = "timoshenko"
    max_element_length: float | None = None
    rotary_inertia: bool = True
    name: str = ""
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self):
        put = object.__setattr__
        put(self, "shaft", tuple(self.shaft))
        put(self, "disks", tuple(self.disks))
        put(self, "bearings", tuple(self.bearings))
        if not self.shaft:
            raise ModelError("shaft must contain at least one ShaftSection")
        for name, items, cls in (("shaft", self.shaft, ShaftSection), ("disks", self.disks, Disk),
                                 ("bearings", self.bearings, Bearing)):
            for i, item in enumerate(items):
                if not isinstance(item, cls):
                    raise ModelError(f"{name}[{i}] must be a {cls.__name__}, got "
                                     f"{type(item).__name__}")
        put(self, "theory", check_option(self.theory, "theory", THEORIES, error=ModelError))
        total = self.length
        if self.max_element_length is not None:
            put(self, "max_element_length", check_positive(
                self.max_element_length, "max_element_length", error=ModelError))
        for name, items in (("disks", self.disks), ("bearings", self.bearings)):
            for i, item in enumerate(items):
                if item.position > total + _TOL:
                    raise ModelError(f"{name}[{i}].position={item.position!r} m lies beyond the "
                                     f"shaft end at {total:g} m")

    @property
    def length(self) -> float:
        """Total shaft length, m."""
        return float(sum(s.length for s in self.shaft))

    @property
    def mass(self) -> float:
        """Total mass of shaft and disks, kg."""
        return float(sum(s.material.density * s.area * s.length for s in self.shaft)
                     + sum(d.mass for d in self.disks))

    # -- assembly --------------------------------------------------------------------------
    def _mesh(self, coarsen: int):
        h_default = self.max_element_length or self.length / 20
        marks = sorted({d.position for d in self.disks} | {b.position for b in self.bearings})
        nodes, owner = [0.0], []
        z0 = 0.0
        for si, sec in enumerate(self.shaft):
            z1 = z0 + sec.length
            cuts = [z0] + [m for m in marks if z0 + _TOL < m < z1 - _TOL] + [z1]
            h = sec.length / sec.n_elements if sec.n_elements else h_default
            for a, b in zip(cuts[:-1], cuts[1:]):
                n = max(1, math.ceil((b - a) / h - 1e-9))
                n = max(1, math.ceil(n / coarsen))
                nodes.extend(a + (b - a) * np.arange(1, n + 1) / n)
                owner.extend([si] * n)
            z0 = z1
        return np.asarray(nodes), owner

    def _assemble(self, coarsen: int = 1) -> _Model:
        key = ("model", coarsen)
        if key in self._cache:
            return self._cache[key]
        z, owner = self._mesh(coarsen)
        n = 4 * z.size
        K, M, C, G = (np.zeros((n, n)) for _ in range(4))
        for e, si in enumerate(owner):
            sec = self.shaft[si]
            L = z[e + 1] - z[e]
            mat = sec.material
            ei = mat.youngs_modulus * sec.area_moment
            phi = 0.0
            if self.theory == "timoshenko":
                phi = 12 * ei / (sec.shear_coefficient * mat.shear_modulus * sec.area * L**2)
            rho_i = mat.density * sec.area_moment if self.rotary_inertia else 0.0
            k, mt, mr = _element(L, ei, mat.density * sec.area, rho_i, phi)
            iu = np.array([4 * e, 4 * e + 2, 4 * e + 4, 4 * e + 6])
            iv = iu + 1
            for idx in (iu, iv):
                K[np.ix_(idx, idx)] += k
                M[np.ix_(idx, idx)] += mt + mr
            # polar inertia ρ I_p = 2 ρ I couples the planes: Friswell et al. eq. 5.70
            G[np.ix_(iu, iv)] += 2 * mr
            G[np.ix_(iv, iu)] -= 2 * mr
        fixed = set()
        for d in self.disks:
            i = 4 * int(np.argmin(np.abs(z - d.position)))
            M[i, i] += d.mass
            M[i + 1, i + 1] += d.mass
            M[i + 2, i + 2] += d.diametral_inertia
            M[i + 3, i + 3] += d.diametral_inertia
            G[i + 2, i + 3] += d.polar_inertia
            G[i + 3, i + 2] -= d.polar_inertia
        for b in self.bearings:
            i = 4 * int(np.argmin(np.abs(z - b.position)))
            rx, ry = b.rigid
            if rx:
                fixed.add(i)
            if ry:
                fixed.add(i + 1)
            if b.clamp:
                fixed.update((i + 2, i + 3))
            K[i, i] += 0.0 if rx else b.kxx
            K[i + 1, i + 1] += 0.0 if ry else b.kyy
            K[i, i + 1] += b.kxy
            K[i + 1, i] += b.kyx
            C[i, i] += b.cxx
            C[i + 1, i + 1] += b.cyy
            C[i, i + 1] += b.cxy
            C[i + 1, i] += b.cyx
        free = np.array([i for i in range(n) if i not in fixed])
        sub = np.ix_(free, free)
        model = _Model(z, len(owner), K[sub], M[sub], C[sub], G[sub], free)
        self._cache[key] = model
        return model

    def _full(self, model: _Model, vec: np.ndarray) -> np.ndarray:
        out = np.zeros((4 * model.positions.size,) + vec.shape[1:], dtype=vec.dtype)
        out[model.free] = vec
        return out

    @staticmethod
    def _circularise(values: np.ndarray, full_vecs: np.ndarray, rtol: float = 1e-6):
        """Within clusters of repeated eigenvalues (isotropic rotor, no gyroscopic split),
        rotate the basis to the circular forward/backward combinations: eigenvectors of the
        whirl form Σ 2 Im(u v̄) relative to the displacement norm inside the cluster."""
        out = full_vecs.astype(complex)
        i = 0
        while i < values.size:
            j = i + 1
            while j < values.size and abs(values[j] - values[i]) <= rtol * max(abs(values[i]),
                                                                                1e-300):
                j += 1
            if j - i > 1:
                phi = out[:, i:j]
                u, v = phi[0::4], phi[1::4]
                whirl = 1j * (u.conj().T @ v) - 1j * (v.conj().T @ u)
                norm = u.conj().T @ u + v.conj().T @ v
                _, rot = scipy.linalg.eigh(whirl, norm)
                out[:, i:j] = phi @ rot
            i = j
        return out

    @staticmethod
    def _whirl(model_full_vecs: np.ndarray):
        u, v = model_full_vecs[0::4], model_full_vecs[1::4]
        num = 2 * np.sum(np.imag(u * np.conj(v)), axis=0)
        den = np.sum(np.abs(u) ** 2 + np.abs(v) ** 2, axis=0)
        index = np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)
        labels = np.where(index > 0.1, "forward", np.where(index < -0.1, "backward", "mixed"))
        return index, labels

    # -- eigen-analysis --------------------------------------------------------------------
    def _eig(self, model: _Model, speed: float, n_modes: int):
        K, M = model.K, model.M
        D = model.C + speed * model.G
        scale = 1.0 / np.sqrt(np.diag(M))  # balance translations against slopes
        Ks, Ms, Ds = (scale[:, None] * A * scale[None, :] for A in (K, M, D))
        symmetric = np.allclose(Ks, Ks.T, rtol=0, atol=1e-12 * np.abs(Ks).max())
        undamped = not np.any(model.C)
        omega = None
        if symmetric and not np.any(Ds):
            lam, vec = scipy.linalg.eigh(Ks, Ms)
            omega = np.sqrt(np.clip(lam, 0.0, None))
            vec = vec.astype(complex)
        elif symmetric and undamped:
            # undamped gyroscopic system: with x = [q̇; q], diag(M, K) ẋ = [[−ΩG, −K], [K, 0]] x;
            # the right-hand matrix is skew, so ω diag(M, K) x = −i A x is a Hermitian pencil
            # (real ω exactly, ± pairs). Needs K positive definite (a supported rotor).
            n = K.shape[0]
            a = np.block([[-Ds, -Ks], [Ks, np.zeros((n, n))]])
            b = np.block([[Ms, np.zeros((n, n))], [np.zeros((n, n)), Ks]])
            try:
                lam, vec = scipy.linalg.eigh(-1j * a, b)
            except np.linalg.LinAlgError:
                pass  # singular K (free rotor): fall back to the general solver
            else:
                keep = lam > 0
                omega, vec = lam[keep], vec[n:, keep]
        if omega is not None:
            zeta = np.zeros_like(omega)
        else:
            n = K.shape[0]
            eye, zero = np.eye(n), np.zeros((n, n))
            a = np.block([[zero, eye], [-Ks, -Ds]])
            b = np.block([[eye, zero], [zero, Ms]])
            s, vec = scipy.linalg.eig(a, b)
            keep = np.isfinite(s) & (s.imag > 1e-9 * max(1.0, np.abs(s).max()))
            s, vec = s[keep], vec[:n, keep]
            omega = s.imag
            zeta = -s.real / np.abs(s)
        order = np.argsort(omega)[:n_modes + 1]  # one extra to close a repeated pair
        vec = self._circularise(omega[order], self._full(model, scale[:, None] * vec[:, order]))
        return omega[order][:n_modes], zeta[order][:n_modes], vec[:, :n_modes]

    def natural_frequencies(self, speed: float = 0.0, *, n_modes: int = 6,
                            error_estimate: bool = True) -> LateralModes:
        """Damped natural frequencies and whirl directions at spin speed ``speed``.

        Parameters
        ----------
        speed : float
            Spin speed Ω, rad/s.
        n_modes : int
            Number of lowest modes returned (an isotropic rotor at rest gives each frequency
            twice, one per bending plane).
        error_estimate : bool
            Also solve a mesh twice as coarse and report the Richardson estimate
            |ω_h − ω_2h|/(2^p − 1), p = 4 (Euler-Bernoulli) or 2 (Timoshenko).

        Returns
        -------
        LateralModes

        References
        ----------
        Friswell et al., *Dynamics of Rotating Machines*, §5.8 (eigenvalues, whirl directions).

        Examples
        --------
        >>> r = Rotor(shaft=[ShaftSection(length=1.0, outer_diameter=0.05)],
        ...           bearings=[Bearing(0.0, 1e7), Bearing(1.0, 1e7)],
        ...           disks=[Disk(0.5, mass=20.0, diametral_inertia=0.1, polar_inertia=0.2)])
        >>> m = r.natural_frequencies(speed=300.0, n_modes=2)
        >>> m.whirl
        ('backward', 'forward')
        """
        speed = float(check_finite_array(speed, "speed", ndim=0, error=ModelError))
        n_modes = check_int(n_modes, "n_modes", minimum=1, error=ModelError)
        model = self._assemble()
        omega, zeta, vec = self._eig(model, speed, n_modes)
        index, labels = self._whirl(vec)
        err = np.full(omega.size, np.nan)
        if error_estimate:
            coarse = self._eig(self._assemble(coarsen=2), speed, n_modes)[0]
            k = min(coarse.size, omega.size)
            rate = 4 if self.theory == "euler-bernoulli" else 2
            err[:k] = np.abs(omega[:k] - coarse[:k]) / (2**rate - 1)
        shapes = np.stack([vec[0::4].T, vec[1::4].T], axis=-1)
        peak = np.abs(shapes).reshape(shapes.shape[0], -1).max(axis=1)
        shapes = shapes / np.where(peak > 0, peak, 1.0)[:, None, None]
        return LateralModes(speed=speed, omega=omega, damping_ratio=zeta,
                            whirl=tuple(labels.tolist()), whirl_index=index, error_estimate=err,
                            positions=model.positions, shapes=shapes, theory=self.theory,
                            n_elements=model.n_elements)

    def critical_speeds(self, orders=(1.0,), *, n_modes: int = 4,
                        speed_range_rpm=None) -> CriticalSpeeds:
        """Undamped critical speeds for excitation orders, by an exact eigen-solve.

        Setting the whirl frequency to k Ω in the undamped equations gives
        K φ = Ω² (k² M − i k G) φ, a Hermitian pencil solved directly (no Campbell-diagram
        interpolation, no root-finding); damping is ignored as in the classical definition.
        Exact for the discretised model; the discretisation error is O(h⁴) (Euler-Bernoulli)
        or O(h²) (Timoshenko).

        Parameters
        ----------
        orders : sequence of float
            Excitation orders (1 = unbalance, synchronous).
        n_modes : int
            Number of lowest critical speeds kept per order.
        speed_range_rpm : (float, float), optional
            Keep only critical speeds inside this range, rpm.

        Returns
        -------
        CriticalSpeeds

        References
        ----------
        Friswell et al., *Dynamics of Rotating Machines*, §5.9 (critical speeds);
        Shi, *Engine Dynamics* ch. 4 §27.

        Examples
        --------
        >>> r = Rotor(shaft=[ShaftSection(length=1.0, outer_diameter=0.05)],
        ...           bearings=[Bearing(0.0, float("inf")), Bearing(1.0, float("inf"))],
        ...           theory="euler-bernoulli", rotary_inertia=False)
        >>> round(float(r.critical_speeds(n_modes=1).speed_rpm[0]), 1)  # 60 × 102.058 Hz
        6123.5
        """
        orders = check_finite_array(orders, "orders", ndim=1, min_length=1, error=ModelError)
        if np.any(orders <= 0):
            raise ModelError(f"orders must be > 0, got {orders.tolist()}")
        n_modes = check_int(n_modes, "n_modes", minimum=1, error=ModelError)
        model = self._assemble()
        K, M, G = model.K, model.M, model.G
        scale = 1.0 / np.sqrt(np.diag(M))
        Ks, Ms, Gs = (scale[:, None] * A * scale[None, :] for A in (K, M, G))
        symmetric = np.allclose(Ks, Ks.T, rtol=0, atol=1e-12 * np.abs(Ks).max())
        rows = []
        for k in orders:
            B = k**2 * Ms - 1j * k * Gs
            if symmetric:
                try:
                    mu, vec = scipy.linalg.eigh(B, Ks.astype(complex))
                except np.linalg.LinAlgError:
                    raise ModelError("the rotor is not supported (singular stiffness): add "
                                     "bearings before asking for critical speeds") from None
                keep = mu > 1e-14 * np.abs(mu).max()
                om = 1.0 / np.sqrt(mu[keep])
                vec = vec[:, keep]
            else:
                lam, vec = scipy.linalg.eig(Ks, B)
                keep = (np.isfinite(lam) & (lam.real > 0)
                        & (np.abs(lam.imag) < 1e-8 * np.abs(lam)))
                om, vec = np.sqrt(lam[keep].real), vec[:, keep]
            order = np.argsort(om)
            om = om[order]
            full = self._circularise(om, self._full(model, scale[:, None] * vec[:, order]))
            labels = self._whirl(full)[1]
            if speed_range_rpm is not None:
                lo, hi = np.asarray(speed_range_rpm, dtype=float) * np.pi / 30
                inside = (om >= lo) & (om <= hi)
                om, labels = om[inside], labels[inside]
            om, labels = om[:n_modes], labels[:n_modes]
            rows.extend((k, w, o) for o, w in zip(om, labels))
        omega = np.array([r[2] for r in rows])
        mode = np.ones(len(rows), dtype=int)
        seen: dict = {}
        for i, (k, w, _) in enumerate(rows):
            seen[(k, w)] = seen.get((k, w), 0) + 1
            mode[i] = seen[(k, w)]
        return CriticalSpeeds(omega=omega, order=np.array([r[0] for r in rows]),
                              whirl=tuple(r[1] for r in rows), mode=mode,
                              method="hermitian eigen-solve K φ = Ω² (k² M − i k G) φ",
                              n_elements=model.n_elements, theory=self.theory)

    def campbell(self, speeds, *, n_modes: int = 6, orders=(1.0,)) -> CampbellDiagram:
        """Campbell diagram: natural frequencies and whirl at each spin speed.

        Parameters
        ----------
        speeds : array_like
            Spin speeds, rad/s (>= 0).
        n_modes : int
            Modes per speed.
        orders : sequence of float
            Excitation orders whose lines and exact critical speeds are included.

        Returns
        -------
        CampbellDiagram

        Examples
        --------
        >>> r = Rotor(shaft=[ShaftSection(length=1.0, outer_diameter=0.05)],
        ...           bearings=[Bearing(0.0, 1e7), Bearing(1.0, 1e7)],
        ...           disks=[Disk(0.5, mass=20.0, diametral_inertia=0.1, polar_inertia=0.2)])
        >>> c = r.campbell([0.0, 500.0], n_modes=2)
        >>> c.omega.shape
        (2, 2)
        """
        speeds = check_finite_array(speeds, "speeds", ndim=1, min_length=1, error=ModelError)
        if np.any(speeds < 0):
            raise ModelError("speeds must be >= 0 rad/s")
        n_modes = check_int(n_modes, "n_modes", minimum=1, error=ModelError)
        model = self._assemble()
        omega = np.full((speeds.size, n_modes), np.nan)
        whirl = np.full((speeds.size, n_modes), "mixed", dtype=object)
        for i, s in enumerate(speeds):
            w, _, vec = self._eig(model, float(s), n_modes)
            omega[i, :w.size] = w
            whirl[i, :w.size] = self._whirl(vec)[1]
        crit = self.critical_speeds(orders, n_modes=n_modes,
                                    speed_range_rpm=(speeds.min() * 30 / np.pi,
                                                     speeds.max() * 30 / np.pi))
        return CampbellDiagram(speeds=speeds, omega=omega, whirl=whirl.astype(str),
                               orders=tuple(float(o) for o in np.atleast_1d(orders)),
                               criticals=crit)

    def unbalance_response(self, speeds, unbalances, *, probes=None) -> UnbalanceResponse:
        """Synchronous steady-state response to rotating unbalances.

        Solves (K − Ω² M + iΩ (C + Ω G)) q = f with f = m e Ω² e^{iβ} (1, −i) on (u, v) of
        each unbalanced node (force rotating forward with the shaft).

        Parameters
        ----------
        speeds : array_like
            Spin speeds, rad/s.
        unbalances : sequence of (position, magnitude, angle)
            Axial position (m), unbalance m·e (kg·m) and angle β (rad) from the x axis.
        probes : array_like, optional
            Positions whose response is returned, m (default: each unbalance position).

        Returns
        -------
        UnbalanceResponse

        References
        ----------
        Friswell et al., *Dynamics of Rotating Machines*, §5.10 (unbalance response).

        Examples
        --------
        >>> r = Rotor(shaft=[ShaftSection(length=1.0, outer_diameter=0.05)],
        ...           bearings=[Bearing(0.0, 1e7, cxx=500.0), Bearing(1.0, 1e7, cxx=500.0)],
        ...           disks=[Disk(0.5, mass=20.0)])
        >>> res = r.unbalance_response([100.0], [(0.5, 1e-4, 0.0)])
        >>> res.response.shape
        (1, 1, 2)
        """
        speeds = check_finite_array(speeds, "speeds", ndim=1, min_length=1, error=ModelError)
        model = self._assemble()
        z = model.positions
        force = np.zeros(4 * z.size, dtype=complex)
        if not len(unbalances):
            raise ModelError("unbalances must list at least one (position, magnitude, angle)")
        for i, item in enumerate(unbalances):
            try:
                pos, mag, ang = (float(v) for v in item)
            except (TypeError, ValueError):
                raise ModelError(f"unbalances[{i}]={item!r} must be (position m, magnitude "
                                 "kg·m, angle rad)") from None
            node = self._node(z, pos, f"unbalances[{i}]")
            force[4 * node] += mag * np.exp(1j * ang)
            force[4 * node + 1] += -1j * mag * np.exp(1j * ang)
        probes = ([u[0] for u in unbalances] if probes is None
                  else check_finite_array(probes, "probes", ndim=1, min_length=1,
                                          error=ModelError))
        nodes = [self._node(z, float(p), "probes") for p in probes]
        f = force[model.free]
        out = np.empty((speeds.size, len(nodes), 2), dtype=complex)
        for i, s in enumerate(speeds):
            dyn = model.K - s**2 * model.M + 1j * s * (model.C + s * model.G)
            try:
                q = self._full(model, np.linalg.solve(dyn, s**2 * f))
            except np.linalg.LinAlgError:
                raise ModelError(f"speed {s:g} rad/s is exactly on an undamped critical speed: "
                                 "the response is unbounded; add bearing damping") from None
            out[i, :, 0] = q[[4 * n for n in nodes]]
            out[i, :, 1] = q[[4 * n + 1 for n in nodes]]
        return UnbalanceResponse(speeds=speeds, positions=np.asarray(probes, dtype=float),
                                 response=out)

    @staticmethod
    def _node(z, pos, what) -> int:
        i = int(np.argmin(np.abs(z - pos)))
        if abs(z[i] - pos) > max(_TOL, 1e-6 * z[-1]):
            raise ModelError(f"{what} position {pos!r} m is not a node; nodes lie at disks, "
                             f"bearings and mesh points (nearest {z[i]:.6g} m) — add a Disk "
                             "or a section boundary there")
        return i

    def refined(self, factor: int = 2) -> "Rotor":
        """The same rotor with elements ``factor`` times shorter (for convergence studies)."""
        factor = check_int(factor, "factor", minimum=1, error=ModelError)
        h = (self.max_element_length or self.length / 20) / factor
        shaft = [replace(s, n_elements=s.n_elements * factor) if s.n_elements else s
                 for s in self.shaft]
        return replace(self, shaft=shaft, max_element_length=h)
