"""Scenes of the synthetic test bench: engine, shaft line, mounts, operating profile, sensors.

A scene is read from TOML (paths relative to the scene file)::

    [scene]
    name = "6L32 run-up"
    engine = "../engines/marine_6l.toml"      # [engine] (and [mounts], if vibrographs are used)
    shaftline = "../shaftlines/marine_6l.toml" # optional: torsional channels need it
    mounts = "../engines/marine_6l.toml"      # optional, default: the engine file
    seed = 1
    max_order = 12.0
    start_angle_deg = 0.0                      # crank angle of cyl 1 from firing TDC at t = 0
    truth_rate = 20.0                          # Hz, time resolution of the ground truth

    [profile]                                  # steady | runup | coastdown | exponential | table
    kind = "runup"
    start_rpm = 200.0
    end_rpm = 760.0
    duration = 40.0
    hold_start = 1.0
    hold_end = 1.0

    [load]
    imep = 2.0e6                               # Pa, at rated speed for law = "propeller"
    law = "propeller"                          # constant | propeller (imep ~ speed^2)

    [imperfections]                            # defaults for every sensor
    jitter_s = 2e-8

    [[imbalance]]                              # optional: masses added to the crankshaft of
    mass = 0.02                                # the synthesized engine only (a known test
    radius = 0.05                              # imbalance: kg, m from the axis, deg ahead of
    angle_deg = 90.0                           # throw 1, m along the crankshaft)
    position = 0.1

    [[sensor]]
    kind = "torsiograph"                       # torsiograph | encoder | tacho | vibrograph |
    name = "tv_free_end"                       # pressure | speed
    node = "damper housing"
    quantity = "angle"                         # angle | angular_velocity
    sample_rate = 2000.0

Sensor keys by kind: *torsiograph* ``node``, ``quantity``, ``sample_rate``; *encoder* and
*tacho* ``node``, ``pulses_per_rev``, ``missing_teeth``, ``tdc_offset_deg`` and, for a tacho,
``output = "pulses" | "analogue"`` (``sample_rate`` for the analogue pick-up voltage; its
``shape = "sine"`` (magnetic, default) or ``"square"`` (Hall/optical, 0-5 V), ``runt_teeth``
(tooth numbers, 0 the first after the gap) reaching only ``runt_level`` of the swing (default
0.11), ``ringing`` (damping ratio of the pick-up chain, 0 = none) at ``ringing_hz``, and for a
once-per-revolution mark ``mark_width_deg``, e.g. a TDC mark one or two samples wide);
*vibrograph* ``point = [x, y, z]`` or ``mount = "name"``, ``direction`` (x/y/z),
``quantity`` (acceleration/velocity/displacement), ``sample_rate`` (the channel carries its
``position`` and ``direction`` attrs, docs/DESIGN.md "Vibrograph sensors"); *pressure* ``cylinder``,
``sample_rate`` and the transducer errors of :mod:`.pressure` (``thermal_shock``,
``thermal_shock_deg``, ``tdc_error_deg``, ``cycle_variation``); *speed* ``sample_rate``. Torsiograph and vibrograph sensors may give a
seismic instrument, ``instrument_frequency`` (Hz) and ``instrument_damping`` (fraction of
critical, default 0.65): the channel is then the instrument's reading
(:mod:`measure.instruments`: a seismic torsiograph/vibrograph for angles and displacements, a
velocity pick-up, an accelerometer), while the truth stays the true motion. Any sensor may
override the imperfection keys.
Unknown keys are errors (with a did-you-mean) naming the file and key.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from crankbench.predict._toml import Table, load_toml
from crankbench.predict.errors import ConfigError

from .imperfections import _KEYS as _IMPERFECTION_KEYS
from .imperfections import Imperfections
from .profile import SpeedProfile, exponential_coastdown, from_table, ramp, steady

__all__ = ["Scene", "SensorSpec", "LoadSpec", "SENSOR_KINDS"]

#: sensor kinds and the keys each accepts (besides kind, name and the imperfection keys)
SENSOR_KINDS = {
    "torsiograph": ("node", "quantity", "sample_rate", "location", "instrument_frequency",
                    "instrument_damping"),
    "encoder": ("node", "pulses_per_rev", "missing_teeth", "tdc_offset_deg", "location"),
    "tacho": ("node", "pulses_per_rev", "missing_teeth", "tdc_offset_deg", "output",
              "sample_rate", "location", "shape", "runt_teeth", "runt_level", "ringing",
              "ringing_hz", "mark_width_deg"),
    "vibrograph": ("point", "mount", "direction", "quantity", "sample_rate", "location",
                   "instrument_frequency", "instrument_damping"),
    "pressure": ("cylinder", "sample_rate", "location", "thermal_shock", "thermal_shock_deg",
                 "tdc_error_deg", "cycle_variation"),
    "speed": ("sample_rate", "location"),
}



@dataclass(frozen=True)
class SensorSpec:
    """One sensor of a scene.

    Attributes
    ----------
    name : str
        Channel name in the record.
    kind : str
        One of :data:`SENSOR_KINDS`.
    params : dict
        Kind-specific settings (SI; angles in keys named ``_deg``).
    imperfections : Imperfections
    """

    name: str
    kind: str
    params: dict
    imperfections: Imperfections = field(default_factory=Imperfections)

    @property
    def sample_rate(self):
        """Sample rate, Hz (None for pulse trains)."""
        return self.params.get("sample_rate")


@dataclass(frozen=True)
class LoadSpec:
    """Engine load along the run.

    Attributes
    ----------
    imep : float or None
        Mean indicated pressure, Pa, at ``reference_rpm`` (None: the engine's combustion data).
    law : str
        "constant" or "propeller" (imep proportional to speed squared).
    reference_rpm : float or None
        Speed at which ``imep`` applies for the propeller law, rpm.
    """

    imep: float | None = None
    law: str = "constant"
    reference_rpm: float | None = None

    def scale(self, speed_rpm):
        """Gas-load factor relative to ``imep`` at each speed (1 for a constant load)."""
        speed_rpm = np.asarray(speed_rpm, float)
        if self.law == "constant":
            return np.ones_like(speed_rpm)
        return (speed_rpm / self.reference_rpm) ** 2


@dataclass(frozen=True)
class Scene:
    """A synthetic test-bench scene (see the module docstring for the TOML form).

    Attributes
    ----------
    name : str
    engine : predict.engine.Engine
    shaftline : predict.torsion.TorsionalSystem or None
    mounts : predict.mounts.MountedEngine or None
    profile : SpeedProfile
    load : LoadSpec
    sensors : tuple of SensorSpec
    seed : int
    max_order : float
    start_angle_deg : float
    truth_rate : float
        Hz.
    balance_masses : tuple of predict.balance.Counterweight
        Masses fixed to the crankshaft by the engine model (``[[balance.mass]]``).
    imbalance : tuple of predict.balance.Counterweight
        Masses the scene adds to the synthesized engine only (``[[imbalance]]``): a known
        imbalance the model does not contain.
    source : str
        Scene file (or "python").
    settings : dict
        The scene as read (for the truth's record of parameters).
    """

    name: str
    engine: object
    shaftline: object
    mounts: object
    profile: SpeedProfile
    load: LoadSpec
    sensors: tuple
    seed: int = 0
    max_order: float = 12.0
    start_angle_deg: float = 0.0
    truth_rate: float = 20.0
    balance_masses: tuple = ()
    imbalance: tuple = ()
    source: str = "python"
    settings: dict = field(default_factory=dict)

    def __post_init__(self):
        if not self.sensors:
            raise ConfigError(f"scene {self.name!r} has no sensors; add [[sensor]] tables")
        names = [s.name for s in self.sensors]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ConfigError(f"scene {self.name!r}: sensor names must be unique, repeated: "
                              f"{', '.join(dup)}")
        needs_shaft = [s.name for s in self.sensors if s.kind in ("torsiograph", "encoder",
                                                                    "tacho")]
        if needs_shaft and self.shaftline is None:
            raise ConfigError(f"scene {self.name!r}: sensors {', '.join(needs_shaft)} need a "
                              "shaft line ([scene] shaftline = 'path.toml')")
        needs_mounts = [s.name for s in self.sensors if s.kind == "vibrograph"]
        if needs_mounts and self.mounts is None:
            raise ConfigError(f"scene {self.name!r}: vibrograph sensors {', '.join(needs_mounts)}"
                              " need a mount model ([mounts] in the engine file or "
                              "[scene] mounts = 'path.toml')")
        if self.shaftline is not None:
            cyl = len(self.shaftline.cylinder_nodes)
            if cyl and cyl != self.engine.n_cylinders:
                raise ConfigError(f"scene {self.name!r}: the shaft line has {cyl} cylinder "
                                  f"nodes but the engine {self.engine.name!r} has "
                                  f"{self.engine.n_cylinders} cylinders; use the engine the "
                                  "shaft line was built for")
            nodes = self.shaftline.node_names
            for s in self.sensors:
                node = s.params.get("node")
                if node is not None and node not in nodes:
                    from crankbench.predict._validate import suggest

                    raise ConfigError(f"scene {self.name!r}: sensor {s.name!r} node={node!r} is "
                                      f"not a shaft-line node{suggest(node, nodes)}; nodes: "
                                      f"{', '.join(nodes)}")
        self._check_size()

    def _check_size(self):
        """Refuse a scene whose arrays cannot fit in memory, naming the key that sets the
        largest of them (before anything is synthesized)."""
        from crankbench.predict._memory import check_allocation

        duration = self.profile.duration
        revolutions = float(self.profile.angle(duration)) / (2.0 * np.pi)
        parts = []   # (bytes, what)
        for s in self.sensors:
            fs = s.params.get("sample_rate")
            if fs:
                # time axis, signal, noise and the written copy: 4 float64 per sample
                n = duration * float(fs)
                parts.append((32.0 * n, f"sensor {s.name!r} sample_rate = {float(fs):g} Hz over "
                                        f"{duration:g} s ({n:.3g} samples)"))
            ppr = s.params.get("pulses_per_rev")
            if ppr:
                n = revolutions * int(ppr)
                parts.append((24.0 * n, f"sensor {s.name!r} pulses_per_rev = {int(ppr)} over "
                                        f"{revolutions:.4g} revolutions ({n:.3g} edges)"))
        n_truth = duration * self.truth_rate
        parts.append((16.0 * n_truth * len(self.sensors) * 2 * self.max_order,
                      f"truth_rate = {self.truth_rate:g} Hz × max_order = {self.max_order:g}"))
        f_max = self.max_order * float(self.profile.speed_rpm.max()) / 60.0
        rates = [float(s.sample_rate) for s in self.sensors
                 if s.kind == "torsiograph" and s.sample_rate]
        if any(s.kind in ("torsiograph", "encoder", "tacho") for s in self.sensors):
            n_t = duration * max(rates + [8.0 * f_max, 1000.0])
            n_nodes = self.shaftline.n_nodes if self.shaftline is not None else 1
            parts.append((8.0 * n_t * (2 * n_nodes + 8),
                          f"torsional integration at {max(rates + [8.0 * f_max, 1000.0]):g} Hz "
                          f"over {duration:g} s"))
        total = sum(b for b, _ in parts)
        _, biggest = max(parts)
        check_allocation(total, error=ConfigError,
                         what=f"scene {self.name!r}: {biggest}",
                         hint="lower the sample rate or the duration ([profile] duration)")

    # ------------------------------------------------------------------------------ TOML
    @classmethod
    def from_toml(cls, path):
        """Read a scene file.

        Raises
        ------
        ConfigError
            Naming the file and the dotted key, for a missing, invalid or unknown key.
        FileNotFoundError
            If the scene or a model file it names does not exist.

        Examples
        --------
        >>> from pathlib import Path
        >>> root = Path(__file__).resolve().parents[2]
        >>> scene = Scene.from_toml(root / "sample_data/scenes/i4_runup.toml")
        >>> scene.profile.kind, len(scene.sensors) > 0
        ('runup', True)
        """
        path = Path(path)
        doc = load_toml(path, error=ConfigError)
        st = doc.table("scene", None)
        if st is None:
            raise ConfigError(f"{path}: has no [scene] table")
        engine_path = _model_path(path, st, "engine", required=True)
        from crankbench.predict.engine import Engine

        engine = Engine.from_toml(engine_path)
        shaftline = None
        shaft_path = _model_path(path, st, "shaftline", required=False)
        if shaft_path is not None:
            from crankbench.predict.torsion import from_toml as torsion_from_toml

            shaftline = torsion_from_toml(shaft_path)
        mounts = None
        mounts_path = _model_path(path, st, "mounts", required=False)
        if mounts_path is None and "mounts" in load_toml(engine_path).data:
            mounts_path = engine_path
        if mounts_path is not None:
            from crankbench.predict.mounts import MountedEngine

            mounts = MountedEngine.from_toml(mounts_path)
        name = st.string("name", path.stem)
        seed = st.integer("seed", 0, minimum=0)
        max_order = st.positive("max_order", 12.0, unit="1", plausible=(0.5, 200.0))
        start_angle = st.number("start_angle_deg", 0.0, unit="deg", plausible=(1e-3, 720.0))
        truth_rate = st.positive("truth_rate", 20.0, unit="Hz", plausible=(0.1, 1e4))
        st.check_unknown(["description"])
        profile = _profile(doc.table("profile", None), path)
        load = _load(doc.table("load", None), engine)
        defaults = Imperfections()
        it = doc.table("imperfections", None)
        if it is not None:
            defaults = Imperfections.from_table(it)
            it.check_unknown()
        sensors = tuple(_sensor(t, defaults) for t in doc.tables("sensor", []))
        from crankbench.predict.balance import Counterweight
        from crankbench.predict.balance_tolerance import BalanceSpec

        imbalance = []
        for t in doc.tables("imbalance", []):
            imbalance.append(Counterweight(
                mass_radius=(t.number("mass", low=0.0, unit="kg", plausible=(1e-6, 1e4))
                             * t.number("radius", low=0.0, unit="m", plausible=(1e-3, 5.0))),
                angle_deg=t.number("angle_deg", unit="deg", plausible=(1e-3, 360.0)),
                position=t.number("position", 0.0, unit="m", plausible=(1e-4, 100.0))))
            t.check_unknown(["description"])
        balance_masses = BalanceSpec.from_toml(engine_path).masses
        doc.check_unknown(["description"])
        settings = dict(doc.data)
        try:
            return cls(name=name, engine=engine, shaftline=shaftline, mounts=mounts,
                       profile=profile, load=load, sensors=sensors, seed=seed,
                       max_order=max_order, start_angle_deg=start_angle, truth_rate=truth_rate,
                       balance_masses=balance_masses, imbalance=tuple(imbalance),
                       source=str(path), settings=settings)
        except ConfigError as exc:  # whole-scene checks: say which file to fix
            raise ConfigError(f"{path}: {exc}") from None


# unit and plausible range of scene keys (plain numbers are in these units)
_RPM = dict(unit="rpm", plausible=(1.0, 1e5))
_S = dict(unit="s", plausible=(1e-3, 1e5))
_FS = dict(unit="Hz", plausible=(1.0, 1e7))


def _model_path(scene_path, table, key, *, required):
    value = table.string(key, ... if required else None)
    if value is None:
        return None
    p = (scene_path.parent / value).resolve()
    if not p.exists():
        raise FileNotFoundError(f"{scene_path}: scene.{key} = {value!r}: file {p} does not exist")
    return p


def _profile(t: Table | None, path) -> SpeedProfile:
    if t is None:
        raise ConfigError(f"{path}: has no [profile] table (steady, runup, coastdown, "
                          "exponential or table)")
    kind = t.string("kind", options=["steady", "runup", "coastdown", "exponential", "table"])
    try:
        if kind == "steady":
            prof = steady(t.positive("speed_rpm", **_RPM), duration=t.positive("duration", **_S))
        elif kind in ("runup", "coastdown"):
            start, end = t.positive("start_rpm", **_RPM), t.positive("end_rpm", **_RPM)
            if (kind == "runup") != (end > start):
                t.fail("end_rpm", f"= {end:g} must be {'above' if kind == 'runup' else 'below'} "
                                  f"start_rpm = {start:g} for kind = {kind!r}")
            prof = ramp(start, end, duration=t.positive("duration", **_S),
                        hold_start=t.number("hold_start", 0.0, low=0.0, **_S),
                        hold_end=t.number("hold_end", 0.0, low=0.0, **_S))
        elif kind == "exponential":
            prof = exponential_coastdown(t.positive("start_rpm", **_RPM),
                                         t.positive("end_rpm", **_RPM),
                                         time_constant=t.positive("time_constant", **_S),
                                         tolerance_rpm=t.positive("tolerance_rpm", 0.5,
                                                                  unit="rpm",
                                                                  plausible=(1e-3, 1e3)))
        else:
            prof = from_table(t.numbers("time", low=0.0, **_S),
                              t.numbers("speed_rpm", low=0.0, strict_low=True, **_RPM))
    except ConfigError as exc:
        if str(exc).startswith(str(path)):
            raise
        raise ConfigError(f"{t.where()}: {exc}") from None
    t.check_unknown(["description"])
    return prof


def _load(t: Table | None, engine) -> LoadSpec:
    if t is None:
        return LoadSpec()
    imep = t.positive("imep", None, unit="Pa", plausible=(1e4, 1e7))
    law = t.string("law", "constant", options=["constant", "propeller"])
    ref = t.positive("reference_rpm", None, **_RPM)
    if law == "propeller":
        ref = ref or engine.rated_speed_rpm
        if ref is None:
            t.fail("reference_rpm", "is needed for law = 'propeller' (the engine has no "
                                    "rated_speed_rpm)")
    t.check_unknown(["description"])
    return LoadSpec(imep=imep, law=law, reference_rpm=ref)


def _sensor(t: Table, defaults: Imperfections) -> SensorSpec:
    kind = t.string("kind", options=list(SENSOR_KINDS))
    name = t.string("name")
    if not name or not name.replace("_", "").isalnum():
        t.fail("name", f"= {name!r} must be letters, digits and underscores (a channel name)")
    p: dict = {}
    if kind in ("torsiograph", "encoder", "tacho"):
        p["node"] = t.string("node")
    if kind == "torsiograph":
        p["quantity"] = t.string("quantity", "angle", options=["angle", "angular_velocity"])
        p["sample_rate"] = t.positive("sample_rate", **_FS)
    if kind in ("encoder", "tacho"):
        p["pulses_per_rev"] = t.integer("pulses_per_rev", minimum=1)
        p["missing_teeth"] = t.integer("missing_teeth", 0, minimum=0)
        if p["missing_teeth"] and p["missing_teeth"] >= p["pulses_per_rev"] - 1:
            t.fail("missing_teeth", f"= {p['missing_teeth']} must be less than "
                                    f"pulses_per_rev - 1 = {p['pulses_per_rev'] - 1}")
        p["tdc_offset_deg"] = t.number("tdc_offset_deg", 0.0, unit="deg", plausible=(1e-3, 720.0))
    if kind == "tacho":
        p["output"] = t.string("output", "pulses", options=["pulses", "analogue"])
        if p["output"] == "analogue":
            p["sample_rate"] = t.positive("sample_rate", **_FS)
            p["shape"] = t.string("shape", "sine", options=["sine", "square"])
            p["runt_teeth"] = [int(k) for k in t.numbers("runt_teeth", [], unit="1")]
            for k in p["runt_teeth"]:
                if not 0 <= k < p["pulses_per_rev"] - p["missing_teeth"]:
                    t.fail("runt_teeth", f"tooth {k} is not on the wheel (teeth 0 .. "
                                         f"{p['pulses_per_rev'] - p['missing_teeth'] - 1}, 0 "
                                         "the first after the gap)")
            p["runt_level"] = t.number("runt_level", 0.11, low=0.0, high=1.0, unit="1",
                                         plausible=(1e-3, 1.0))
            p["ringing"] = t.number("ringing", 0.0, low=0.0, high=1.0, unit="1",
                                      plausible=(1e-4, 1.0))
            p["ringing_hz"] = t.positive("ringing_hz", p["sample_rate"] / 8.0, unit="Hz",
                                           plausible=(0.1, 1e7))
            if p["ringing"] and p["ringing_hz"] >= p["sample_rate"] / 2:
                t.fail("ringing_hz", f"= {p['ringing_hz']:g} must be below half the sample "
                                     "rate")
            p["mark_width_deg"] = t.positive("mark_width_deg", None, unit="deg",
                                               plausible=(1e-3, 90.0))
    if kind == "vibrograph":
        if ("point" in t) == ("mount" in t):
            t.fail("point", "give exactly one of point = [x, y, z] (m) or mount = 'name'")
        if "point" in t:
            p["point"] = t.numbers("point", length=3, unit="m", plausible=(1e-4, 100.0)).tolist()
        else:
            p["mount"] = t.string("mount")
        p["direction"] = t.string("direction", "z", options=["x", "y", "z"])
        p["quantity"] = t.string("quantity", "acceleration",
                                 options=["acceleration", "velocity", "displacement"])
        p["sample_rate"] = t.positive("sample_rate", **_FS)
    if kind == "pressure":
        from .pressure import TransducerErrors

        p["cylinder"] = t.integer("cylinder", 1, minimum=1)
        p["sample_rate"] = t.positive("sample_rate", **_FS)
        p["transducer"] = TransducerErrors.from_table(t)
    if kind == "speed":
        p["sample_rate"] = t.positive("sample_rate", **_FS)
    if kind in ("torsiograph", "vibrograph") and "instrument_frequency" in t:
        p["instrument_frequency"] = t.positive("instrument_frequency", unit="Hz",
                                               plausible=(0.1, 1e6))
        p["instrument_damping"] = t.number("instrument_damping", 0.65, low=0.0, unit="1",
                                           plausible=(1e-3, 10.0))
    location = t.string("location", None)
    if location is not None:
        p["location"] = location
    imperfections = Imperfections.from_table(t, defaults)
    t.check_unknown(list(_IMPERFECTION_KEYS))
    return SensorSpec(name=name, kind=kind, params=p, imperfections=imperfections)
