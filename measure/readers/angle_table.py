"""Crank-angle-domain tables: cylinder pressure as an indicating system exports it.

Combustion indicating systems (AVL IndiCom, Kistler KiBox, Dewesoft's CA mode, ...) export
cylinder pressure against crank angle, not time:

* **long** layout: ``Cycle;CA [deg];P1 [bar];P2 [bar]`` with the angle repeating over each
  cycle (the cycle column may be missing: a new cycle starts where the angle wraps);
* **wide** layout: ``CA [deg];cycle 1 [bar];cycle 2 [bar];...``, one column per cycle of one
  pressure channel;
* one (averaged) cycle: ``KW [°KW];Zylinderdruck [bar]``.

Decimal commas, semicolons and German headers are read by the text sniffer
(:mod:`measure.readers.text`); ``.xlsx`` sheets the same way. The angle column is found by its
name (CA, crank angle, KW, °KW, Kurbelwinkel, angle, Winkel, phi, theta) with a degree or
radian unit and no time column; ``[source] angle_column``, ``cycle_column``,
``speed_column``, ``layout`` and ``firing_tdc_deg`` of a channel map
(:mod:`measure.channelmap`) say it explicitly.

Data model (:func:`read_angle_table`): an ``xarray.Dataset`` with dims ``(cycle,
crank_angle)``; coordinate ``crank_angle`` (rad, the file's own axis: its 0 is a TDC, firing
or not; one cycle of 720° or 360°, the closing point of an axis given as 0..720 inclusive
dropped), ``cycle`` (the file's cycle numbers, int); each pressure channel (Pa, ``quantity``
"pressure", ``cylinder`` when its name says) on ``(cycle, crank_angle)``; a ``speed`` (rad/s)
on ``(cycle,)`` when the file has a speed column (its mean over each cycle); attrs ``domain``
= "crank_angle", ``cycle_deg`` (720 or 360), ``angle_step_deg``, ``layout``, ``raw_source``
and, when a map gives it, ``firing_tdc_deg``. :func:`analysis.pressure_cycles.\
indicator_analysis_cycles` analyses it.

Bad input is refused with a :class:`~crankbench.predict.errors.RecordError` naming the file and
what was expected: uneven angle steps, a cycle with missing rows or another start angle, an
axis that does not span a whole 720° or 360° cycle, cycle columns in different units, empty
cells.
"""

from __future__ import annotations

import logging
import re
from pathlib import Path

import numpy as np

from crankbench.predict.errors import RecordError

__all__ = ["read_angle_table", "is_angle_table", "angle_column_of"]

log = logging.getLogger("crankbench")

_TEXT_SUFFIXES = {".csv", ".txt", ".tsv", ".tab", ".asc", ".dat"}
_ANGLE_NAMES = re.compile(r"^(ca|crank ?angle|crankangle|kw|kurbelwinkel|angle|winkel|phi|theta|"
                          r"deg ?ca|grad ?kw|crank|alpha)$")
_CYCLE_NAMES = re.compile(r"^(cycle|cyc|cycles|zyklus|zyk|arbeitsspiel|as|cycle ?(no|nr|number|"
                          r"#|index)|zyklus ?-?(nr|nummer)|cycle_(no|nr|number|index))\.?$")
_SPEED_NAMES = re.compile(r"^(speed|n|drehzahl|engine ?speed|rpm|n_mot|nmot|motordrehzahl)$")
_CYCLE_IN_NAME = re.compile(r"(?:^|[\s_\-])(?:cycle|cyc|zyklus|zyk|as|arbeitsspiel)\s*[#_\-]?\s*"
                            r"(\d+)\s*$|^\s*(\d+)\s*$", re.I)
#: angle units: degree spellings of indicating software (°KW, °CA, deg CA, Grad KW)
_DEG_UNITS = {"deg", "°", "degree", "degrees", "grad", "°kw", "°ca", "degca", "degkw", "kw",
              "ca", "°crank", "° ca", "° kw", "deg ca", "deg kw", "grad kw", "°kwl"}


def _key(text):
    return re.sub(r"\s+", " ", str(text or "").replace("°", "").strip().lower())


def _angle_unit(unit, name):
    """'deg' or 'rad' from a column's unit (or from a name like '°KW'), else None."""
    for text in (unit, name):
        if text is None:
            continue
        u = str(text).strip().lower()
        if u in _DEG_UNITS or u.replace(" ", "") in _DEG_UNITS:
            return "deg"
        if u == "rad":
            return "rad"
    return None


def _columns(table):
    from .table import split_header

    out = []
    for i, header in enumerate(table.names):
        name, unit = split_header(header)
        if unit is None and i < len(table.units) and table.units[i]:
            unit = table.units[i]
        out.append((name or f"column {i + 1}", unit))
    return out


def angle_column_of(table):
    """0-based index of a table's crank-angle column found by name, or None (also None when
    the table has a time column: it is then a time record).

    Examples
    --------
    >>> class T:
    ...     names, units = ["Zyklus", "°KW", "P1 [bar]"], [None, None, None]
    >>> angle_column_of(T())
    1
    """
    from .table import TIME_NAMES

    cols = _columns(table)
    if any(_key(n) in TIME_NAMES for n, _ in cols):
        return None
    for i, (name, unit) in enumerate(cols):
        if _ANGLE_NAMES.match(_key(name)) and (unit is None or _angle_unit(unit, None)):
            return i
        if unit is None and _angle_unit(None, name) == "deg" and "°" in str(name):
            return i
    return None


def _open(path, source=None):
    from .table import open_table

    suffix = Path(path).suffix.lower()
    module = "xlsx" if suffix == ".xlsx" else "csv"
    return open_table(path, module, source=source)


def is_angle_table(path) -> bool:
    """Whether ``path`` is a text/spreadsheet table with a crank-angle column and no time
    column (an indicating system's angle-domain export).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "ca.csv"
    >>> _ = p.write_text("CA [deg];P1 [bar]\\n" + "".join(f"{a};1,0\\n" for a in range(-360, 360)))
    >>> is_angle_table(p)
    True
    """
    suffix = Path(path).suffix.lower()
    if suffix not in _TEXT_SUFFIXES | {".xlsx"}:
        return False
    try:
        table = _open(path)
    except (RecordError, OSError, ValueError):
        return False
    return any(table.names) and angle_column_of(table) is not None


def _resolve(value, table, key, file):
    from crankbench.measure.channelmap import _resolve as resolve

    return resolve(value, table.names, file=file, key=key, describe=table.describe(),
                   n_columns=table.n_columns)


def _cylinder(name, location=None):
    for text in (location or "", name):
        m = re.search(r"(?:cyl(?:inder)?|zyl(?:inder)?|p)[ _\-]?(\d+)", str(text), re.I)
        if m:
            return int(m.group(1))
    return None


def _grid(a, label, file):
    """Check one cycle's angles (deg): even steps; returns the step."""
    if a.size < 8:
        raise RecordError(f"{file}: {label} has {a.size} angle rows; expected a whole cycle "
                          "(hundreds of rows)")
    d = np.diff(a)
    step = float(np.median(d))
    if not step > 0:
        raise RecordError(f"{file}: {label}: the crank angle does not increase (median step "
                          f"{step:g} deg); expected an increasing angle within each cycle")
    bad = np.flatnonzero(np.abs(d - step) > 1e-3 * step + 1e-6)
    if bad.size:
        k = int(bad[0])
        raise RecordError(f"{file}: {label}: uneven crank-angle step at {a[k]:g} -> {a[k + 1]:g}"
                          f" deg (the step is {step:g} deg elsewhere; {bad.size} uneven steps); "
                          "expected an evenly sampled angle axis (missing or repeated rows?)")
    return step


def _span(a, step, file, label):
    """Cycle span (720 or 360) of an axis, and whether its last point closes it (0..720)."""
    open_span = a.size * step
    for span in (720.0, 360.0):
        if abs(open_span - span) < 0.5 * step:
            return span, False
        if abs(open_span - step - span) < 0.5 * step:
            return span, True
    raise RecordError(f"{file}: {label}: the angle axis {a[0]:g}..{a[-1]:g} deg ({a.size} rows "
                      f"of {step:g} deg) spans {open_span:g} deg; expected one whole cycle: 720 "
                      "deg (4-stroke) or 360 deg (2-stroke), e.g. -360..359.9 or 0..720")


def read_angle_table(path, *, map=None):  # noqa: A002 - the library's name for a channel map
    """Read an angle-domain indicating export (see the module docstring for the data model).

    Parameters
    ----------
    path : path-like
        Delimited text (any dialect the sniffer reads) or ``.xlsx``.
    map : path-like, dict or measure.channelmap.ChannelMap, optional
        ``[source]`` ``angle_column``, ``angle_units``, ``cycle_column``, ``speed_column``,
        ``layout`` ("long"/"wide"), ``firing_tdc_deg`` and the dialect keys; ``[channel.X]``
        tables name the pressure columns (``column``, ``units``, ``scale``, ``offset``,
        ``location``); in the wide layout one channel whose ``column`` is the first cycle
        column (every later column is a further cycle).

    Returns
    -------
    xarray.Dataset
        Dims ``(cycle, crank_angle)``, pressure in Pa, angle in rad.

    Raises
    ------
    RecordError
        No crank-angle column, uneven steps, a cycle with missing rows, a span other than 720°
        or 360°, cycle columns in different units, empty cells.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "ca.csv"
    >>> rows = "".join(f"{c};{a / 2:.1f};{1 + c}\\n" for c in (1, 2) for a in range(-720, 720))
    >>> _ = p.write_text("Cycle;CA [deg];P1 [bar]\\n" + rows)
    >>> ds = read_angle_table(p)
    >>> dict(ds.sizes), ds.attrs["cycle_deg"], float(ds["P1"][1, 0]) / 1e5
    ({'cycle': 2, 'crank_angle': 1440}, 720.0, 3.0)
    """
    from crankbench.measure.channelmap import ChannelMap, load_map

    cmap = None if map is None else (map if isinstance(map, ChannelMap) else load_map(map))
    src = {} if cmap is None else dict(cmap.source)
    file = Path(path).name
    table = _open(path, source=src)
    cols = _columns(table)
    if "angle_column" in src:
        ia = _resolve(src["angle_column"], table, "source.angle_column", file)
    else:
        ia = angle_column_of(table)
        if ia is None:
            raise RecordError(f"{file}: no crank-angle column (read as {table.describe()}; "
                              f"columns {[str(h) for h in table.names]}); expected one named "
                              "like 'CA [deg]', 'KW [°KW]' or 'crank angle [deg]' and no time "
                              "column, or a channel map with [source] angle_column")
    a_unit = src.get("angle_units") or _angle_unit(cols[ia][1], cols[ia][0])
    if a_unit is None and cols[ia][1] is None:
        a_unit = "deg"
        log.info("%s: crank-angle column %s names no unit: taken as degrees", file,
                 table.label(ia))
    if a_unit not in ("deg", "rad"):
        raise RecordError(f"{file}: crank-angle column {table.label(ia)} is in {cols[ia][1]!r}; "
                          "expected degrees (deg, °, °KW, °CA) or rad")
    ic = _resolve(src["cycle_column"], table, "source.cycle_column", file) \
        if "cycle_column" in src else next(
            (i for i, (n, _) in enumerate(cols) if i != ia and _CYCLE_NAMES.match(_key(n))), None)
    isp = _resolve(src["speed_column"], table, "source.speed_column", file) \
        if "speed_column" in src else _speed_column(cols, {ia, ic})
    used = {ia, ic, isp} - {None}
    chans = _pressure_columns(table, cols, cmap, used, file)
    layout = src.get("layout") or _layout(chans, ic)
    if layout == "wide" and cmap is not None and len(chans) == 1:
        first = chans[0]                      # the map names the first cycle column
        chans = [dict(first, index=i, name=f"{first['name']} cycle {k + 1}")
                 for k, i in enumerate(j for j in range(first["index"], table.n_columns)
                                       if j not in used)]
    if layout == "wide" and ic is not None:
        raise RecordError(f"{file}: a cycle column ({table.label(ic)}) and the wide layout (one "
                          "column per cycle) exclude each other; set [source] layout = \"long\"")
    idx = [ia] + ([ic] if ic is not None else []) + ([isp] if isp is not None else []) \
        + [c["index"] for c in chans]
    data = dict(zip(idx, table.read(idx)))
    angle = data[ia] * (180.0 / np.pi if a_unit == "rad" else 1.0)
    if not np.all(np.isfinite(angle)):
        row = int(np.flatnonzero(~np.isfinite(angle))[0])
        raise RecordError(f"{file}: crank-angle column {table.label(ia)} is empty or not a "
                          f"number in data row {row + 1}; expected a number in every row")
    if layout == "wide":
        return _wide(table, cols, chans, angle, data, src, file, isp)
    return _long(table, chans, angle, data, ic, isp, src, file)


def _speed_column(cols, taken):
    from crankbench.measure.units import _lookup

    from .table import name_is_unit

    for i, (name, unit) in enumerate(cols):
        if i in taken:
            continue
        unit = unit or name_is_unit(name)
        hit = unit is not None and _lookup(str(unit)) is not None and \
            _lookup(str(unit))[2] == "rotational_speed"
        if hit and (_SPEED_NAMES.match(_key(name)) or name_is_unit(name)):
            return i
    return None


def _pressure_columns(table, cols, cmap, used, file):
    """[{index, name, unit, scale, offset, location}] of the pressure columns."""
    from crankbench.measure.units import _lookup

    if cmap is not None and cmap.channels:
        out = []
        for spec in cmap.channels:
            i = _resolve(spec.column, table, f"channel.{spec.name}.column", file)
            unit = spec.units or cols[i][1]
            if unit is None or _lookup(str(unit)) is None or \
                    _lookup(str(unit))[2] != "pressure":
                raise RecordError(f"{file}: channel.{spec.name} ({table.label(i)}) is in "
                                  f"{unit!r}; an angle-domain export's channels are cylinder "
                                  "pressures: give units = \"bar\" (or Pa, kPa, MPa, psi)")
            out.append(dict(index=i, name=spec.name, unit=str(unit), scale=spec.scale,
                            offset=spec.offset, location=spec.location))
        return out
    out, skipped = [], []
    for i, (name, unit) in enumerate(cols):
        if i in used:
            continue
        hit = unit is not None and _lookup(str(unit)) is not None
        if hit and _lookup(str(unit))[2] == "pressure":
            out.append(dict(index=i, name=name, unit=str(unit), scale=1.0, offset=0.0,
                            location=None))
        else:
            skipped.append(table.label(i))
    if skipped:
        log.info("%s: columns not read (not a pressure): %s", file, ", ".join(skipped))
    if not out:
        raise RecordError(f"{file}: no cylinder-pressure column (a column with a pressure unit, "
                          f"e.g. 'P1 [bar]'); columns {[str(h) for h in table.names]}; give a "
                          "channel map naming the pressure column and its units")
    return out


def _layout(chans, ic):
    if ic is not None or len(chans) < 2:
        return "long"
    numbered = [_CYCLE_IN_NAME.search(c["name"]) for c in chans]
    return "wide" if all(numbered) else "long"


def _common(src, file):
    attrs = {"domain": "crank_angle", "raw_source": file}
    if "firing_tdc_deg" in src:
        attrs["firing_tdc_deg"] = float(src["firing_tdc_deg"])
    return attrs


def _dataset(cycles, axis_deg, step, span, closed, chans_out, speed, attrs):
    import xarray as xr

    n = int(round(span / step))
    coords = {"cycle": ("cycle", np.asarray(cycles, np.int64), {"long_name": "cycle number"}),
              "crank_angle": ("crank_angle", np.deg2rad(axis_deg[:n]),
                              {"units": "rad", "long_name": "crank angle as exported (its 0 "
                               "is a TDC)"})}
    data = {}
    for name, values, vattrs in chans_out:
        data[name] = (("cycle", "crank_angle"), values[:, :n], vattrs)
    if speed is not None:
        data["speed"] = (("cycle",), speed, {"units": "rad/s", "quantity": "rotational_speed",
                                             "long_name": "mean speed of each cycle"})
    attrs = dict(attrs, cycle_deg=float(span), angle_step_deg=float(step),
                 closing_point_dropped=int(closed))
    return xr.Dataset(data, coords=coords, attrs=attrs)


def _to_pa(values, chan, file):
    from crankbench.measure.units import to_si

    v = values * chan["scale"] + chan["offset"]
    try:
        si, unit, _ = to_si(v, chan["unit"], channel=chan["name"])
    except RecordError as exc:
        raise RecordError(f"{file}: {exc}") from None
    return np.asarray(si, float)


def _chan_attrs(chan, label):
    cyl = _cylinder(chan["name"], chan.get("location"))
    attrs = {"units": "Pa", "quantity": "pressure", "source_column": label}
    if cyl is not None:
        attrs["cylinder"] = cyl
    if chan.get("location"):
        attrs["location"] = chan["location"]
    return attrs


def _long(table, chans, angle, data, ic, isp, src, file):
    if ic is not None:
        c = data[ic]
        if not np.all(np.isfinite(c)):
            row = int(np.flatnonzero(~np.isfinite(c))[0])
            raise RecordError(f"{file}: cycle column {table.label(ic)} is empty in data row "
                              f"{row + 1}")
        starts = np.flatnonzero(np.concatenate([[True], c[1:] != c[:-1]]))
        numbers = c[starts].astype(np.int64)
        values, counts = np.unique(numbers, return_counts=True)
        if np.any(counts > 1):
            raise RecordError(f"{file}: the rows of cycle(s) {values[counts > 1].tolist()[:5]} "
                              "are not together (the cycle number comes back after another); "
                              "expected each cycle's rows in one block")
    else:
        starts = np.flatnonzero(np.concatenate([[True], np.diff(angle) < 0]))
        numbers = np.arange(1, starts.size + 1)
    ends = np.concatenate([starts[1:], [angle.size]])
    lengths = ends - starts
    n = int(np.max(lengths))
    ref = angle[starts[int(np.argmax(lengths))]:starts[int(np.argmax(lengths))] + n]
    step = _grid(ref, f"cycle {numbers[int(np.argmax(lengths))]}", file)
    span, closed = _span(ref, step, file, "the cycle")
    for k, (s, e) in enumerate(zip(starts, ends)):
        if e - s != n or abs(angle[s] - ref[0]) > 1e-3 * step:
            raise RecordError(f"{file}: cycle {numbers[k]} has {e - s} rows from {angle[s]:g} "
                              f"deg; the others have {n} rows from {ref[0]:g} deg (missing rows "
                              "or a cycle cut short); expected whole cycles on one angle axis")
        if np.max(np.abs(angle[s:e] - ref)) > 1e-3 * step + 1e-6:
            _grid(angle[s:e], f"cycle {numbers[k]}", file)
            raise RecordError(f"{file}: cycle {numbers[k]} is on another angle axis than "
                              f"cycle {numbers[0]}; expected every cycle on the same axis")
    out = []
    for chan in chans:
        v = data[chan["index"]]
        if not np.all(np.isfinite(v)):
            row = int(np.flatnonzero(~np.isfinite(v))[0])
            cyc = numbers[int(np.searchsorted(starts, row, side="right") - 1)]
            raise RecordError(f"{file}: {table.label(chan['index'])} is empty or not a number "
                              f"in data row {row + 1} (cycle {cyc}); expected a pressure in "
                              "every row")
        p = _to_pa(v, chan, file).reshape(numbers.size, n)
        out.append((chan["name"], p, _chan_attrs(chan, table.label(chan["index"]))))
    speed = None
    if isp is not None:
        from crankbench.measure.units import to_si

        sp, _, _ = to_si(data[isp], cols_unit(table, isp), channel="speed")
        sp = np.asarray(sp, float).reshape(numbers.size, n)
        speed = np.nanmean(sp, axis=1)
    attrs = dict(_common(src, file), layout="long")
    return _dataset(numbers, ref, step, span, closed, out, speed, attrs)


def cols_unit(table, i):
    from .table import name_is_unit

    name, unit = _columns(table)[i]
    return unit or name_is_unit(name) or "rpm"


def _wide(table, cols, chans, angle, data, src, file, isp):
    step = _grid(angle, "the angle column", file)
    span, closed = _span(angle, step, file, "the angle column")
    units = {c["unit"] for c in chans}
    if len(units) > 1:
        raise RecordError(f"{file}: the cycle columns of the wide layout are in different units "
                          f"({', '.join(sorted(units))}); expected one pressure channel in one "
                          "unit (one column per cycle)")
    numbers = []
    for k, c in enumerate(chans):
        m = _CYCLE_IN_NAME.search(c["name"])
        numbers.append(int(m.group(1) or m.group(2)) if m else k + 1)
    if len(set(numbers)) != len(numbers):
        numbers = list(range(1, len(chans) + 1))
    rows = []
    for c in chans:
        v = data[c["index"]]
        if not np.all(np.isfinite(v)):
            row = int(np.flatnonzero(~np.isfinite(v))[0])
            raise RecordError(f"{file}: cycle column {table.label(c['index'])} is empty or not "
                              f"a number in data row {row + 1} (at {angle[row]:g} deg); "
                              "expected a pressure at every angle of every cycle")
        rows.append(_to_pa(v, c, file))
    order = np.argsort(numbers, kind="stable")
    p = np.asarray(rows)[order]
    first = chans[0]
    name = _channel_name(chans)
    out = [(name, p, _chan_attrs(dict(first, name=name), f"{table.label(first['index'])}.."))]
    speed = None
    if isp is not None:
        log.info("%s: speed column %s of a wide layout (one value per angle) is not per cycle; "
                 "its mean is used for every cycle", file, table.label(isp))
        from crankbench.measure.units import to_si

        sp, _, _ = to_si(data[isp], cols_unit(table, isp), channel="speed")
        speed = np.full(len(chans), float(np.nanmean(sp)))
    attrs = dict(_common(src, file), layout="wide")
    return _dataset(np.asarray(numbers)[order], angle, step, span, closed, out, speed, attrs)


def _channel_name(chans):
    """The pressure channel of a wide layout: the cycle columns' names less the cycle number
    (``'P1 cycle 3'`` -> ``'P1'``), else ``'pressure'``."""
    rest = {(_CYCLE_IN_NAME.sub("", c["name"]).strip(" _-") or "") for c in chans}
    if len(rest) == 1 and next(iter(rest)):
        return next(iter(rest))
    return "pressure"
