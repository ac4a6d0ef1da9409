"""Shaft lines described in TOML beside the engine model.

Layout (SI unless the key names another unit; values at each part's own speed)::

    [shaftline]
    name = "6L32 + gearbox + CPP"
    engine = "../engines/marine_6l.toml"   # relative to this file (or an inline [engine])
    shear_modulus = 80e9                   # default G for shafts, Pa
    speed_range_rpm = [200, 800]           # for critical speeds / forced response
    imep = 2.2e6                           # Pa, load of the default excitation (optional)

    [[shaftline.mass]]                     # disks, flywheel, propeller, crank throws
    name = "cyl 1"
    cylinder = 1                           # the cylinder acting on this node
    throw_inertia = 30.0                   # throw only: crank-train masses are added
    # inertia = 41.0                       # ... or the total inertia
    ratio = 1.0                            # speed relative to the crankshaft
    damping = 0.0                          # absolute viscous, N·m·s/rad

    [[shaftline.shaft]]
    from = "cyl 1"
    to = "cyl 2"
    stiffness = 6.0e7                      # or length + diameter [+ bore], or segments
    diameter = 0.30                        # for stress (with stiffness given)
    loss_factor = 0.02                     # hysteretic η (and/or damping, N·m·s/rad)

    [[shaftline.coupling]]  from, to, stiffness, damping, loss_factor
    [[shaftline.gear]]      driver, driven, ratio, mesh_stiffness (optional: rigid mesh)
    [[shaftline.ground]]    node, stiffness, damping
    [[shaftline.damper]]    type = "viscous" | "tuned" | "pendulum" | "friction", node, ...

    [limits]                               # user-given (e.g. from a classification rule)
    speed_rpm = [0, 800]
    continuous_mpa = [40, 40]
    transient_mpa = [100, 100]
    sections = ["cyl 6-flywheel"]          # optional, default every section with a diameter
    source = "..."

Any number may be written with its unit as a string, converted by pint
(``diameter = "300 mm"``, ``shear_modulus = "81 GPa"``, ``stiffness = "60 MN*m/rad"``); a
value far outside the key's plausible range warns with the likely slip.
"""

from __future__ import annotations

from pathlib import Path

from .._toml import load_toml
from ..errors import ModelError
from . import dampers as _dampers
from .elements import ShaftLine
from .stress import StressLimits

__all__ = ["from_toml", "load_limits"]

_DAMPER_KEYS = {
    "viscous": ("ring_inertia", "damping"),
    "tuned": ("ring_inertia", "stiffness", "damping", "loss_factor"),
    "pendulum": ("mass", "pivot_radius", "length", "damping"),
    "friction": ("ring_inertia", "slip_torque", "design_frequency", "design_amplitude"),
}


# unit and plausible range of the shaft-line keys (plain numbers are in these units)
_SPEED = (1.0, 1e5)
_SHEAR = dict(unit="Pa", plausible=(1e9, 3e11))          # shafts: composites to steel
_INERTIA = dict(unit="kg*m^2", plausible=(1e-7, 1e7))    # model engine throw to ship propeller
_STIFFNESS = dict(unit="N*m/rad", plausible=(10.0, 1e12))
_DAMPING = dict(unit="N*m*s/rad", plausible=(1e-6, 1e9))
_DIAMETER = dict(unit="m", plausible=(1e-3, 3.0))
_RATIO = dict(unit="1", plausible=(1e-3, 1e3))
_LOSS = dict(unit="1", plausible=(1e-5, 1.0))
_DAMPER_UNITS = {
    "ring_inertia": _INERTIA, "damping": _DAMPING, "stiffness": _STIFFNESS, "loss_factor": _LOSS,
    "mass": dict(unit="kg", plausible=(1e-3, 1e4)),
    "pivot_radius": dict(unit="m", plausible=(1e-3, 3.0)),
    "length": dict(unit="m", plausible=(1e-4, 3.0)),
    "slip_torque": dict(unit="N*m", plausible=(1e-2, 1e7)),
    "design_frequency": dict(unit="rad/s", plausible=(0.1, 1e5)),   # "50 Hz" = 314 rad/s
    "design_amplitude": dict(unit="rad", plausible=(1e-7, 0.5)),
}


def load_limits(table) -> StressLimits:
    """Build :class:`StressLimits` from a ``[limits]`` :class:`~predict._toml.Table`."""
    speeds = table.numbers("speed_rpm", low=0.0, unit="rpm", plausible=_SPEED)
    cont = table.numbers("continuous_mpa", length=speeds.size, low=0.0, strict_low=True,
                         unit="MPa", plausible=(0.1, 3000.0))
    trans = table.numbers("transient_mpa", length=speeds.size, low=0.0, strict_low=True,
                          unit="MPa", plausible=(0.1, 3000.0))
    sections = table.raw("sections", [])
    if not isinstance(sections, list) or not all(isinstance(s, str) for s in sections):
        table.fail("sections", "must be an array of section names")
    source = table.string("source", "user-given")
    table.check_unknown()
    try:
        return StressLimits(speeds, cont * 1e6, trans * 1e6, sections=sections, source=source)
    except ModelError as exc:
        raise ModelError(f"{table.where()} {exc}") from None


def from_toml(path):
    """Load a shaft line (and its engine) from TOML into a :class:`TorsionalSystem`.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    TorsionalSystem
        With ``engine`` attached (when named), ``limits`` (when a ``[limits]`` table exists)
        and ``operating`` attributes ``speed_range_rpm`` and ``imep`` in ``system.operating``.

    Raises
    ------
    ModelError
        Naming the file and dotted key, for missing, invalid or unknown keys.

    Examples
    --------
    >>> from pathlib import Path
    >>> import crankbench.predict.torsion as pt
    >>> p = Path(__file__).resolve().parents[2] / "sample_data/shaftlines/two_rotor.toml"
    >>> s = pt.from_toml(p)
    >>> print(s.natural_frequencies().round(3))
    [ 0.    15.915]
    """
    path = Path(path)
    doc = load_toml(path)
    sl = doc.table("shaftline", None)
    if sl is None:
        raise ModelError(f"{path}: has no [shaftline] table")
    engine = None
    eng_ref = sl.string("engine", None)
    from ..engine import Engine

    if eng_ref is not None:
        eng_path = (path.parent / eng_ref).resolve()
        if not eng_path.exists():
            sl.fail("engine", f"= {eng_ref!r}: engine file {eng_path} does not exist")
        engine = Engine.from_toml(eng_path)
    elif "engine" in doc:
        engine = Engine.from_toml(path)
    doc.raw("engine", None)
    line = ShaftLine(sl.string("name", path.stem), engine=engine,
                     shear_modulus=sl.positive("shear_modulus", 80.0e9, **_SHEAR))
    speed_range = sl.numbers("speed_range_rpm", None, length=2, low=0.0, unit="rpm",
                             plausible=_SPEED)
    imep = sl.positive("imep", None, unit="Pa", plausible=(1e4, 1e7))

    def wrap(table, func, *args, **kwargs):
        try:
            return func(*args, **kwargs)
        except ModelError as exc:
            raise ModelError(f"{table.where()}: {exc}") from None

    for t in sl.tables("mass", []):
        kw = dict(ratio=t.number("ratio", 1.0, **_RATIO),
                  damping=t.number("damping", 0.0, low=0.0, **_DAMPING),
                  cylinder=t.integer("cylinder", None, minimum=1))
        if "throw_inertia" in t:
            kw["throw_inertia"] = t.number("throw_inertia", low=0.0, **_INERTIA)
            inertia = None
        else:
            inertia = t.positive("inertia", **_INERTIA)
        name = t.string("name")
        t.check_unknown()
        wrap(t, line.add_mass, name, inertia, **kw)
    for t in sl.tables("gear", []):
        kw = dict(ratio=t.positive("ratio", **_RATIO),
                  mesh_stiffness=t.positive("mesh_stiffness", None, **_STIFFNESS))
        a, b = t.string("driver"), t.string("driven")
        t.check_unknown(["name"])
        wrap(t, line.add_gear, a, b, name=t.data.get("name"), **kw)
    for t in sl.tables("shaft", []):
        segs = t.raw("segments", None)
        if segs is not None and not (isinstance(segs, list) and all(
                isinstance(s, list) and 2 <= len(s) <= 3 for s in segs)):
            t.fail("segments", "must be an array of [length, diameter] or "
                               "[length, diameter, bore] arrays (m)")
        if segs is not None:
            segs = [[t.quantity(f"segments[{i}][{j}]", v, unit="m") for j, v in enumerate(seg)]
                    for i, seg in enumerate(segs)]
        kw = dict(stiffness=t.positive("stiffness", None, **_STIFFNESS),
                  length=t.positive("length", None, unit="m", plausible=(1e-3, 100.0)),
                  diameter=t.positive("diameter", None, **_DIAMETER),
                  bore=t.number("bore", 0.0, low=0.0, **_DIAMETER),
                  segments=segs, shear_modulus=t.positive("shear_modulus", None, **_SHEAR),
                  damping=t.number("damping", 0.0, low=0.0, **_DAMPING),
                  loss_factor=t.number("loss_factor", 0.0, low=0.0, **_LOSS),
                  name=t.string("name", None))
        a, b = t.string("from"), t.string("to")
        t.check_unknown()
        wrap(t, line.add_shaft, a, b, **kw)
    for t in sl.tables("coupling", []):
        kw = dict(stiffness=t.positive("stiffness", **_STIFFNESS),
                  damping=t.number("damping", 0.0, low=0.0, **_DAMPING),
                  loss_factor=t.number("loss_factor", 0.0, low=0.0, **_LOSS),
                  name=t.string("name", None))
        a, b = t.string("from"), t.string("to")
        t.check_unknown()
        wrap(t, line.add_coupling, a, b, **kw)
    for t in sl.tables("ground", []):
        kw = dict(stiffness=t.positive("stiffness", **_STIFFNESS),
                  damping=t.number("damping", 0.0, low=0.0, **_DAMPING),
                  name=t.string("name", None))
        node = t.string("node")
        t.check_unknown()
        wrap(t, line.add_ground, node, **kw)
    for t in sl.tables("damper", []):
        kind = t.string("type", options=list(_DAMPER_KEYS))
        node = t.string("node")
        name = t.string("name", None)
        kw = {}
        for key in _DAMPER_KEYS[kind]:
            optional = key in ("damping", "loss_factor") and kind != "viscous"
            if optional:
                kw[key] = t.number(key, 0.0, low=0.0, **_DAMPER_UNITS[key])
            else:
                kw[key] = t.positive(key, **_DAMPER_UNITS[key])
        t.check_unknown()
        func = {"viscous": _dampers.add_viscous_damper, "tuned": _dampers.add_tuned_damper,
                "pendulum": _dampers.add_pendulum_absorber,
                "friction": _dampers.add_friction_damper}[kind]
        wrap(t, func, line, node, name=name, **kw)
    sl.check_unknown(["description"])
    limits = None
    lt = doc.table("limits", None)
    if lt is not None:
        limits = load_limits(lt)
    doc.check_unknown(["description", "engine"])
    system = wrap(sl, line.build, limits=limits)
    return system.replace(operating=dict(
        speed_range_rpm=None if speed_range is None else tuple(speed_range), imep=imep,
        source=str(path)))
