"""Tables of columns (delimited text, spreadsheets) and the Record read from their headers.

A :class:`Table` is what a text export or a spreadsheet holds: columns of numbers, maybe a header
row of names, maybe a units row, maybe a sample rate stated above the header. It reads only the
columns asked for. :func:`table_record` turns a table into a Record from its headers alone
(``name [unit]`` or a units row, a time column or a stated sample rate); when the headers do
not say enough, the error names what is missing and points to a channel map
(:mod:`measure.channelmap`), which gives the rest.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from crankbench.predict.errors import RecordError

from .text import Dialect, read_columns, sniff

__all__ = ["Table", "TextTable", "SheetTable", "table_record", "split_header", "TIME_NAMES",
           "open_table", "TABLE_FORMATS"]

_HEADER_RE = re.compile(r"^\s*(?P<name>.*?)\s*(?:\[(?P<u1>[^\]]*)\]|\((?P<u2>[^)]*)\))\s*$")
#: column names taken as the time axis (case-insensitive, unit stripped)
TIME_NAMES = {"time", "t", "zeit", "timestamp", "time_s", "x_value", "temps", "tiempo", "tempo"}
#: format modules whose files are tables (a channel map reads their columns)
TABLE_FORMATS = ("csv", "xlsx")


#: unit spellings never read from a name suffix (``cyl_1``, ``valve_in``, ``pos_m`` are names)
_NO_SUFFIX_UNITS = {"1", "-", "%", "in", "m", "n", "c", "deg"}


def suffix_unit(name):
    """The unit a column name states as its last ``_``-separated word (``"speed_rpm"`` ->
    ``"rpm"``, ``"acc_g"`` -> ``"g"``, ``"time_ms"`` -> ``"ms"``), or None.

    Only spellings of :mod:`measure.units` count, and not the ones that are ordinary words or
    indices in names (1, in, m, N, C, deg).

    Examples
    --------
    >>> suffix_unit("speed_hz"), suffix_unit("p_cyl_bar"), suffix_unit("acc_x"), suffix_unit("cyl_1")
    ('hz', 'bar', None, None)
    """
    from ..units import _lookup

    if not name or "_" not in str(name):
        return None
    base, _, tail = str(name).rpartition("_")
    if not base.strip() or tail.lower() in _NO_SUFFIX_UNITS:
        return None
    return tail if _lookup(tail) is not None else None


#: column names that are themselves a speed unit (a rig's "RPM" column): taken as that unit
_SPEED_NAMES = {"rpm", "1/min", "u/min", "r/min", "min-1", "min^-1"}


def name_is_unit(name):
    """The unit a column name *is* (``"RPM"`` -> ``"rpm"``), for rotational speed only, or None.

    A rig's speed column is often headed just ``RPM``; other bare unit words (``"g"``,
    ``"V"``) say nothing about what was measured and are not taken.

    Examples
    --------
    >>> name_is_unit("RPM"), name_is_unit("U/min"), name_is_unit("g")
    ('rpm', 'rpm', None)
    """
    key = str(name or "").strip().lower()
    return "rpm" if key in _SPEED_NAMES else None


def split_header(text):
    """``"p [bar]"`` or ``"p (bar)"`` -> ``("p", "bar")``; no unit -> ``(text, None)``.

    Examples
    --------
    >>> split_header("Pressure cyl 1 (bar)"), split_header("crank")
    (('Pressure cyl 1', 'bar'), ('crank', None))
    """
    if text is None:
        return None, None
    m = _HEADER_RE.match(str(text))
    if m:
        unit = m.group("u1") if m.group("u1") is not None else m.group("u2")
        return m.group("name"), unit.strip()
    return str(text).strip(), None


class Table:
    """Columns of a file (override :meth:`read`).

    Attributes
    ----------
    file : str
    names : list of (str or None)
        Header text of each column.
    units : list of (str or None)
        Unit of each column from a units row (None where none).
    n_columns : int
    sample_rate : float or None
        Stated in the file (Hz), if found.
    clock_columns : tuple of int
        Columns of date/time text, read as seconds from their first stamp.
    start_times : dict
        ``{column: {"start_time": ISO 8601}}`` of the date/time columns read so far.
    """

    file: str
    names: list
    units: list
    n_columns: int
    sample_rate: float | None = None
    clock_columns: tuple = ()

    def describe(self) -> str:
        """How the table was read (dialect, sheet)."""
        raise NotImplementedError

    def read(self, columns) -> np.ndarray:
        """Columns (0-based indices) as a (k, rows) float64 array."""
        raise NotImplementedError

    def label(self, index: int) -> str:
        """``column 3 ('Pressure [bar]')`` for messages."""
        name = self.names[index] if index < len(self.names) else None
        return f"column {index + 1}" + (f" ({name!r})" if name else "")


class TextTable(Table):
    """A delimited text file (:mod:`measure.readers.text`)."""

    def __init__(self, path, dialect: Dialect | None = None, **hints):
        self.path = Path(path)
        self.file = str(path)
        self.dialect = dialect or sniff(path, **hints)
        d = self.dialect
        self.n_columns = d.n_columns
        self.names = list(d.names) + [None] * (d.n_columns - len(d.names))
        self.units = list(d.units) + [None] * (d.n_columns - len(d.units))
        self.sample_rate = d.sample_rate
        self.clock_columns = d.clock_columns
        self.start_times = {}

    def describe(self) -> str:
        return self.dialect.describe()

    def read(self, columns) -> np.ndarray:
        return read_columns(self.path, self.dialect, columns, file=self.file,
                            starts=self.start_times)


class SheetTable(Table):
    """One worksheet of an ``.xlsx`` workbook (openpyxl, read-only).

    Header rows are the rows above the first row of numbers whose cells hold text; a row whose
    texts are all unit spellings is the units row. Date/time cells in a column become seconds
    from the first one.
    """

    def __init__(self, path, sheet=None, *, header_rows=None, skip_rows=None):
        import openpyxl

        self.path = Path(path)
        self.file = str(path)
        wb = openpyxl.load_workbook(self.path, read_only=True, data_only=True)
        try:
            if sheet is None:
                self._first_table(wb, header_rows, skip_rows)
                return
            if isinstance(sheet, int):
                if not 1 <= sheet <= len(wb.worksheets):
                    raise RecordError(f"{self.file}: sheet {sheet} does not exist; the workbook "
                                      f"has {len(wb.worksheets)} sheet(s): "
                                      f"{', '.join(wb.sheetnames)}")
                ws = wb.worksheets[sheet - 1]
            else:
                if sheet not in wb.sheetnames:
                    from crankbench.predict._validate import suggest

                    raise RecordError(f"{self.file}: no sheet {sheet!r}"
                                      f"{suggest(sheet, wb.sheetnames)}; sheets: "
                                      f"{', '.join(wb.sheetnames)}")
                ws = wb[sheet]
            self.sheet = ws.title
            rows = [list(r) for r in ws.iter_rows(values_only=True)]
        finally:
            wb.close()
        self._parse(rows, header_rows, skip_rows)

    def _first_table(self, wb, header_rows, skip_rows):
        """Read the first worksheet that holds a table of numbers (a workbook often opens with
        a cover or notes sheet), saying which when it is not the first."""
        faults = []
        for ws in wb.worksheets:
            self.sheet = ws.title
            rows = [list(r) for r in ws.iter_rows(values_only=True)]
            try:
                self._parse(rows, header_rows, skip_rows)
            except RecordError as exc:
                faults.append(f"{ws.title!r}: {str(exc).split(': ', 1)[-1]}")
                continue
            if faults:
                import logging

                logging.getLogger("crankbench").info(
                    "%s: reading sheet %r, the first with a table of numbers (sheets: %s; "
                    "choose another with [source] sheet in a channel map)", self.file, ws.title,
                    ", ".join(wb.sheetnames))
            return
        raise RecordError(f"{self.file}: no sheet holds a table of numbers ("
                          + "; ".join(faults) + "); expected a sheet of numeric columns")

    def _parse(self, rows, header_rows, skip_rows):
        import datetime as dt

        def numeric(v):
            return isinstance(v, (int, float, dt.datetime, dt.time, dt.timedelta)) and \
                not isinstance(v, bool)

        while rows and all(v is None for v in rows[-1]):
            rows.pop()
        width = max((len(r) for r in rows), default=0)
        while width and all(len(r) < width or r[width - 1] is None for r in rows):
            width -= 1
        rows = [(r + [None] * width)[:width] for r in rows]
        if header_rows is not None or skip_rows is not None:
            first = int(skip_rows or 0) + int(header_rows or 0)
        else:
            first = next((i for i, r in enumerate(rows)
                          if any(numeric(v) for v in r) and all(
                              numeric(v) or v is None for v in r)), None)
            if first is None:
                raise RecordError(f"{self.file}: sheet {self.sheet!r} has no row of numbers "
                                  f"({len(rows)} rows); expected a table of numbers")
        head = rows[:first]
        data = rows[first:]
        if not data:
            raise RecordError(f"{self.file}: sheet {self.sheet!r} has a header but no data rows")
        header = [r for r in head if any(isinstance(v, str) and v.strip() for v in r)]
        n_header = 0
        for r in reversed(header):  # header rows: the text rows right above the data, filled
            filled = sum(v is not None for v in r)
            if sum(isinstance(v, str) for v in r) >= max(1, 0.5 * filled) and \
                    filled >= max(1, 0.5 * width):
                n_header += 1
            else:
                break
        header = header[len(header) - n_header:] if n_header else []
        from .text import _looks_like_units, _rate_from

        names, units = [None] * width, [None] * width
        texts = [[("" if v is None else str(v)).strip() for v in r] for r in header]
        unit_rows = [r for r in texts if _looks_like_units(r)]
        name_rows = [r for r in texts if not _looks_like_units(r)]
        if name_rows:
            names = [t or None for t in name_rows[0]]
        if unit_rows and name_rows:
            units = [t.strip("[]()").strip() or None for t in unit_rows[0]]
        self.sample_rate = _rate_from([" ".join(str(v) for v in r if v is not None)
                                       for r in rows[:first]])
        self.names, self.units, self.n_columns = names, units, width
        self.header_rows, self.skip_rows = n_header, first - n_header
        self._data = data

    def describe(self) -> str:
        return (f"sheet {self.sheet!r}, {self.header_rows} header row(s), "
                f"{self.skip_rows} row(s) before the header")

    def read(self, columns) -> np.ndarray:
        import datetime as dt

        out = np.full((len(columns), len(self._data)), np.nan)
        for j, c in enumerate(columns):
            if not 0 <= c < self.n_columns:
                raise RecordError(f"{self.file}: column {c + 1} does not exist; {self.describe()}"
                                  f" has {self.n_columns} column(s)")
            first_time = None
            for i, row in enumerate(self._data):
                v = row[c]
                if v is None:
                    continue
                if isinstance(v, bool) or isinstance(v, str):
                    text = str(v).strip()
                    try:
                        v = float(text.replace(",", ".")) if text else float("nan")
                    except ValueError:
                        line = self.skip_rows + self.header_rows + i + 1
                        raise RecordError(f"{self.file}: sheet {self.sheet!r}, row {line}, "
                                          f"{self.label(c)}: {text!r} is not a number; expected "
                                          "numbers in every data cell") from None
                elif isinstance(v, (dt.datetime, dt.time, dt.timedelta)):
                    if isinstance(v, dt.time):
                        v = dt.timedelta(hours=v.hour, minutes=v.minute, seconds=v.second,
                                         microseconds=v.microsecond)
                    first_time = v if first_time is None else first_time
                    v = (v - first_time).total_seconds()
                out[j, i] = float(v)
        return out


def open_table(path, module_name, *, source=None) -> Table:
    """The :class:`Table` of a text or spreadsheet file, with the map's ``[source]`` hints."""
    source = dict(source or {})
    if module_name == "xlsx":
        return SheetTable(path, source.get("sheet"), header_rows=source.get("header_rows"),
                          skip_rows=source.get("skip_rows"))
    hints = {k: source[k] for k in ("delimiter", "decimal", "header_rows", "skip_rows",
                                     "encoding") if k in source}
    return TextTable(path, **hints)


def _time_from(table, index, unit, file, t):
    """Check and convert the time column ``t`` (values as read)."""
    from ..units import to_si

    finite = np.flatnonzero(np.isfinite(t))
    n = int(finite[-1]) + 1 if finite.size else 0
    t = t[:n]
    if unit not in (None, "", "s") and index not in table.clock_columns:
        t, si, _ = to_si(t, unit, channel=table.names[index])
        if si != "s":
            raise RecordError(f"{file}: time {table.label(index)} has unit {unit!r}; expected "
                              "a time unit (s, ms)")
    if n < 2:
        raise RecordError(f"{file}: time {table.label(index)} has {n} value(s); expected at "
                          "least 2 to infer the sample rate")
    if not np.all(np.isfinite(t)):
        i = int(np.flatnonzero(~np.isfinite(t))[0])
        raise RecordError(f"{file}: time {table.label(index)} is empty or NaN/inf at data row "
                          f"{i + 1}; expected a time in every row")
    return _unrounded(t, file, table.label(index), table)


def _printed_resolution(t: np.ndarray) -> tuple:
    """The printed step of each stamp (s) under the two ways loggers print time: fixed decimals
    (``%.3f``: one step for the column, ``10**-k`` with ``k`` the most decimals any stamp
    needs) and significant digits (``%.6g``: ``9.99988`` then ``10.0001``, the step growing
    tenfold at each power of ten, ``S`` = the most significant digits any stamp needs).
    Returns ``(fixed, significant)``, each an array like ``t``."""
    digits = np.full(t.size, 15, dtype=np.int64)
    undecided = np.ones(t.size, bool)
    for k in range(15):
        scaled = t[undecided] * 10.0 ** k
        exact = np.abs(scaled - np.rint(scaled)) <= 1e-6 + 1e-12 * np.abs(scaled)
        idx = np.flatnonzero(undecided)[exact]
        digits[idx] = k
        undecided[idx] = False
        if not undecided.any():
            break
    fixed = np.full(t.size, 10.0 ** -int(digits.max()))
    nonzero = t != 0
    exponent = np.zeros(t.size, dtype=np.int64)
    exponent[nonzero] = np.floor(np.log10(np.abs(t[nonzero]))).astype(np.int64)
    sig = int((digits + exponent + 1)[nonzero].max()) if nonzero.any() else 0
    significant = np.where(nonzero, 10.0 ** (exponent + 1 - sig), fixed)
    return fixed, significant


def _unrounded(t: np.ndarray, file, label, table=None) -> np.ndarray:
    """A time column printed with fewer decimals than its sample interval needs is a uniform
    clock rounded: 5 kHz as ``%.3f`` (steps of 0 and 1 ms), or 8 kHz as ``%.6g`` (steps of
    0.1 and 0.2 ms once the stamps pass 10 s). It is rebuilt as the uniform grid it rounds,
    with a warning, when every stamp is within (0.6 ×) its printed resolution's half-step of
    that grid; any other irregular column is returned as read (the record's checks name its
    fault: a gap, jitter, a reversal)."""
    step = np.diff(t)
    if t.size < 3 or np.any(step < 0) or not np.all(np.isfinite(t)):
        return t
    dt = (t[-1] - t[0]) / (t.size - 1)
    if not dt > 0 or np.all(np.abs(step - dt) <= 1e-3 * dt):
        return t
    fixed, significant = _printed_resolution(t)
    # least-squares clock through every stamp (the end points alone are off by up to q/2)
    i = np.arange(t.size, dtype=float)
    dt = np.polyfit(i, t - t[0], 1)[0]
    grid = i * dt
    r = t - t[0] - grid
    t0 = t[0] + 0.5 * float(r.max() + r.min())   # the offset with the smallest worst deviation
    r = t - t0 - grid
    # the true clock is within q/2 of every stamp; the least-squares slope can be pulled a
    # little by how the exact half-step stamps happened to round: allow 0.6 q
    # (+ 1e-4 of a sample interval: the fit's own slope and offset error, far below anything
    # an analysis can see, where fine stamps near t = 0 are printed almost exactly)
    q = next((q for q in (fixed, significant) if np.all(np.abs(r) <= 0.6 * q + 1e-4 * dt)),
             None)
    if q is None or not q.max() > 1e-3 * dt:   # printed finely: the clock itself is irregular
        return t
    # a clock whose interval is a whole number of printed steps prints uniformly: any
    # irregular step there (a repeated stamp at 1 kHz printed to 1 ms) is the logger's own
    odd = np.flatnonzero(np.abs(np.diff(t) - dt) > 1e-3 * dt)
    ratio = dt / q[odd]
    if np.any(np.abs(ratio - np.rint(ratio)) < 1e-3):
        return t
    import logging

    note = (f"time {label} is rounded to {float(q.max()):.3g} s, and its {dt:.3g} s sample "
            "interval is not a whole number of those steps (stamps irregular by their printed "
            f"decimals): rebuilt as a uniform {1.0 / dt:.6g} Hz clock (every stamp within "
            f"{float(np.abs(r).max()):.2g} s of it, about half the rounding step)")
    logging.getLogger("crankbench").warning("%s: %s", file, note)
    if table is not None:
        read_note(table, note)
    return t0 + grid


def last_row_cut(table, last_row: np.ndarray) -> bool:
    """Whether a table's last row may have been cut mid-write: a logger stopped while writing
    leaves a last line without its line break, with cells missing or a number cut short
    (``76.5564`` written as ``7``) that no check can tell from a real value. Such a row is
    dropped by the callers, with a warning and a ``read_notes`` entry; it costs one sample
    of a complete file that merely lacks its final line break. A last line of text (a
    footer) or one ending in a line break is kept whatever it holds."""
    last_row = np.asarray(last_row, float)
    if not isinstance(table, TextTable):
        return False
    try:
        with open(table.file, "rb") as f:
            f.seek(0, 2)
            size = f.tell()
            f.seek(max(0, size - 4096))
            tail = f.read()
    except OSError:
        return False
    if not tail or tail.endswith((b"\n", b"\r")):
        return False
    line = tail.rsplit(b"\n", 1)[-1].decode("utf-8", "replace")
    if any(c.isalpha() and c not in "eE" for c in line):     # a footer, not a data row
        return False
    import logging

    empty = int(np.count_nonzero(~np.isfinite(last_row)))
    note = ("the last line has no line break: the file was cut while writing (logger stopped?)"
            f"{f' and the row has {empty} empty cell(s)' if empty else ''}; that row is dropped "
            "(a number cut short would look valid)")
    logging.getLogger("crankbench").warning("%s: %s", table.file, note)
    read_note(table, note)
    return True


def read_note(table, note: str) -> None:
    """Keep what reading changed (a rebuilt clock, a dropped row) with the table: the record
    carries it as its ``read_notes`` attr, so an imported or reported record still says so."""
    notes = getattr(table, "read_notes", None)
    if notes is None:
        notes = []
        table.read_notes = notes
    notes.append(note)


def read_notes_attrs(table) -> dict:
    """``{"read_notes": "...; ..."}`` for a record read from ``table``, or ``{}``."""
    notes = getattr(table, "read_notes", None)
    return {"read_notes": "; ".join(notes)} if notes else {}


def duplicate_names(table) -> None:
    """Refuse two columns with the same header (they would silently become one channel)."""
    seen: dict = {}
    for i, name in enumerate(table.names):
        if not name:
            continue
        key = split_header(name)[0]
        if key in seen:
            raise RecordError(
                f"{table.file}: columns {seen[key] + 1} and {i + 1} are both named {key!r} "
                f"({table.describe()}); channel names must be unique — rename one, or read "
                "the file with a channel map that names each column by its number")
        seen[key] = i


def table_record(table: Table, *, channels=None):
    """A Record from a table's headers alone (no channel map).

    Each column header is ``name [unit]`` (or ``name (unit)``, or a units row gives the unit);
    the time axis is the column named time/t (with a time unit), else the first column of
    date/time text (seconds from its first stamp; the stamp is the record's ``start_time``),
    else the sample rate stated in the file.

    Raises
    ------
    RecordError
        No header row, no unit for a column, no time column and no stated sample rate,
        duplicate names — each naming the file, the column, how the file was read and the map
        setting that would supply what is missing.
    """
    from ._common import build_dataset, select, si_channel

    file = table.file
    if not any(table.names):
        raise RecordError(
            f"{file}: no header row (read as {table.describe()}): channel names and units "
            f"cannot be inferred for its {table.n_columns} column(s); give a channel map "
            "(measure.read(path, map=...), --map MAP.toml) naming each column's units")
    duplicate_names(table)
    parsed = []
    from_names = []
    for i, header in enumerate(table.names):
        name, unit = split_header(header)
        if unit is None and i < len(table.units) and table.units[i]:
            unit = table.units[i]
        if unit is None and suffix_unit(name) is not None:
            unit = suffix_unit(name)
            from_names.append(f"{name} -> {unit}")
        elif unit is None and name_is_unit(name) is not None:
            unit = name_is_unit(name)
            from_names.append(f"{name} -> {unit}")
        parsed.append((name or f"column {i + 1}", unit))
    if from_names:
        import logging

        logging.getLogger("crankbench").info("%s: units read from the column names: "
                                             "%s", file, ", ".join(from_names))
    headers = [str(h) for h in table.names]

    def is_time(name, unit):
        key = name.strip().lower() if name else ""
        if key in TIME_NAMES:
            return True
        return bool(unit) and suffix_unit(name) == unit and \
            key.rpartition("_")[0] in TIME_NAMES
    clocks = tuple(table.clock_columns)
    time_idx = next((i for i, (name, unit) in enumerate(parsed) if is_time(name, unit)), None)
    if time_idx is None and clocks:
        time_idx = clocks[0]
    skipped = [i for i in clocks if i != time_idx]  # date/time text is no channel
    if skipped:
        import logging

        logging.getLogger("crankbench").info(
            "%s: date/time %s not read (the time axis is %s)", file,
            ", ".join(table.label(i) for i in skipped), table.label(time_idx))
    if time_idx is None and not table.sample_rate:
        from .angle_table import angle_column_of

        angle = angle_column_of(table)
        hint = "" if angle is None else (
            f"; {table.label(angle)} is a crank angle: an indicating system's "
            "angle-domain export is analysed by `crankbench pressure FILE --model ENGINE.toml` "
            "(measure.readers.angle_table), not read as a time record")
        raise RecordError(f"{file}: no time column; expected a first column named 'time [s]' "
                          f"(found columns {headers}), or a sample rate: give a channel map "
                          f"with [source] sample_rate (Hz) or time_column{hint}")
    names = [p[0] for i, p in enumerate(parsed) if i != time_idx and i not in skipped]
    wanted = select(names, channels, file=file)
    idx = [i for i, (name, _) in enumerate(parsed)
           if i != time_idx and i not in skipped and name in wanted]
    for i in idx:
        name, unit = parsed[i]
        if unit is None:
            raise RecordError(f"{file}: column {headers[i]!r} names no unit; expected "
                              f"'{name} [unit]', e.g. '{name} [g]', or a channel map giving its "
                              "units")
    both = table.read(([time_idx] if time_idx is not None else []) + idx)  # one pass
    if both.ndim == 2 and both.shape[1] > 1 and last_row_cut(table, both[:, -1]):
        both = both[:, :-1]
    t = None
    if time_idx is not None:
        t = _time_from(table, time_idx, parsed[time_idx][1], file, both[0])
        span = t[-1] - t[0]
        fs = (t.size - 1) / span if np.isfinite(span) and span > 0 else float("nan")
        data = both[1:]
    else:
        fs = float(table.sample_rate)
        data = both
    if t is None:
        n = data.shape[1] if data.size else 0
        from ..record import time_coordinate

        t = time_coordinate(n, fs)
    out = []
    for row, i in enumerate(idx):
        name, unit = parsed[i]
        values = data[row, :t.size]
        values, attrs = si_channel(name, values, {"units": unit, "sample_rate": fs}, file=file)
        out.append((name, "time", values, attrs))
    attrs = {"units_from_names": "; ".join(from_names)} if from_names else {}
    attrs.update(read_notes_attrs(table))
    if time_idx in clocks:
        attrs.update(getattr(table, "start_times", {}).get(time_idx, {}))
    return build_dataset(out, {"time": t}, attrs)
