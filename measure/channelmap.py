"""Channel maps: what each column of a test-bench file is, in a small TOML file.

A real rig's export says little: ``CH1 CH2 CH3`` in volts, or no header at all. A channel map
says the rest, once per rig, so no Python is needed to bring its records in
(``crankbench import SRC --map MAP.toml -o OUT.h5``, ``measure.read(SRC, map=MAP)`` and
``--map`` on ``info``, ``analyse``, ``compare``, ``report``, ``batch``)::

    description = "genset 60-2 wheel, TDC mark, cylinder pressure at 100 kHz"

    [source]                      # all optional
    sample_rate = 100000.0        # Hz, when the file has no time column ...
    # time_column = 1             # ... or its 1-based number or header text
    # time_units = "ms"           # unit of the time column (default: its header's, else s)
    delimiter = "tab"             # comma | tab | semicolon | space | pipe (default: sniffed)
    decimal = ","                 # "." or "," (default: sniffed)
    header_rows = 0               # header lines above the data (default: sniffed)
    # skip_rows = 3               # lines before the header
    # sheet = "Data"              # .xlsx: sheet name or 1-based number (default: the first)
    # start_time = "2026-03-01T10:00:00+00:00"
    # engine_id = "G3"
    # test_id = "run 7"
    # keep_unmapped = false       # also read the columns not mapped (from their headers)
    # imep = "13 bar"             # the run's load, so predicted amplitudes can be judged:
    # load_law = "constant"       #   constant | propeller (gas load ∝ speed²) ...
    # load_reference_rpm = 720    #   ... with imep at this speed (default: rated)

    [channel.pressure]
    column = 3                    # 1-based number or the header text
    units = "bar"                 # of the calibrated value
    scale = 51.948                # value = raw * scale + offset (in units): p = (V/5 - 0.115)
    offset = -29.87               #   / 0.00385 kPa -> 51.948 bar/V * V - 29.87 bar ...
    quantity = "pressure"         # optional when the unit implies it
    location = "cylinder 1"       # optional sensor metadata: location, direction, node

    [channel.acc_fl_z]            # a vibrograph on the block, placed for the mount model:
    column = 4
    units = "g"
    direction = "z"               # x, y, z (signed), vertical, lateral, axial (engine frame)
    mount = "FL"                  # at a named mount of the engine model, or
    # position = ["0.35 m", "-0.42 m", "-0.30 m"]   # x, y, z in the engine frame
    # instrument_natural_frequency = "12 Hz"        # a seismic pick-up read through its model
    # instrument_damping_ratio = 0.65

    [channel.crank]
    column = 1
    role = "wheel"                # a raw pulse signal: decoded to edge times
    pulses_per_rev = 60           # pitch positions, missing teeth included (360: an encoder)
    missing_teeth = 2             # 0 for an encoder; leave out to infer it from the pattern
    tdc_offset_deg = 84.0         # optional: TDC of cylinder 1 after the first tooth after the gap
    keep_raw = true               # also keep the voltage as channel "crank_raw"

    [channel.tdc]
    column = 2
    role = "tdc"                  # one mark per revolution ...
    per_cycle = false             # ... or per four-stroke cycle

Role channels may also give ``units`` (of the raw signal, default V), ``scale``/``offset``,
``slope`` ("rising"/"falling" edges), ``level`` (fixed switching level, raw units) and
``hysteresis`` (fraction of the swing); by default the levels follow the signal
(:mod:`measure.edges`). Decoded channels are stored as pulse trains (dim ``pulse_<name>``,
attrs ``pulses_per_rev``, ``missing_teeth``, ``role``; a per-cycle mark has ``speed_ratio`` 0.5),
wheels before marks, so the speed reference and the crank angle use them.

A crank-angle-domain export of an indicating system (pressure per cycle against crank angle,
no time axis) is said by ``[source] angle_column`` (with ``angle_units`` "deg"/"rad",
``cycle_column``, ``speed_column``, ``layout`` "long"/"wide", ``firing_tdc_deg``); it is read
by :func:`measure.readers.angle_table.read_angle_table` (``crankbench pressure --map``), and a
time-domain read of it is refused.

Keys are checked like model files: an unknown key is an error with a did-you-mean, a column
that is not in the file is an error listing the columns there. The Record keeps its
provenance: ``raw_source`` (file name), ``raw_sha256`` and ``channel_map`` (the map's text).
For files that already carry named channels (.h5, .mf4, .tdms, ...) ``column`` names a channel
(or its 1-based position) and ``scale``/``offset`` apply to its values as read (in SI).
"""

from __future__ import annotations

import hashlib
import logging
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from crankbench.predict._toml import Table as TomlTable
from crankbench.predict.errors import AnalysisError, ConfigError, RecordError

from .provenance import SOURCE_ATTRS
from .readers.text import DELIMITERS

__all__ = ["ChannelMap", "ChannelSpec", "load_map", "apply_map", "read_mapped", "ROLES"]

log = logging.getLogger("crankbench")

ROLES = ("wheel", "tdc")
_SOURCE_TABLE_KEYS = ("sample_rate", "time_column", "time_units", "delimiter", "decimal",
                      "header_rows", "skip_rows", "encoding", "sheet")
#: every key of [source] and of a [channel.<name>] table
#: the run's load as the record states it (record attrs; analysis.pipeline.LoadCase)
LOAD_KEYS = ("imep", "load_law", "load_reference_rpm")
#: an angle-domain indicating export (measure.readers.angle_table; crankbench pressure)
ANGLE_KEYS = ("angle_column", "angle_units", "cycle_column", "speed_column", "layout",
              "firing_tdc_deg")
SOURCE_KEYS = _SOURCE_TABLE_KEYS + ("start_time", "engine_id", "test_id", "keep_unmapped") \
    + LOAD_KEYS + ANGLE_KEYS
CHANNEL_KEYS = ("column", "units", "quantity", "scale", "offset", "location", "direction",
                "node", "position", "mount", "instrument_natural_frequency",
                "instrument_damping_ratio", "role", "pulses_per_rev", "missing_teeth",
                "per_cycle", "keep_raw", "slope", "level", "hysteresis", "tdc_offset_deg")
#: sensor-placement keys of plain channels (vibrograph comparison, analysis.vibrograph)
_PLACEMENT_KEYS = ("position", "mount", "instrument_natural_frequency",
                   "instrument_damping_ratio")


@dataclass(frozen=True)
class ChannelSpec:
    """One mapped channel (see the module docstring for the keys).

    Attributes
    ----------
    name : str
    column : int or str
        1-based column number or header text (a channel name for record files).
    units, quantity : str or None
    scale, offset : float
        ``value = raw * scale + offset``, in ``units``.
    location, direction, node : str or None
    role : str or None
        None, "wheel" or "tdc".
    pulses_per_rev : int or None
    missing_teeth : int or None
        None: inferred (wheel).
    per_cycle : bool
    keep_raw : bool
    slope : str
    level, hysteresis : float or None
    tdc_offset_deg : float or None
    position : tuple of 3 float or None
        Sensor position x, y, z, m, in the engine frame (vibrograph placement).
    mount : str or None
        Name of the engine model's mount the sensor sits at (instead of ``position``).
    instrument_natural_frequency : float or None
        Natural frequency, Hz, of a seismic pick-up whose reading the channel is.
    instrument_damping_ratio : float or None
        Its damping ratio (default 0.65 when only the frequency is given).
    """

    name: str
    column: int | str
    units: str | None = None
    quantity: str | None = None
    scale: float = 1.0
    offset: float = 0.0
    location: str | None = None
    direction: str | None = None
    node: str | None = None
    role: str | None = None
    pulses_per_rev: int | None = None
    missing_teeth: int | None = None
    per_cycle: bool = False
    keep_raw: bool = False
    slope: str = "rising"
    level: float | None = None
    hysteresis: float | None = None
    tdc_offset_deg: float | None = None
    position: tuple | None = None
    mount: str | None = None
    instrument_natural_frequency: float | None = None
    instrument_damping_ratio: float | None = None


@dataclass(frozen=True)
class ChannelMap:
    """A parsed, validated channel map.

    Attributes
    ----------
    channels : tuple of ChannelSpec
    source : dict
        The ``[source]`` settings given (delimiter already resolved).
    text : str
        The map's TOML text (kept in the Record for provenance).
    origin : str
        File name (or "<dict>").
    """

    channels: tuple
    source: dict = field(default_factory=dict)
    text: str = ""
    origin: str = "<map>"

    @property
    def sha256(self) -> str:
        """SHA-256 of the map text."""
        return hashlib.sha256(self.text.encode("utf-8")).hexdigest()

    @classmethod
    def from_toml(cls, path) -> "ChannelMap":
        """Read and validate a map file.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> p = pathlib.Path(tempfile.mkdtemp()) / "rig.toml"
        >>> _ = p.write_text('[source]\\nsample_rate = 1000.0\\n[channel.p]\\ncolumn = 2\\n'
        ...                  'units = "bar"\\nscale = 2.0\\n')
        >>> m = ChannelMap.from_toml(p)
        >>> m.channels[0].column, m.channels[0].scale, m.source["sample_rate"]
        (2, 2.0, 1000.0)
        """
        from crankbench.predict._toml import load_toml

        path = Path(path)
        if not path.exists():
            raise FileNotFoundError(f"{path}: no such channel map file")
        doc = load_toml(path, error=ConfigError)
        text = path.read_text(encoding="utf-8")
        return _parse(doc, text=text, origin=str(path))

    @classmethod
    def from_dict(cls, data: dict, *, origin="<dict>") -> "ChannelMap":
        """Validate a map given as a dict (the parsed TOML)."""
        import tomllib

        text = _to_toml(data)
        try:
            tomllib.loads(text)
        except tomllib.TOMLDecodeError:  # pragma: no cover - our writer writes valid TOML
            text = repr(data)
        return _parse(TomlTable(data, source=origin, error=ConfigError), text=text,
                      origin=origin)


def _to_toml(data: dict) -> str:
    """Minimal TOML of a map dict (tables of scalars), for the provenance text."""
    import json

    def value(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, (int, float)):
            return repr(v)
        return json.dumps(str(v), ensure_ascii=False)

    lines = [f"{k} = {value(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for k, v in data.items():
        if isinstance(v, dict) and k != "channel":
            lines.append(f"\n[{k}]")
            lines += [f"{kk} = {value(vv)}" for kk, vv in v.items()]
    for name, spec in (data.get("channel") or {}).items():
        lines.append(f"\n[channel.{json.dumps(str(name), ensure_ascii=False)}]")
        lines += [f"{kk} = {value(vv)}" for kk, vv in dict(spec).items()]
    return "\n".join(lines) + "\n"


def _parse(doc: TomlTable, *, text: str, origin: str) -> ChannelMap:
    source = {}
    src = doc.table("source", None)
    if src is not None:
        if "sample_rate" in src:
            source["sample_rate"] = src.positive("sample_rate", unit="Hz", plausible=(1e-3, 1e8))
        if "time_column" in src:
            source["time_column"] = _column(src, "time_column")
        if "time_units" in src:
            source["time_units"] = src.string("time_units")
        if "delimiter" in src:
            d = src.string("delimiter")
            if d not in DELIMITERS:
                src.fail("delimiter", f"= {d!r} is not one of comma, tab, semicolon, space, "
                                      "pipe (or ',', ';', '\\t', '|')")
            source["delimiter"] = DELIMITERS[d]
        if "decimal" in src:
            source["decimal"] = src.string("decimal", options=[".", ","])
        for key in ("header_rows", "skip_rows"):
            if key in src:
                source[key] = src.integer(key, minimum=0)
        if "encoding" in src:
            source["encoding"] = src.string("encoding")
        if "sheet" in src:
            value = src.raw("sheet")
            if isinstance(value, bool) or not isinstance(value, (int, str)):
                src.fail("sheet", f"= {value!r} must be a sheet name or a 1-based number")
            source["sheet"] = value
        for key in ("start_time", "engine_id", "test_id"):
            if key in src:
                source[key] = src.string(key)
        if "keep_unmapped" in src:
            source["keep_unmapped"] = _bool(src, "keep_unmapped")
        if "imep" in src:
            source["imep"] = src.positive("imep", unit="Pa", plausible=(1e4, 1e7))
        if "load_law" in src:
            source["load_law"] = src.string("load_law", options=("constant", "propeller"))
        if "load_reference_rpm" in src:
            source["load_reference_rpm"] = src.positive("load_reference_rpm", unit="rpm",
                                                        plausible=(1.0, 1e5))
        for key in ("angle_column", "cycle_column", "speed_column"):
            if key in src:
                source[key] = _column(src, key)
        if "angle_units" in src:
            source["angle_units"] = src.string("angle_units", options=("deg", "rad"))
        if "layout" in src:
            source["layout"] = src.string("layout", options=("long", "wide"))
        if "firing_tdc_deg" in src:
            source["firing_tdc_deg"] = src.number("firing_tdc_deg", unit="deg")
        if "angle_column" in source and ("sample_rate" in source or "time_column" in source):
            src.fail("angle_column", "and a time axis (sample_rate / time_column) are both "
                                     "given; an angle-domain export has no time axis")
        if "sample_rate" in source and "time_column" in source:
            src.fail("sample_rate", "and time_column are both given; give one (the time "
                                    "column's own rate is used)")
        src.check_unknown(SOURCE_KEYS)
    chans = doc.table("channel", None)
    if chans is None or not chans.keys():
        doc.fail("channel", "is missing: a map names at least one channel as "
                            "[channel.<name>] with a column")
    specs = []
    for name in list(chans.keys()):
        t = chans.table(name)
        specs.append(_channel(t, str(name)))
    doc.check_unknown(["description"])
    cols = {}
    for s in specs:
        key = s.column if isinstance(s.column, int) else str(s.column)
        if key in cols:
            raise ConfigError(f"{origin}: channel.{s.name}.column = {s.column!r} is also the "
                              f"column of channel.{cols[key]}; each column maps to one channel "
                              "(keep_raw = true keeps a pulse signal's raw values)")
        cols[key] = s.name
    names = {s.name for s in specs}
    for s in specs:
        if s.keep_raw and f"{s.name}_raw" in names:
            raise ConfigError(f"{origin}: channel.{s.name}.keep_raw would add channel "
                              f"'{s.name}_raw', which the map also names")
    return ChannelMap(channels=tuple(specs), source=source, text=text, origin=origin)


def _bool(t, key):
    value = t.raw(key)
    if not isinstance(value, bool):
        t.fail(key, f"= {value!r} must be true or false")
    return value


def _column(t, key):
    value = t.raw(key)
    if isinstance(value, bool) or not isinstance(value, (int, str)):
        t.fail(key, f"= {value!r} must be a 1-based column number or the column's header text")
    if isinstance(value, int) and value < 1:
        t.fail(key, f"= {value!r} must be >= 1 (columns are numbered from 1)")
    return value


def _placement(t, kw) -> None:
    """The sensor-placement keys of a plain channel (position in m, mount name, pick-up)."""
    if "position" in t:
        kw["position"] = tuple(float(v) for v in t.numbers("position", unit="m", length=3))
    kw["mount"] = t.string("mount", None)
    if kw["mount"] is not None and kw.get("position") is not None:
        t.fail("mount", "and 'position' both place the sensor; give one")
    kw["instrument_natural_frequency"] = t.number("instrument_natural_frequency", None,
                                                  unit="Hz", low=0.0, strict_low=True)
    kw["instrument_damping_ratio"] = t.number("instrument_damping_ratio", None, unit="1",
                                              low=0.0, strict_low=True)
    if kw["instrument_damping_ratio"] is not None and kw["instrument_natural_frequency"] is None:
        t.fail("instrument_damping_ratio", "needs instrument_natural_frequency (Hz) too")


def _channel(t, name) -> ChannelSpec:
    kw = {"name": name, "column": _column(t, "column")}
    role = t.string("role", None, options=list(ROLES))
    kw["role"] = role
    kw["units"] = t.string("units", None)
    kw["quantity"] = t.string("quantity", None)
    if kw["quantity"] is not None:
        from .units import QUANTITIES

        if kw["quantity"] not in QUANTITIES or kw["quantity"] == "pulse_times":
            t.fail("quantity", f"= {kw['quantity']!r} is not one of "
                               f"{', '.join(q for q in QUANTITIES if q != 'pulse_times')}")
    kw["scale"] = t.number("scale", 1.0, unit=None)      # channel units per raw unit
    if kw["scale"] == 0.0:
        t.fail("scale", "= 0 would make every value the offset; expected a non-zero factor")
    kw["offset"] = t.number("offset", 0.0, unit=None)
    for key in ("location", "direction", "node"):
        kw[key] = t.string(key, None)
    if role is not None:
        for key in _PLACEMENT_KEYS:
            if key in t:
                t.fail(key, "places a vibration sensor; it does not apply to pulse channels "
                            "(role = 'wheel' or 'tdc')")
    else:
        _placement(t, kw)
    if role is None:
        if kw["units"] is None:
            t.fail("units", "is missing (required): the unit of the channel's values, e.g. "
                            "'bar', 'g', 'V'")
        for key in ("pulses_per_rev", "missing_teeth", "per_cycle", "keep_raw", "slope",
                    "level", "hysteresis", "tdc_offset_deg"):
            if key in t:
                t.fail(key, "applies only to pulse channels (role = 'wheel' or 'tdc')")
        t.check_unknown(CHANNEL_KEYS)
        return ChannelSpec(**kw)
    kw["keep_raw"] = _bool(t, "keep_raw") if "keep_raw" in t else False
    kw["slope"] = t.string("slope", "rising", options=["rising", "falling"])
    kw["level"] = t.number("level", None, unit=None)     # in the raw signal's units
    kw["hysteresis"] = t.number("hysteresis", None, low=0.0, high=0.99, unit="1")
    kw["tdc_offset_deg"] = t.number("tdc_offset_deg", None, low=-720.0, high=720.0, unit="deg")
    if role == "wheel":
        kw["pulses_per_rev"] = t.integer("pulses_per_rev", minimum=1)
        if "missing_teeth" in t:
            value = t.raw("missing_teeth")
            if value != "auto":
                value = t.integer("missing_teeth", minimum=0)
                if value >= kw["pulses_per_rev"] - 1 and value:
                    t.fail("missing_teeth", f"= {value} must be less than pulses_per_rev - 1 "
                                            f"= {kw['pulses_per_rev'] - 1}")
                kw["missing_teeth"] = value
        if "per_cycle" in t:
            t.fail("per_cycle", "applies to role = 'tdc' marks")
    else:
        if "per_cycle" in t:
            kw["per_cycle"] = _bool(t, "per_cycle")
        for key in ("pulses_per_rev", "missing_teeth"):
            if key in t:
                t.fail(key, "applies to role = 'wheel' (a TDC mark is once per revolution, "
                            "or per cycle with per_cycle = true)")
    t.check_unknown(CHANNEL_KEYS)
    return ChannelSpec(**kw)


def load_map(value) -> ChannelMap:
    """A :class:`ChannelMap` from a path, a dict or a map.

    Raises
    ------
    ConfigError
        Invalid map (naming the file and key); FileNotFoundError for a missing file.
    """
    if isinstance(value, ChannelMap):
        return value
    if isinstance(value, dict):
        return ChannelMap.from_dict(value)
    if isinstance(value, (str, Path)):
        return ChannelMap.from_toml(value)
    raise ConfigError(f"map must be a path to a TOML channel map, a dict or a ChannelMap, got "
                      f"{type(value).__name__}")


# ------------------------------------------------------------------------------------------
# applying a map
# ------------------------------------------------------------------------------------------
def _resolve(spec_column, names, *, file, key, describe, n_columns):
    """0-based index of a map's ``column`` among a file's columns (names may hold None)."""
    from crankbench.predict._validate import suggest

    from .readers.table import split_header

    if isinstance(spec_column, int):
        if spec_column > n_columns:
            raise ConfigError(f"{key} = {spec_column}: {file} has only {n_columns} column(s) "
                              f"({describe})")
        return spec_column - 1
    text = str(spec_column)
    exact = [i for i, h in enumerate(names) if h is not None and str(h) == text]
    if not exact:
        exact = [i for i, h in enumerate(names) if h is not None and
                 split_header(h)[0] == split_header(text)[0]]
    if len(exact) == 1:
        return exact[0]
    shown = [str(h) for h in names if h is not None]
    if len(exact) > 1:
        raise ConfigError(f"{key} = {text!r}: {file} has {len(exact)} columns with that name "
                          f"(columns {', '.join(str(i + 1) for i in exact)}); give the column "
                          "number instead")
    if not shown:
        raise ConfigError(f"{key} = {text!r}: {file} has no header row ({describe}); give "
                          "the column number (1-based)")
    raise ConfigError(f"{key} = {text!r} is not a column of {file}{suggest(text, shown)}; "
                      f"columns: {', '.join(repr(h) for h in shown[:30])}")


def _channel_record_spec(spec, values, time, fs, label, file):
    """make_record spec of a plain (calibrated) channel."""
    values = values * spec.scale + spec.offset if (spec.scale != 1.0 or spec.offset) else values
    attrs = {"column": label}
    if spec.scale != 1.0 or spec.offset:
        attrs["calibration"] = (f"{spec.units} = raw × {spec.scale:.10g} + {spec.offset:.10g}")
    if spec.node:
        attrs["node"] = spec.node
    if spec.position is not None:
        attrs["position"] = list(spec.position)
    for key in ("mount", "instrument_natural_frequency", "instrument_damping_ratio"):
        if getattr(spec, key) is not None:
            attrs[key] = getattr(spec, key)
    out = dict(data=values, units=spec.units, sample_rate=fs, location=spec.location,
               direction=spec.direction, attrs=attrs, **time)
    if spec.quantity:
        out["quantity"] = spec.quantity
    else:
        from .units import to_si

        try:
            hint = to_si(1.0, spec.units, channel=spec.name)[2]
        except RecordError as exc:
            raise ConfigError(f"channel.{spec.name}.units: {exc}") from None
        if hint is None or hint == "sensitivity":
            out["quantity"] = "other"
            log.info("%s: channel %r (%s): units %r imply no quantity; stored as 'other' "
                     "(give quantity in the map)", file, spec.name, label, spec.units)
    return out


def _decode(spec, values, t, fs, label, file, wheel):
    """Decode a role channel; return (pulse spec, raw spec or None, DecodedPulses)."""
    from .wheel import decode_marks, decode_wheel

    units = spec.units or "V"
    raw = values * spec.scale + spec.offset if (spec.scale != 1.0 or spec.offset) else values
    where = f"{file}: channel {spec.name!r} ({label})"
    finite = np.isfinite(raw)
    if not finite.all():
        i = int(np.flatnonzero(~finite)[0])
        raise RecordError(f"{where}: {int((~finite).sum())} empty or NaN sample(s), first at "
                          f"t = {t[i]:.6g} s; a pulse signal needs every sample")
    opts = dict(fs=fs, t0=0.0, slope=spec.slope, level=spec.level,
                hysteresis=spec.hysteresis, name=where)
    try:
        if spec.role == "wheel":
            dec = decode_wheel(raw, pulses_per_rev=spec.pulses_per_rev,
                               missing_teeth=spec.missing_teeth, **opts)
        else:
            dec = decode_marks(raw, per_cycle=spec.per_cycle, wheel=wheel, **opts)
    except AnalysisError as exc:
        raise RecordError(str(exc)) from None
    # sample index -> the file's own time (exact for a jittered time column too)
    edges = np.interp(dec.edges * fs, np.arange(t.size, dtype=float), t)
    attrs = {**dec.attrs(), "column": label}
    if spec.node:
        attrs["node"] = spec.node
    if spec.tdc_offset_deg is not None:
        attrs["tdc_offset_deg"] = float(spec.tdc_offset_deg)
    if spec.keep_raw:
        attrs["raw_channel"] = f"{spec.name}_raw"
    pulse = dict(data=edges, units="s", quantity="pulse_times",
                 pulses_per_rev=dec.pulses_per_rev, missing_teeth=dec.missing_teeth,
                 location=spec.location, direction=spec.direction, attrs=attrs)
    raw_spec = None
    if spec.keep_raw:
        from .units import to_si

        try:
            hint = to_si(1.0, units, channel=spec.name)[2]
        except RecordError as exc:
            raise ConfigError(f"channel.{spec.name}.units: {exc}") from None
        raw_spec = dict(data=raw, units=units, quantity=hint if hint in ("voltage",) else
                        "other", sample_rate=fs, location=spec.location,
                        attrs={"column": label, "decoded_as": spec.name, "role": spec.role})
    return pulse, raw_spec, dec


def _assemble(cmap, plain, roles, extra, attrs, file, allow_nonfinite):
    """Build the Record: sampled channels, then wheels, then marks."""
    from .record import make_record

    channels = {}
    for name, spec in plain:
        channels[name] = spec
    wheel = None
    pulses = {}
    for kind in ("wheel", "tdc"):
        for spec, values, t, fs, label in roles:
            if spec.role != kind:
                continue
            pulse, raw, dec = _decode(spec, values, t, fs, label, file, wheel)
            if kind == "wheel" and wheel is None:
                wheel = dec
            pulses[spec.name] = pulse
            if raw is not None:
                channels[f"{spec.name}_raw"] = raw
    channels.update(extra)
    channels.update(pulses)
    try:
        return make_record(channels, attrs=attrs, start_time=cmap.source.get("start_time"),
                           allow_nonfinite=allow_nonfinite)
    except RecordError as exc:
        raise RecordError(f"{file}: {exc}") from None


def apply_map(table, cmap: ChannelMap, *, allow_nonfinite=False):
    """A Record from a table (:class:`measure.readers.table.Table`) and a channel map.

    Raises
    ------
    ConfigError
        A column not in the file, a unit not known, a setting that does not fit the file.
    RecordError
        The data: no time, a pulse channel that cannot be decoded, non-numeric cells —
        naming the file, the column and what was seen.
    """
    from .readers.table import TIME_NAMES, last_row_cut, read_notes_attrs, split_header

    file = Path(table.file).name
    src = cmap.source
    describe = table.describe()

    def index(column, key):
        return _resolve(column, table.names, file=file, key=key, describe=describe,
                        n_columns=table.n_columns)

    time_idx = time_unit = None
    if "angle_column" in src:
        raise RecordError(f"{file}: the map's [source] angle_column makes it a crank-angle-domain "
                          "export (cylinder pressure against crank angle, no time axis): read "
                          "it with crankbench pressure FILE --map MAP or "
                          "measure.readers.angle_table.read_angle_table")
    if "time_column" in src:
        time_idx = index(src["time_column"], "source.time_column")
    elif "sample_rate" not in src:
        auto = [i for i, h in enumerate(table.names)
                if h is not None and (split_header(h)[0] or "").strip().lower() in TIME_NAMES]
        if auto:
            time_idx = auto[0]
        elif table.clock_columns:
            time_idx = table.clock_columns[0]
        elif not table.sample_rate:
            raise RecordError(
                f"{file}: no time axis: the map gives neither [source] sample_rate nor "
                f"time_column, and the file ({describe}) has no column named time and states "
                "no sample rate; add sample_rate (Hz) or time_column to the map's [source]")
    if time_idx is not None:
        time_unit = src.get("time_units") or split_header(table.names[time_idx])[1] or \
            (table.units[time_idx] if time_idx < len(table.units) else None) or "s"
    mapped = [(spec, index(spec.column, f"channel.{spec.name}.column")) for spec in cmap.channels]
    if time_idx is not None:
        for spec, i in mapped:
            if i == time_idx:
                raise ConfigError(f"channel.{spec.name}.column = {spec.column!r} is the time "
                                  "column; map it as [source] time_column only")
    used = {i for _, i in mapped} | ({time_idx} if time_idx is not None else set())
    unmapped = []
    if src.get("keep_unmapped"):
        unmapped = [i for i in range(table.n_columns) if i not in used]
    cols = sorted(used | set(unmapped))
    data = dict(zip(cols, table.read(cols)))
    n = max((c.size for c in data.values()), default=0)
    # rows: up to the last row where any read column has a number
    last = max((int(np.flatnonzero(np.isfinite(c))[-1]) + 1 if np.isfinite(c).any() else 0
                for c in data.values()), default=0)
    n = min(n, last)
    if n > 1 and data and last_row_cut(table, [c[n - 1] if c.size >= n else np.nan
                                               for c in data.values()]):
        n -= 1
    if n < 4:
        raise RecordError(f"{file}: {n} data row(s) ({describe}); expected a record of at "
                          "least 4 samples")
    clock = time_idx is not None and time_idx in table.clock_columns
    if clock and "time_units" in src:
        raise ConfigError(f"source.time_units = {src['time_units']!r}: time column "
                          f"{table.label(time_idx)} holds dates/times, read as seconds from its "
                          "first stamp; leave time_units out")
    if time_idx is not None:
        from .units import to_si

        t = data[time_idx][:n]
        if not np.all(np.isfinite(t)):
            i = int(np.flatnonzero(~np.isfinite(t))[0])
            raise RecordError(f"{file}: time column {table.label(time_idx)} is empty at data "
                              f"row {i + 1} ({describe}); expected a time in every row")
        try:
            t, si, _ = to_si(t, "s" if clock else time_unit, channel=str(table.names[time_idx]))
        except RecordError as exc:
            raise ConfigError(f"source.time_units: {exc}") from None
        # stamps printed coarser than the rate (ms stamps, %.3f, %.6g): the uniform clock
        # they round (any other irregularity is left for the record's checks to name)
        from .readers.table import _unrounded

        t = _unrounded(t, file, table.label(time_idx), table)
        if si != "s":
            raise ConfigError(f"{file}: time column {table.label(time_idx)} has unit "
                              f"{time_unit!r}; expected a time unit (s, ms, us)")
        if t[-1] <= t[0]:
            raise RecordError(f"{file}: time column {table.label(time_idx)} does not increase "
                              f"({t[0]:g} .. {t[-1]:g} s)")
        fs = (n - 1) / float(t[-1] - t[0])
        time = {"time": t}
    else:
        fs = float(src.get("sample_rate") or table.sample_rate)
        t = np.arange(n) / fs
        time = {}
        if "sample_rate" not in src:
            log.info("%s: sample rate %g Hz as stated in the file", file, fs)
    plain, roles = [], []
    for spec, i in mapped:
        values = data[i][:n]
        label = table.label(i)
        if spec.role is None:
            plain.append((spec.name, _channel_record_spec(spec, values, time, fs, label, file)))
        else:
            roles.append((spec, values, t, fs, label))
    extra = {}
    for i in unmapped:
        name, unit = split_header(table.names[i]) if table.names[i] else (None, None)
        unit = unit or (table.units[i] if i < len(table.units) else None)
        if not name or not unit:
            raise RecordError(f"{file}: keep_unmapped: {table.label(i)} has no name and unit in "
                              "its header; map it or leave keep_unmapped out")
        extra[name] = dict(data=data[i][:n], units=unit, sample_rate=fs, **time,
                           attrs={"column": table.label(i)})
    attrs = {k: src[k] for k in ("engine_id", "test_id") + LOAD_KEYS if k in src}
    attrs.update(read_notes_attrs(table))
    if clock and "start_time" not in src:  # the first stamp, unless the map states one
        attrs.update(getattr(table, "start_times", {}).get(time_idx, {}))
    return _assemble(cmap, plain, roles, extra, attrs, file, allow_nonfinite)


def apply_map_to_record(record, cmap: ChannelMap, *, file, allow_nonfinite=False):
    """A Record from a record file's channels (.h5, .mf4, .tdms, ...) and a channel map.

    ``column`` names a channel (or its 1-based position); values are taken as read (SI).
    """
    from .record import channel_time

    for key in _SOURCE_TABLE_KEYS:
        if key in cmap.source:
            raise ConfigError(f"source.{key} applies to text and spreadsheet files; {file} is a "
                              "record file whose channels carry their own time and units")
    names = [str(v) for v in record.data_vars]
    plain, roles, used = [], [], set()
    for spec in cmap.channels:
        i = _resolve(spec.column, names, file=file, key=f"channel.{spec.name}.column",
                     describe="channels", n_columns=len(names))
        used.add(i)
        var = record[names[i]]
        if var.attrs.get("quantity") == "pulse_times":
            raise ConfigError(f"channel.{spec.name}.column = {spec.column!r}: {names[i]!r} is "
                              "already a pulse train (edge times); map a sampled channel")
        t = channel_time(record, names[i])
        fs = float(var.attrs["sample_rate"])
        values = np.asarray(var.values, dtype=np.float64)
        label = f"channel {names[i]!r}"
        if spec.role is None:
            plain.append((spec.name, _channel_record_spec(spec, values, {"time": t}, fs, label,
                                                          file)))
        else:
            roles.append((spec, values, t, fs, label))
    extra = {}
    if cmap.source.get("keep_unmapped"):
        for i, name in enumerate(names):
            if i in used:
                continue
            var = record[name]
            spec = dict(data=np.asarray(var.values), units=var.attrs["units"],
                        quantity=var.attrs["quantity"],
                        attrs={k: v for k, v in var.attrs.items()
                               if k not in ("units", "quantity", "sample_rate",
                                            "pulses_per_rev", "missing_teeth")})
            if var.attrs["quantity"] == "pulse_times":
                spec.update(pulses_per_rev=var.attrs["pulses_per_rev"],
                            missing_teeth=var.attrs.get("missing_teeth", 0))
            else:
                spec.update(time=channel_time(record, name),
                            sample_rate=var.attrs["sample_rate"])
            extra[name] = spec
    attrs = {k: v for k, v in record.attrs.items() if k not in SOURCE_ATTRS}
    attrs.update({k: cmap.source[k] for k in ("engine_id", "test_id") + LOAD_KEYS
                  if k in cmap.source})
    return _assemble(cmap, plain, roles, extra, attrs, file, allow_nonfinite)


def read_mapped(path, module, cmap, *, allow_nonfinite=False):
    """Read ``path`` (format ``module``) through the channel map ``cmap`` into a Record."""
    from .readers.table import TABLE_FORMATS, open_table

    name = module.__name__.rsplit(".", 1)[-1]
    if name in TABLE_FORMATS:
        table = open_table(path, name, source=cmap.source)
        return apply_map(table, cmap, allow_nonfinite=allow_nonfinite)
    record = module.read(path)
    return apply_map_to_record(record, cmap, file=Path(path).name,
                               allow_nonfinite=allow_nonfinite)
