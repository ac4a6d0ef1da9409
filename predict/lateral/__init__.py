"""Lateral (bending) vibration of shafts and beams: critical speeds and whirl.

Submodules, imported on use so ``import predict.lateral`` does no work:

``beams``
    Closed forms: uniform beams with classical end conditions, a massless shaft carrying one
    disk, influence (flexibility) coefficients.
``approx``
    The classical approximations on a shaft carrying concentrated masses: Rayleigh (upper
    bound), Dunkerley (lower bound) and Stodola's iteration (two-sided bracket).
``fe``
    Beam finite elements (Euler-Bernoulli or Timoshenko) with disks, bearings as springs and
    the gyroscopic effect: natural frequencies, Campbell diagram with forward/backward whirl,
    critical speeds, unbalance response.
``elements``
    Material, shaft sections, disks, bearings and the beam element matrices.
``results``
    Result objects (modes, critical speeds, Campbell diagram, unbalance response).
``toml``
    The ``[rotor]`` model-file loader.
``journal``
    Plain journal bearings: short-bearing closed form and finite-length Reynolds solution,
    eccentricity/Sommerfeld relation, stiffness and damping coefficients as a ``Bearing``.
"""

from .._lazy import lazy_names


#: public name -> submodule that defines it
_LAZY = {
    "beam_natural_frequencies": "beams",
    "BeamModes": "beams",
    "influence_coefficient": "beams",
    "point_stiffness": "beams",
    "disk_on_shaft_frequency": "beams",
    "MassShaft": "approx",
    "rayleigh": "approx",
    "dunkerley": "approx",
    "dunkerley_combine": "approx",
    "stodola": "approx",
    "ApproxResult": "approx",
    "Rotor": "fe",
    "ShaftSection": "fe",
    "Disk": "fe",
    "Bearing": "fe",
    "Material": "fe",
    "STEEL": "fe",
    "element_matrices": "elements",
    "lumped_exact": "approx",
    "load_rotor": "toml",
    "RotorModel": "toml",
    "JournalBearing": "journal",
    "BearingCoefficients": "journal",
}

__getattr__, __dir__, __all__ = lazy_names(__name__, _LAZY)
