"""Rotor building blocks: material, shaft sections, rigid disks, bearings, beam element matrices.

Used by :class:`predict.lateral.fe.Rotor`; SI units throughout.

References
----------
.. [1] M. I. Friswell, J. E. T. Penny, S. D. Garvey, A. W. Lees, *Dynamics of Rotating
   Machines*, Cambridge University Press (2010), §5.4 (shaft element matrices).
.. [2] J. S. Przemieniecki, *Theory of Matrix Structural Analysis*, McGraw-Hill (1968),
   §5.6 and §11.6 (beam element with shear deformation and rotary inertia).
.. [3] G. R. Cowper, "The shear coefficient in Timoshenko's beam theory", J. Appl. Mech. 33
   (1966) 335-340.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._validate import check_int, check_nonnegative, check_positive
from ..errors import ModelError

__all__ = ["Material", "STEEL", "ShaftSection", "Disk", "Bearing", "element_matrices"]


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

def element_matrices(length, ei, rho_a, rho_i, phi):
    """Stiffness, translational mass and rotary mass of a Timoshenko beam element.

    One bending plane, dofs (w₁, θ₁, w₂, θ₂); φ = 12 EI / (κ G A L²) (0 = Euler-Bernoulli).

    Parameters
    ----------
    length : float
        Element length L, m.
    ei : float
        Bending stiffness EI, N·m².
    rho_a, rho_i : float
        Mass per length ρA (kg/m) and rotary inertia per length ρI (kg·m).
    phi : float
        Shear parameter.

    Returns
    -------
    tuple of ndarray
        (K, M_translational, M_rotary), each 4×4. Named return order is fixed and documented.

    References
    ----------
    Przemieniecki §5.6, §11.6; Friswell et al. (2010) §5.4.

    Examples
    --------
    >>> k, mt, mr = element_matrices(1.0, 1.0, 420.0, 0.0, 0.0)
    >>> float(k[0, 0]), float(mt[0, 0])
    (12.0, 156.0)
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
