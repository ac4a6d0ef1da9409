"""Loading a rotor model (``[rotor]`` table) for lateral critical-speed analysis.

File layout (SI units; rpm only in keys that say so)::

    [rotor]
    name = "two-disk rotor"
    theory = "timoshenko"          # or "euler-bernoulli"
    max_element_length = 0.05      # m, fidelity of the shaft mesh
    rotary_inertia = true

    [rotor.material]               # default for every section
    youngs_modulus = 2.11e11       # Pa
    density = 7810.0               # kg/m³
    poisson_ratio = 0.3            # or shear_modulus (Pa)

    [[rotor.shaft]]                # sections from left to right
    length = 0.5                   # m
    outer_diameter = 0.05          # m
    inner_diameter = 0.0           # m (optional)
    n_elements = 4                 # optional; a section may have its own [..material]

    [[rotor.disks]]
    position = 0.5                 # m from the left end
    mass = 32.6                    # kg, with diametral_inertia / polar_inertia (kg·m²)
    # or: outer_diameter, width, inner_diameter, density (geometry)

    [[rotor.bearings]]
    position = 0.0
    kxx = 1.0e6                    # N/m; rigid = true for an ideal pin, clamp = true to fix slopes
    kyy = 1.0e6
    cxx = 0.0                      # N·s/m; also kxy, kyx, cxy, cyx, cyy
    # or a plain journal bearing, coefficients at a design speed and static load:
    # [rotor.bearings.journal]  diameter, length, radial_clearance (m), viscosity (Pa·s),
    #                           load (N, acting along −y), speed_rpm, model = "finite"|"short"

    [analysis]                     # optional
    speed_range_rpm = [0.0, 12000.0]
    n_speeds = 41
    orders = [1.0]
    n_modes = 4

    [[unbalance]]                  # optional: unbalance response
    position = 0.5                 # m (a disk or node position)
    magnitude = 1.0e-4             # kg·m
    angle_deg = 0.0

Any number may be written with its unit as a string, converted by pint
(``outer_diameter = "50 mm"``, ``kxx = "1 kN/mm"``, ``magnitude = "100 g*mm"``); a value far
outside the key's plausible range warns with the likely slip.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._toml import Table, load_toml
from ..errors import ModelError
from .fe import STEEL, THEORIES, Bearing, Disk, Material, Rotor, ShaftSection

__all__ = ["RotorModel", "load_rotor"]


@dataclass(frozen=True)
class RotorModel:
    """A rotor with the analysis settings of its model file.

    Attributes
    ----------
    rotor : Rotor
    speed_range_rpm : tuple of float
    n_speeds : int
    orders : tuple of float
    n_modes : int
    unbalances : tuple of (position m, magnitude kg·m, angle rad)
    source : str
    """

    rotor: Rotor
    speed_range_rpm: tuple
    n_speeds: int
    orders: tuple
    n_modes: int
    unbalances: tuple
    source: str

    @property
    def speeds(self) -> np.ndarray:
        """Analysis spin speeds, rad/s."""
        lo, hi = self.speed_range_rpm
        return np.linspace(lo, hi, self.n_speeds) * math.pi / 30


# unit and plausible range of the rotor keys (plain numbers are in these units)
_LENGTH = dict(unit="m", plausible=(1e-3, 100.0))
_POSITION = dict(unit="m", plausible=(1e-4, 100.0))
_DIAMETER = dict(unit="m", plausible=(1e-3, 5.0))
_DENSITY = dict(unit="kg/m^3", plausible=(300.0, 25000.0))
_INERTIA = dict(unit="kg*m^2", plausible=(1e-8, 1e7))
_BEARING_K = dict(unit="N/m", plausible=(1e2, 1e13))
_BEARING_C = dict(unit="N*s/m", plausible=(1e-2, 1e10))


def _bool(t: Table, key: str, default: bool) -> bool:
    value = t.raw(key, default)
    if not isinstance(value, bool):
        t.fail(key, f"= {value!r} must be true or false")
    return value


def _material(t: Table | None, default: Material) -> Material:
    if t is None or not t.data:
        return default
    e = t.positive("youngs_modulus", default.youngs_modulus, unit="Pa", plausible=(1e9, 1e12))
    rho = t.positive("density", default.density, **_DENSITY)
    g = t.positive("shear_modulus", None, unit="Pa", plausible=(1e9, 5e11))
    nu = t.number("poisson_ratio", None, low=-0.999, high=0.499, unit="1",
                  plausible=(0.05, 0.499))
    t.check_unknown()
    try:
        if g is not None:
            return Material(e, rho, shear_modulus=g)
        return Material(e, rho, poisson_ratio=default.poisson_ratio if nu is None else nu)
    except ModelError as exc:
        t.fail(None, str(exc))


def load_rotor(path: str | Path) -> RotorModel:
    """Read a rotor model TOML file (layout in the module docstring).

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    RotorModel

    Raises
    ------
    ModelError
        Naming the file, the dotted key and what was expected.

    Examples
    --------
    >>> import pathlib
    >>> p = pathlib.Path(__file__).parents[2] / "sample_data" / "rotors" / "two_disk.toml"
    >>> model = load_rotor(p)
    >>> len(model.rotor.disks), model.rotor.theory
    (2, 'timoshenko')
    """
    doc = load_toml(path)
    r = doc.table("rotor", None)
    if r is None or not r.data:
        doc.fail("rotor", "table is missing (required): the file must define [rotor]")
    material = _material(r.table("material", None), STEEL)
    sections = []
    for s in r.tables("shaft"):
        mat = _material(s.table("material", None), material)
        values = dict(length=s.positive("length", **_LENGTH),
                      outer_diameter=s.positive("outer_diameter", **_DIAMETER),
                      inner_diameter=s.number("inner_diameter", 0.0, low=0.0, **_DIAMETER),
                      material=mat,
                      n_elements=s.integer("n_elements", None, minimum=1))
        s.check_unknown()
        try:
            sections.append(ShaftSection(**values))
        except ModelError as exc:  # cross-field checks (bore >= diameter)
            s.fail(None, str(exc))
    if not sections:
        r.fail("shaft", "needs at least one [[rotor.shaft]] section")
    disks = []
    for d in r.tables("disks", []):
        position = d.number("position", low=0.0, **_POSITION)
        if "mass" in d:
            values = dict(position=position,
                          mass=d.positive("mass", unit="kg", plausible=(1e-3, 1e6)),
                          diametral_inertia=d.number("diametral_inertia", 0.0, low=0.0,
                                                     **_INERTIA),
                          polar_inertia=d.number("polar_inertia", 0.0, low=0.0, **_INERTIA))
            build = Disk
        else:
            values = dict(position=position,
                          outer_diameter=d.positive("outer_diameter", unit="m",
                                                    plausible=(1e-3, 20.0)),
                          width=d.positive("width", unit="m", plausible=(1e-4, 10.0)),
                          inner_diameter=d.number("inner_diameter", 0.0, low=0.0, unit="m",
                                                  plausible=(1e-4, 20.0)),
                          density=d.positive("density", material.density, **_DENSITY))
            build = Disk.from_geometry
        d.check_unknown()
        try:
            disks.append(build(**values))
        except ModelError as exc:  # cross-field checks (bore >= diameter)
            d.fail(None, str(exc))
    bearings = []
    for b in r.tables("bearings", []):
        jt = b.table("journal", None)
        if jt is not None:
            bearings.append(_journal_bearing(b, jt))
            continue
        rigid = _bool(b, "rigid", False)
        inf = math.inf
        kxx = inf if rigid else b.number("kxx", low=0.0, **_BEARING_K)
        kw = dict(kyy=inf if rigid else b.number("kyy", None, low=0.0, **_BEARING_K),
                  kxy=b.number("kxy", 0.0, **_BEARING_K), kyx=b.number("kyx", 0.0, **_BEARING_K),
                  cxx=b.number("cxx", 0.0, low=0.0, **_BEARING_C),
                  cyy=b.number("cyy", None, low=0.0, **_BEARING_C),
                  cxy=b.number("cxy", 0.0, **_BEARING_C), cyx=b.number("cyx", 0.0, **_BEARING_C),
                  clamp=_bool(b, "clamp", False))
        position = b.number("position", low=0.0, **_POSITION)
        b.check_unknown()
        try:
            bearings.append(Bearing(position, kxx, **kw))
        except ModelError as exc:  # cross-field checks (rigid with cross-coupling)
            b.fail(None, str(exc))
    values = dict(theory=r.string("theory", "timoshenko", options=THEORIES),
                  max_element_length=r.positive("max_element_length", None, unit="m",
                                                plausible=(1e-4, 100.0)),
                  rotary_inertia=_bool(r, "rotary_inertia", True),
                  name=r.string("name", Path(path).stem))
    r.check_unknown()
    try:
        rotor = Rotor(shaft=sections, disks=disks, bearings=bearings, **values)
    except ModelError as exc:  # cross-item checks (a disk beyond the shaft end)
        r.fail(None, str(exc))

    a = doc.table("analysis", {})
    rng = a.numbers("speed_range_rpm", [0.0, 10000.0], length=2, low=0.0, unit="rpm",
                    plausible=(1.0, 1e6))
    if rng[1] <= rng[0]:
        a.fail("speed_range_rpm", f"= {rng.tolist()} must be increasing")
    orders = a.numbers("orders", [1.0], low=0.0, strict_low=True, unit="1",
                       plausible=(1e-2, 100.0))
    n_speeds = a.integer("n_speeds", 41, minimum=2)
    n_modes = a.integer("n_modes", 4, minimum=1)
    a.check_unknown()
    unbalances = []
    for u in doc.tables("unbalance", []):
        unbalances.append((u.number("position", low=0.0, **_POSITION),
                           u.positive("magnitude", unit="kg*m", plausible=(1e-9, 10.0)),
                           math.radians(u.number("angle_deg", 0.0, unit="deg",
                                                 plausible=(1e-3, 360.0)))))
        u.check_unknown()
    doc.check_unknown()
    return RotorModel(rotor=rotor, speed_range_rpm=(float(rng[0]), float(rng[1])),
                      n_speeds=n_speeds, orders=tuple(float(o) for o in orders),
                      n_modes=n_modes, unbalances=tuple(unbalances), source=str(path))


def _journal_bearing(b: Table, jt: Table):
    """A ``[rotor.bearings.journal]`` entry: coefficients of the film at its design point."""
    from .journal import BEARING_MODELS, JournalBearing

    position = b.number("position", low=0.0, **_POSITION)
    b.check_unknown(["journal"])
    kw = dict(diameter=jt.positive("diameter", **_DIAMETER),
              length=jt.positive("length", unit="m", plausible=(1e-3, 5.0)),
              radial_clearance=jt.positive("radial_clearance", unit="m",
                                           plausible=(1e-7, 1e-2)),
              viscosity=jt.positive("viscosity", unit="Pa*s", plausible=(1e-5, 10.0)),
              model=jt.string("model", "finite", options=BEARING_MODELS))
    load = jt.positive("load", unit="N", plausible=(1e-2, 1e8))
    speed = jt.positive("speed_rpm", unit="rpm", plausible=(1.0, 1e6))
    jt.check_unknown()
    try:
        co = JournalBearing(**kw).coefficients(load=(0.0, -load), omega=speed * math.pi / 30)
    except (ModelError, ValueError) as exc:
        jt.fail(None, str(exc))
    return co.bearing(position)
