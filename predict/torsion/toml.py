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
    cylinder = 1                           # the cylinder acting on this node (an array for
                                           # a V throw or a radial row on one crank pin)
    throw_inertia = 30.0                   # throw only: crank-train masses are added
    # inertia = 41.0                       # ... or the total inertia
    ratio = 1.0                            # speed relative to the crankshaft
    damping = 0.0                          # absolute viscous, N·m·s/rad

    [[shaftline.shaft]]
    from = "cyl 1"
    to = "cyl 2"
    stiffness = 6.0e7                      # or length + diameter [+ bore], or segments,
                                           # or a [shaftline.shaft.throw] table (journal_*,
                                           # pin_*, web_*, crank_radius, method)
    # density = 7850 (kg/m³) or inertia = 1.2 (kg·m²): distributed inertia, split into
    # elements = N pieces (default 21)
    diameter = 0.30                        # for stress (with stiffness given)
    loss_factor = 0.02                     # hysteretic η (and/or damping, N·m·s/rad)

    [[shaftline.coupling]]  from, to, stiffness, damping, loss_factor
    [[shaftline.gear]]      driver, driven, ratio, mesh_stiffness (optional: rigid mesh)
    [[shaftline.ground]]    node, stiffness, damping
    [[shaftline.damper]]    type = "viscous" | "tuned" | "pendulum" | "friction", node, ...
                            (friction: ring_inertia, slip_torque and either
                            model = "harmonic-balance" — the default without a design point:
                            the non-linear slip/stick ring, forced response by harmonic
                            balance — or design_frequency + design_amplitude, the linearised
                            equivalent viscous damper)

    [excitation]                           # a bench without an engine (motor-driven):
    node = "motor"                         # where the exciting torque acts
    orders = [1, 2, 6]                     # excitation orders (per turn of the reference shaft)
    torque = [12.0, 4.0, 1.5]              # N·m amplitudes; leave out when unknown (criticals
                                           #   are then compared by speed, not amplitude)
    phase_deg = [0, 0, 0]                  # optional
    law = "constant"                       # or "speed_squared" (torque ∝ speed², e.g. a fan)
    reference_rpm = 1500.0                 # speed where the torques apply for speed_squared

    [limits]                               # rule data, see load_limits
    application = "propulsion"
    operating_range_rpm = [500, 750]
    [[limits.shafting]]  section, tensile_strength_mpa, design, kind, material  (IACS UR M68)
    [limits.crankshaft]  sections, continuous_mpa, transient_mpa, source  (engine maker)

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
    "friction": ("ring_inertia", "slip_torque"),
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
_STRESS_MPA = dict(unit="MPa", plausible=(0.1, 3000.0))
_DAMPER_UNITS = {
    "ring_inertia": _INERTIA, "damping": _DAMPING, "stiffness": _STIFFNESS, "loss_factor": _LOSS,
    "mass": dict(unit="kg", plausible=(1e-3, 1e4)),
    "pivot_radius": dict(unit="m", plausible=(1e-3, 3.0)),
    "length": dict(unit="m", plausible=(1e-4, 3.0)),
    "slip_torque": dict(unit="N*m", plausible=(1e-2, 1e7)),
    "design_frequency": dict(unit="rad/s", plausible=(0.1, 1e5)),   # "50 Hz" = 314 rad/s
    "design_amplitude": dict(unit="rad", plausible=(1e-7, 0.5)),
}


def load_limits(table, *, engine=None):
    """Build the stress limits from a ``[limits]`` :class:`~predict._toml.Table`.

    Two forms, which may be combined:

    * rule data (IACS UR M68 for shafting, the engine maker's figure for the crankshaft)::

        [limits]
        application = "propulsion"        # or "auxiliary" (constant-speed generating set)
        rated_speed_rpm = 720               # n_0 (default: the engine's rated_speed_rpm)
        operating_range_rpm = [500, 750]    # continuous operation
        misfire_operation = false           # intended to run on with one cylinder misfiring
        tachometer_tolerance_rpm = 5
        source = "IACS UR M68 Rev.2"        # rule edition named in the report

        [[limits.shafting]]                 # one per shaft section under M68
        section = "propeller shaft"
        tensile_strength_mpa = 600          # specified minimum σ_B
        design = "propeller key"            # C_K feature, see predict.torsion.rules.M68_CK
        kind = "propeller"                  # intermediate | propeller | thrust
        material = "carbon"                 # carbon | alloy
        # diameter = 0.34                   # m; default the section's diameter

        [limits.crankshaft]                 # outside M68: the engine maker's figure
        sections = ["cyl 1-cyl 2", ...]
        continuous_mpa = 40
        transient_mpa = 100
        source = "maker's document and revision"

        [limits.vibration]                  # vibration severity of the engine structure
        standard = "ISO 10816-6"            # default; or "ISO 10816-1"
        machine_class = 5                   # the contract's class (default: from the engine)
        rated_power_kw = 3000               # rated power the class is chosen by (default: the
                                            # indicated power from the engine's imep)
        mounting = "resilient"              # or "rigid" (default: resilient if the engine
                                            # model has [mounts], else unknown)
        # boundaries_mm_s = [11.2, 11.2, 17.8]   # own A/B, B/C, C/D boundaries, velocity rms
        source = "contract clause ..."

    * user-given curves (``speed_rpm``, ``continuous_mpa``, ``transient_mpa``, ``sections``,
      ``source``), held against the sections they name.

    Returns
    -------
    RuleLimits
        With ``curves`` (a :class:`StressLimits`) when user curves are given.
    """
    from .rules import MakerLimit, RuleLimits, SectionRule

    curves = None
    if "speed_rpm" in table or "continuous_mpa" in table or "transient_mpa" in table:
        speeds = table.numbers("speed_rpm", low=0.0, unit="rpm", plausible=_SPEED)
        cont = table.numbers("continuous_mpa", length=speeds.size, low=0.0, strict_low=True,
                             **_STRESS_MPA)
        trans = table.numbers("transient_mpa", length=speeds.size, low=0.0, strict_low=True,
                              **_STRESS_MPA)
        sections = table.raw("sections", [])
        if not isinstance(sections, list) or not all(isinstance(s, str) for s in sections):
            table.fail("sections", "must be an array of section names")
        try:
            curves = StressLimits(speeds, cont * 1e6, trans * 1e6, sections=sections,
                                  source=table.string("source", "user-given"))
        except ModelError as exc:
            raise ModelError(f"{table.where()} {exc}") from None
    application = table.string("application", "propulsion", options=("propulsion", "auxiliary"))
    rated = table.positive("rated_speed_rpm", None, unit="rpm", plausible=_SPEED)
    if rated is None and engine is not None:
        rated = getattr(engine, "rated_speed_rpm", None)
    op = table.numbers("operating_range_rpm", None, length=2, low=0.0, unit="rpm",
                       plausible=_SPEED)
    if op is not None and not op[0] < op[1]:
        table.fail("operating_range_rpm", f"= {op.tolist()!r} must be [low, high] with low < high")
    misfire = table.raw("misfire_operation", False)
    if not isinstance(misfire, bool):
        table.fail("misfire_operation", f"= {misfire!r} must be true or false")
    tol = table.number("tachometer_tolerance_rpm", 0.0, low=0.0, unit="rpm",
                       plausible=(1e-3, 1e3))
    source = table.string("source", None) if curves is None else None
    shafting = []
    for t in table.tables("shafting", []):
        kw = dict(section=t.string("section"),
                  tensile_strength=t.positive("tensile_strength_mpa", unit="MPa",
                                              plausible=(100.0, 3000.0)) * 1e6,
                  design=t.string("design", "integral flange",
                                  options=list(_m68_ck())),
                  material=t.string("material", "carbon", options=("carbon", "alloy")),
                  kind=t.string("kind", "intermediate",
                                options=("intermediate", "propeller", "thrust")),
                  diameter=t.positive("diameter", None, **_DIAMETER))
        t.check_unknown()
        shafting.append(SectionRule(**kw))
    crank = None
    ct = table.table("crankshaft", None)
    if ct is not None:
        secs = ct.raw("sections")
        if not isinstance(secs, list) or not secs or not all(isinstance(s, str) for s in secs):
            ct.fail("sections", "must be a non-empty array of section names")
        c = ct.positive("continuous_mpa", **_STRESS_MPA)
        tr = ct.positive("transient_mpa", **_STRESS_MPA)
        if tr < c:
            ct.fail("transient_mpa", f"= {tr:g} must be >= continuous_mpa = {c:g}")
        crank = MakerLimit(tuple(secs), c * 1e6, tr * 1e6,
                           source=ct.string("source", "engine maker's figure"))
        ct.check_unknown()
    vibration = None
    vt = table.table("vibration", None)
    if vt is not None:
        vibration = {"standard": vt.string("standard", "ISO 10816-6",
                                           options=("ISO 10816-6", "ISO 10816-1")),
                     "machine_class": vt.raw("machine_class", None),
                     "boundaries_mm_s": vt.numbers("boundaries_mm_s", None, length=3, low=0.0,
                                                   strict_low=True, unit="mm/s",
                                                   plausible=(0.01, 1000.0)),
                     "rated_power_kw": vt.positive("rated_power_kw", None, unit="kW",
                                                   plausible=(0.1, 2e5)),
                     "mounting": vt.string("mounting", None, options=("rigid", "resilient")),
                     "source": vt.string("source", "model [limits.vibration]")}
        mc = vibration["machine_class"]
        if mc is not None and not isinstance(mc, (int, str)):
            vt.fail("machine_class", f"= {mc!r} must be a class name (1-7, or I-IV)")
        b = vibration["boundaries_mm_s"]
        if b is not None and not (b[0] <= b[1] < b[2]):
            vt.fail("boundaries_mm_s", f"= {b.tolist()!r} must ascend (A/B, B/C, C/D, mm/s)")
        vt.check_unknown()
    table.check_unknown()
    extra = {} if source is None else {"source": source}
    return RuleLimits(application=application, rated_speed_rpm=rated,
                      operating_range_rpm=None if op is None else (float(op[0]), float(op[1])),
                      shafting=tuple(shafting), crankshaft=crank, misfire_operation=misfire,
                      tachometer_tolerance_rpm=tol, curves=curves, vibration=vibration, **extra)


def _complete_limits(limits, system, table):
    """Check the sections named in ``[limits]`` exist; give M68 sections the model's diameter."""
    import dataclasses

    import numpy as np

    names = list(system.edge_names)
    for name in limits.sections:
        if name not in names:
            table.fail("sections" if limits.curves is not None and name in
                       limits.curves.sections else "shafting",
                       f"names section {name!r}, which is not a section of the shaft line "
                       f"(sections: {', '.join(names)})")
    rules = []
    for r in limits.shafting:
        if r.diameter is None:
            d = float(system.section_diameters[names.index(r.section), 0])
            if not np.isfinite(d):
                table.fail("shafting", f"section {r.section!r} has no diameter in the model: "
                                       "give diameter (m) in its [[limits.shafting]] entry")
            r = dataclasses.replace(r, diameter=d)
        rules.append(r)
    return dataclasses.replace(limits, shafting=tuple(rules))


def _m68_ck():
    from .rules import M68_CK

    return M68_CK


def from_toml(path):
    """Load a shaft line (and its engine) from TOML into a :class:`TorsionalSystem`.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    TorsionalSystem
        With ``engine`` attached (when named), ``limits`` (when a ``[limits]`` table exists)
        and ``operating`` attributes ``speed_range_rpm``, ``imep``, ``load_law`` ("constant" or
        "propeller": how the run's gas load follows speed, so measured amplitudes can be judged
        against the prediction) and ``load_reference_rpm`` (where ``imep`` applies on the
        propeller law; default the engine's rated speed) in ``system.operating``.

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
    load_law = sl.string("load_law", None, options=("constant", "propeller"))
    load_reference = sl.positive("load_reference_rpm", None, unit="rpm", plausible=_SPEED)

    def wrap(table, func, *args, **kwargs):
        try:
            return func(*args, **kwargs)
        except ModelError as exc:
            raise ModelError(f"{table.where()}: {exc}") from None

    for t in sl.tables("mass", []):
        cyl = t.raw("cylinder", None)
        if isinstance(cyl, list):
            if not cyl or not all(isinstance(c, int) and not isinstance(c, bool) and c >= 1
                                  for c in cyl):
                t.fail("cylinder", f"= {cyl!r} must be a cylinder number or an array of them")
        else:
            cyl = t.integer("cylinder", None, minimum=1)
        kw = dict(ratio=t.number("ratio", 1.0, **_RATIO),
                  damping=t.number("damping", 0.0, low=0.0, **_DAMPING), cylinder=cyl)
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
                  name=t.string("name", None),
                  density=t.positive("density", None, unit="kg/m^3", plausible=(300.0, 25000.0)),
                  inertia=t.positive("inertia", None, **_INERTIA),
                  elements=t.integer("elements", None, minimum=1))
        tt = t.table("throw", None)
        if tt is not None:
            from .throws import THROW_METHODS, UNAVAILABLE_THROW_METHODS, CrankThrow

            # tuplin/bicera pass here so that throw_stiffness says why they are unavailable
            kw["throw_method"] = tt.string("method", "wilson", options=(
                *THROW_METHODS, *UNAVAILABLE_THROW_METHODS))
            dims = {key: tt.positive(key, **_DIAMETER) for key in (
                "journal_diameter", "journal_length", "pin_diameter", "pin_length",
                "web_thickness", "web_width", "crank_radius")}
            dims.update(journal_bore=tt.number("journal_bore", 0.0, low=0.0, **_DIAMETER),
                        pin_bore=tt.number("pin_bore", 0.0, low=0.0, **_DIAMETER))
            tt.check_unknown()
            kw["throw"] = wrap(tt, CrankThrow, **dims)
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
        if kind == "friction":
            kw["design_frequency"] = t.positive("design_frequency", None,
                                                  **_DAMPER_UNITS["design_frequency"])
            kw["design_amplitude"] = t.positive("design_amplitude", None,
                                                  **_DAMPER_UNITS["design_amplitude"])
            lin = kw["design_frequency"] is not None or kw["design_amplitude"] is not None
            kw["model"] = t.string("model", "linearised" if lin else "harmonic-balance",
                                   options=("harmonic-balance", "linearised"))
            if kw["model"] == "linearised" and not (kw["design_frequency"] and
                                                    kw["design_amplitude"]):
                t.fail("model", '= "linearised" needs design_frequency (rad/s) and '
                                "design_amplitude (rad)")
            if kw["model"] == "harmonic-balance" and lin:
                t.fail("design_frequency" if kw["design_frequency"] else "design_amplitude",
                       'belongs to model = "linearised"; the harmonic-balance friction '
                       "damper has no design point")
        t.check_unknown()
        func = {"viscous": _dampers.add_viscous_damper, "tuned": _dampers.add_tuned_damper,
                "pendulum": _dampers.add_pendulum_absorber,
                "friction": _dampers.add_friction_damper}[kind]
        wrap(t, func, line, node, name=name, **kw)
    sl.check_unknown(["description"])
    limits = None
    lt = doc.table("limits", None)
    if lt is not None:
        limits = load_limits(lt, engine=engine)
    excitation = _excitation(doc.table("excitation", None), line)
    doc.check_unknown(["description", "engine"])
    system = wrap(sl, line.build, limits=limits)
    if limits is not None:
        system = system.replace(limits=_complete_limits(limits, system, lt))
    return system.replace(operating=dict(
        speed_range_rpm=None if speed_range is None else tuple(speed_range), imep=imep,
        load_law=load_law, load_reference_rpm=load_reference,
        source=str(path), excitation=excitation))


def _excitation(t, line):
    """The ``[excitation]`` table of a bench without an engine, as a plain dict (or None)."""
    if t is None:
        return None
    nodes = list(getattr(line, "_alias", {})) or None
    node = t.string("node", None, options=nodes) if nodes else t.string("node", None)
    orders = t.numbers("orders", low=0.0, strict_low=True, unit="1", plausible=(1e-2, 100.0))
    torque = t.numbers("torque", None, length=orders.size, low=0.0, unit="N*m",
                       plausible=(1e-4, 1e8))
    phase = t.numbers("phase_deg", None, length=orders.size, unit="deg",
                      plausible=(1e-3, 720.0))
    law = t.string("law", "constant", options=["constant", "speed_squared"])
    ref = t.positive("reference_rpm", None, unit="rpm", plausible=_SPEED)
    if law == "speed_squared" and ref is None:
        t.fail("reference_rpm", "is needed for law = 'speed_squared' (the speed at which the "
                                "torques apply)")
    if len(set(orders.tolist())) != orders.size:
        t.fail("orders", f"= {orders.tolist()} repeats an order")
    t.check_unknown(["description"])
    return {"node": node, "orders": orders.tolist(),
            "torque": None if torque is None else torque.tolist(),
            "phase_deg": None if phase is None else phase.tolist(), "law": law,
            "reference_rpm": ref, "source": t.where()}
