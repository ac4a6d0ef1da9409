"""Delimited text tables of any common dialect: sniffed, then parsed column-wise with bounded
memory.

Test benches export text in every dialect: comma, tab, semicolon or runs of spaces between
fields, a decimal point or a decimal comma, a UTF-8 byte-order mark (or Windows-1252 text with
``°`` and ``µ``), a preamble of free text (``Sample rate: 100 kHz``), one header row of names,
a second of units, or no header at all. :func:`sniff` reads the first 64 kB and works out

* the encoding (BOM, UTF-8, else Windows-1252),
* the delimiter and decimal mark: every candidate pair is tried on the lines from the end of
  the sample up; the one that reads the longest run of fully numeric rows with one field count
  wins (more fields first when two tie, a named tab/semicolon/comma before whitespace), and a
  header row whose field count agrees breaks a tie between field counts — if nothing can,
  the error says which readings were possible and which setting to give;
* header rows: the lines right above the data with the same field count (a units row is
  recognised by its unit spellings), the preamble above them, and a sample rate or time step
  stated in the preamble.

A column of date/time text (``2026-11-24 10:00:00.301``, ISO with ``T`` and a UTC offset,
``24.11.2026 10:00:00,301``, ``2026/11/24 10:00:00``, ``10:00:00.301``; see
:mod:`measure.readers.clock`) counts as data too: the sniffer records its format
(``Dialect.clocks``), keeps a date and its time one field when runs of whitespace separate
the fields, and requires every cell of that column to be a stamp of that format and every other
cell a number.

:func:`read_columns` then parses only the wanted columns with pandas' C parser in chunks of
65 536 rows into one preallocated ``(columns, rows)`` float64 array, so memory stays at the size
of the numbers kept (8 bytes a value) plus one chunk, and a bad cell is reported with its
line, column and the dialect it was read with. A date/time column becomes seconds from its
first stamp (float64, parsed per chunk with pandas' ``to_datetime`` and the column's format);
a bad stamp is reported with its line, column and the format expected.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from crankbench.predict.errors import RecordError

from .clock import StampParser, join_split_stamps, same_kind, stamp_format

__all__ = ["Dialect", "sniff", "read_columns", "describe_delimiter", "DELIMITERS"]

#: delimiter names accepted in channel maps -> the delimiter (None: runs of whitespace)
DELIMITERS = {",": ",", "comma": ",", ";": ";", "semicolon": ";", "\t": "\t", "tab": "\t",
              "|": "|", "pipe": "|", " ": None, "space": None, "whitespace": None}
_CANDIDATES = ("\t", ";", ",", "|", None)
_SAMPLE_BYTES = 1 << 16
_CHUNK_ROWS = 1 << 16
_RATE_RE = re.compile(
    r"(?:sample[ _-]?rate|sampling[ _-]?(?:rate|frequency)|abtastrate|fs)\s*[:=]?\s*"
    r"([0-9]+(?:[.,][0-9]+)?(?:[eE][+-]?[0-9]+)?)\s*(hz|khz|mhz|s/s|ks/s)?", re.IGNORECASE)
_STEP_RE = re.compile(
    r"(?:delta[ _-]?t|delta_x|time[ _-]?step|sample[ _-]?interval|increment|dt)\s*[:=]?\s*"
    r"([0-9]+(?:[.,][0-9]+)?(?:[eE][+-]?[0-9]+)?)\s*(s|ms|us|µs)?\b", re.IGNORECASE)
_NA = {"", "nan", "na", "n/a", "-nan", "inf", "-inf", "+inf", "infinity", "-infinity"}


def describe_delimiter(delimiter) -> str:
    """Words for a delimiter."""
    return {",": "comma-separated", ";": "semicolon-separated", "\t": "tab-separated",
            "|": "pipe-separated", None: "whitespace-separated", "": "one column"}[delimiter]


@dataclass(frozen=True)
class Dialect:
    """How a text table is written.

    Attributes
    ----------
    delimiter : str or None
        Field separator; None for runs of whitespace, "" for a single column.
    decimal : str
        "." or ",".
    header_rows : int
        Header lines above the data (names, maybe units).
    skip_rows : int
        Physical lines before the header (preamble, comments, blank lines).
    encoding : str
    n_columns : int
    names : tuple
        Header text per column (None without a header).
    units : tuple
        Unit per column from a units row (None where there is none).
    sample_rate : float or None
        Stated in the preamble (Hz), if found.
    bom : bool
    """

    delimiter: str | None
    decimal: str
    header_rows: int
    skip_rows: int
    encoding: str
    n_columns: int
    names: tuple = ()
    units: tuple = ()
    sample_rate: float | None = None
    bom: bool = False
    notes: tuple = field(default=(), compare=False)
    clocks: tuple = ()

    @property
    def clock_columns(self) -> tuple:
        """0-based columns holding date/time text (read as seconds from their first stamp)."""
        return tuple(c for c, _, _ in self.clocks)

    @property
    def data_start(self) -> int:
        """Physical line number (0-based) of the first data row."""
        return self.skip_rows + self.header_rows

    def describe(self) -> str:
        """E.g. 'tab-separated, decimal comma, 2 header rows, UTF-8 with BOM'."""
        parts = [describe_delimiter(self.delimiter),
                 "decimal comma" if self.decimal == "," else "decimal point",
                 f"{self.header_rows} header row{'s' if self.header_rows != 1 else ''}"
                 if self.header_rows else "no header row"]
        if self.skip_rows:
            parts.append(f"{self.skip_rows} line{'s' if self.skip_rows != 1 else ''} before "
                         "the header")
        parts.append({"utf-8-sig": "UTF-8 with BOM", "utf-8": "UTF-8", "cp1252":
                      "Windows-1252", "utf-16": "UTF-16"}.get(self.encoding, self.encoding))
        parts += [f"date/time in column {c + 1} ({fmt})" for c, fmt, _ in self.clocks]
        return ", ".join(parts)


def _encoding(head: bytes) -> tuple[str, bool]:
    if head.startswith(b"\xef\xbb\xbf"):
        return "utf-8-sig", True
    if head.startswith((b"\xff\xfe", b"\xfe\xff")):
        return "utf-16", True
    try:
        head.decode("utf-8")
        return "utf-8", False
    except UnicodeDecodeError as exc:
        if exc.start >= len(head) - 3:  # a multi-byte character cut by the sample's end
            return "utf-8", False
        return "cp1252", False


def _number(token: str, decimal: str) -> bool:
    tok = token.strip().strip('"').strip("'").strip()
    if tok.lower() in _NA:
        return True
    if decimal == ",":
        if "." in tok:
            return False
        tok = tok.replace(",", ".")
    try:
        float(tok)
    except ValueError:
        return False
    return True


def _value(token: str, decimal: str) -> bool:
    """A number, an empty/NaN cell or a date/time stamp."""
    return _number(token, decimal) or stamp_format(token) is not None


def _split(line: str, delimiter) -> list[str]:
    if delimiter == "":
        return [line.strip()]
    if delimiter is None:
        # a date and the time after it are one stamp, not two whitespace-separated fields
        return join_split_stamps(line.split())
    return [f for f in _split_quoted(line, delimiter)]


def _split_quoted(line: str, delimiter: str) -> list[str]:
    if '"' not in line:
        return line.rstrip("\r\n").split(delimiter)
    out, cur, quoted = [], [], False
    for ch in line.rstrip("\r\n"):
        if ch == '"':
            quoted = not quoted
        elif ch == delimiter and not quoted:
            out.append("".join(cur))
            cur = []
            continue
        cur.append(ch)
    out.append("".join(cur))
    return out


def _row(line, delimiter, decimal):
    """(fields, numeric) of one line read with a delimiter and decimal mark."""
    fields = _split(line, delimiter)
    numeric = all(_value(f, decimal) for f in fields) and not all(
        f.strip() == "" for f in fields)
    return fields, numeric


def _longest_run(lines, delimiter, decimal) -> tuple[int, int, int]:
    """(start, rows, fields) of the longest run of numeric rows with one field count."""
    best = (0, 0, 0)
    start, k, rows = 0, None, 0
    for i, line in enumerate(lines):
        fields, numeric = _row(line, delimiter, decimal)
        if numeric and len(fields) == k:
            rows += 1
        elif numeric:
            start, k, rows = i, len(fields), 1
        else:
            k, rows = None, 0
        if rows > best[1]:
            best = (start, rows, k)
    return best


def _header_fields(line, delimiter, k, trailing=False):
    fields = _split(line, delimiter)
    if delimiter not in (None, "") and len(fields) == k + 1 and fields[-1].strip() == "":
        fields = fields[:-1]
    if trailing and len(fields) == k - 1:
        fields = fields + [""]  # data rows end with a delimiter, the header does not
    if len(fields) != k and delimiter is None:
        fields = [f for f in re.split(r"\t|\s{2,}", line.strip())]
    if len(fields) != k and k == 1:
        fields = [line.strip()]
    return [f.strip().strip('"').strip() for f in fields] if len(fields) == k else None


def _looks_like_units(fields) -> bool:
    from ..units import unit_factor

    known = 0
    for f in fields:
        text = f.strip().strip("[]()").strip()
        if not text:
            continue
        try:
            unit_factor(text)
            known += 1
        except RecordError:
            return False
    return known > 0


def _rate_from(preamble) -> float | None:
    for line in preamble:
        m = _RATE_RE.search(line)
        if m:
            value = float(m.group(1).replace(",", "."))
            unit = (m.group(2) or "hz").lower()
            value *= {"hz": 1.0, "khz": 1e3, "mhz": 1e6, "s/s": 1.0, "ks/s": 1e3}[unit]
            if value > 0:
                return value
        m = _STEP_RE.search(line)
        if m:
            step = float(m.group(1).replace(",", "."))
            step *= {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6}[(m.group(2) or "s").lower()]
            if step > 0:
                return 1.0 / step
    return None


def sniff(path, *, delimiter=..., decimal=None, header_rows=None, skip_rows=None,
          encoding=None, comment="#") -> Dialect:
    """Work out how a text table is written (see the module docstring).

    Parameters
    ----------
    path : path-like
    delimiter : str or None, optional
        Known delimiter (None = whitespace, "" = one column); default sniffed.
    decimal : {".", ","}, optional
    header_rows : int, optional
        Header lines above the data (after ``skip_rows``).
    skip_rows : int, optional
        Lines before the header.
    encoding : str, optional
    comment : str
        Lines starting with this are skipped when sniffing (crankbench's own metadata lines).

    Returns
    -------
    Dialect

    Raises
    ------
    RecordError
        Naming the file and exactly what could not be inferred (no numeric rows; several
        readings possible) and the setting that fixes it.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "bench.txt"
    >>> _ = p.write_text("Sample rate: 10 kHz\\nt\\tp\\ns\\tbar\\n0,0\\t1,5\\n0,1\\t1,25\\n",
    ...                  encoding="utf-8-sig")
    >>> d = sniff(p)
    >>> d.describe(), d.names, d.units, d.sample_rate
    ('tab-separated, decimal comma, 2 header rows, 1 line before the header, UTF-8 with BOM', ('t', 'p'), ('s', 'bar'), 10000.0)
    """
    path = Path(path)
    file = str(path)
    with path.open("rb") as f:
        head = f.read(_SAMPLE_BYTES)
        truncated = bool(f.read(1))
    enc, bom = (encoding, False) if encoding else _encoding(head)
    if encoding is None and bom and enc == "utf-8-sig":
        bom = True
    text = head.decode("utf-16" if enc == "utf-16" else enc, errors="replace")
    if text.startswith("\ufeff"):
        text = text[1:]
    lines = text.splitlines()
    if truncated and lines:
        lines = lines[:-1]  # the sample may end mid-line
    physical = list(range(len(lines)))
    keep = [i for i in physical if lines[i].strip() and not (comment and
                                                             lines[i].startswith(comment))]
    if not keep:
        raise RecordError(f"{file}: no data lines (only blank or '{comment}' comment lines); "
                          "expected rows of numbers")
    fixed_start = None
    if header_rows is not None or skip_rows is not None:
        fixed_start = int(skip_rows or 0) + int(header_rows or 0)
    data_index = [i for i in keep if fixed_start is None or i >= fixed_start][:2000]
    body = [lines[i] for i in data_index]
    delims = _CANDIDATES if delimiter is ... else (delimiter,)
    decs = (".", ",") if decimal is None else (decimal,)
    readings = []
    for d in delims:
        for dec in decs:
            if d == "," and dec == ",":
                continue
            start, rows, k = _longest_run(body, d, dec)
            if rows:
                readings.append((rows, k, d, dec, start))
    if not readings:
        given = []
        if delimiter is not ...:
            given.append(f"delimiter {delimiter!r}")
        if decimal is not None:
            given.append(f"decimal {decimal!r}")
        tried = ", ".join(given) or ("tried comma, tab, semicolon, pipe and whitespace "
                                     "delimiters with a decimal point or comma")
        if len(body) <= 3:
            raise RecordError(f"{file}: the table has a header but no data rows "
                              f"({len(body)} line(s), the last {body[-1][:80]!r}); expected "
                              "rows of numbers under it")
        raise RecordError(
            f"{file}: cannot find rows of numbers to read ({tried}); the last line reads "
            f"{body[-1][:80]!r}; expected a table of numbers (set delimiter, decimal and "
            "header_rows in the map's [source] table)")
    best_rows = max(r[0] for r in readings)
    top = [r for r in readings if r[0] == best_rows]
    # a header line with the same field count decides between field counts
    if len({r[1] for r in top}) > 1 and fixed_start is None:
        agree = []
        for r in top:
            if r[4] > 0:
                above = body[r[4] - 1]
                fields = _header_fields(above, r[2], r[1])
                if r[1] == 1 and any(c in above for c in ",;\t|"):
                    continue  # a one-column reading whose header holds a delimiter
                if fields is not None and not all(_value(f, r[3]) for f in fields):
                    agree.append(r)
        if agree:
            top = agree
    top = [(r, k, "" if k == 1 else d, dec, st) for r, k, d, dec, st in top]
    top = list(dict.fromkeys(top))
    if len({r[1] for r in top}) > 1 and delimiter is ...:
        options = "; or ".join(f"{describe_delimiter(d)} with decimal "
                               f"{'comma' if dec == ',' else 'point'} ({k} column"
                               f"{'s' if k != 1 else ''})" for _, k, d, dec, _ in top[:4])
        raise RecordError(f"{file}: the delimiter cannot be inferred: every row reads as "
                          f"{options}; set delimiter and decimal in the map's [source] table")
    rank = {c: i for i, c in enumerate(_CANDIDATES + ("",))}
    top.sort(key=lambda r: (-r[1], rank[r[2]], r[3] != "."))
    rows, k, delim, dec, start = top[0]
    trailing = k >= 2 and delim not in (None, "") and all(
        _split(body[i], delim)[-1].strip() == "" for i in range(start, start + rows))
    if trailing and start > 0:  # an all-empty last column the header names is a column
        named = _split(body[start - 1], delim)
        trailing = not (len(named) == k and named[-1].strip())
    clocks = _clocks(body, data_index, start, rows, delim, dec, k, file)
    # every line after the run must be a data row too: else name the bad cell
    for i in range(start + rows, len(body)):
        fields, numeric = _row(body[i], delim, dec)
        if numeric and len(fields) == k:
            _check_kinds(fields, clocks, data_index[i] + 1, delim, dec, file)
            continue
        line_no = data_index[i] + 1
        if len(fields) != k:
            raise RecordError(f"{file}: line {line_no} has {len(fields)} field(s) where the "
                              f"table has {k} (read as {describe_delimiter(delim)}, decimal "
                              f"{'comma' if dec == ',' else 'point'}): {body[i][:80]!r}")
        _check_kinds(fields, clocks, line_no, delim, dec, file)
        col = next(c for c, f in enumerate(fields) if not _number(f, dec))
        raise RecordError(f"{file}: line {line_no}, column {col + 1}: {fields[col].strip()!r} "
                          f"is not a number (read as {describe_delimiter(delim)}, decimal "
                          f"{'comma' if dec == ',' else 'point'}); expected numbers in every "
                          "data cell")
    first_data = start
    # header and preamble
    first_line = data_index[first_data] if data_index else 0
    if fixed_start is not None:
        n_header = int(header_rows or 0)
        n_skip = int(skip_rows or 0)
        head_lines = lines[n_skip:n_skip + n_header]
        if first_line != n_skip + n_header:
            bad = lines[n_skip + n_header] if n_skip + n_header < len(lines) else ""
            raise RecordError(
                f"{file}: line {n_skip + n_header + 1} ({bad[:60]!r}) is not a row of {k} "
                f"numbers read as {describe_delimiter(delim)} with decimal "
                f"{'comma' if dec == ',' else 'point'}, but skip_rows={n_skip} and "
                f"header_rows={n_header} put the data there")
    else:
        head_lines = []
        j = first_line - 1
        while j >= 0:
            line = lines[j]
            if not line.strip() or (comment and line.startswith(comment)):
                break
            fields = _header_fields(line, delim, k, trailing)
            if fields is None or all(_value(f, dec) for f in fields):
                break
            head_lines.insert(0, line)
            j -= 1
        n_header = len(head_lines)
        n_skip = first_line - n_header
        if j >= 0 and head_lines:
            # a "header" with numeric rows above it is a bad data row, not a header
            above_fields = _header_fields(lines[j], delim, k)
            if above_fields is not None and all(_value(f, dec) for f in above_fields):
                bad = _header_fields(head_lines[0], delim, k)
                _check_kinds(bad, clocks, j + 2, delim, dec, file)
                col = next(i for i, f in enumerate(bad) if not _value(f, dec))
                raise RecordError(
                    f"{file}: line {j + 2}, column {col + 1}: {bad[col]!r} is not a number "
                    f"(read as {describe_delimiter(delim)}, decimal "
                    f"{'comma' if dec == ',' else 'point'}); expected numbers in every data "
                    "cell")
    names, units = (), ()
    parsed = [_header_fields(h, delim, k, trailing) for h in head_lines]
    parsed = [p for p in parsed if p is not None]
    if parsed:
        unit_rows = [p for p in parsed if _looks_like_units(p)]
        name_rows = [p for p in parsed if not _looks_like_units(p)]
        names = tuple((f or None) for f in (name_rows[0] if name_rows else parsed[0]))
        if unit_rows and name_rows:
            units = tuple((f.strip("[]()").strip() or None) for f in unit_rows[0])
    preamble = lines[:n_skip]
    if trailing:  # every row ends with a delimiter: no column after it
        k -= 1
        names, units = names[:k], units[:k]
    return Dialect(delimiter=delim, decimal=dec, header_rows=n_header, skip_rows=n_skip,
                   encoding=enc, n_columns=k, names=names, units=units,
                   sample_rate=_rate_from(preamble), bom=bom,
                   clocks=tuple(c for c in clocks if c[0] < k))


def _clocks(body, data_index, start, rows, delim, dec, k, file) -> list:
    """[(column, format, example)] of the columns of date/time text in the run of data rows,
    each checked to hold stamps of one format (or empty cells) and the others numbers."""
    clocks = {}
    for i in range(start, start + rows):
        for c, f in enumerate(_split(body[i], delim)):
            fmt = stamp_format(f)
            if fmt is not None and c not in clocks:
                clocks[c] = (c, fmt, f.strip().strip('"').strip())
    clocks = [clocks[c] for c in sorted(clocks)]
    for i in range(start, start + rows):
        _check_kinds(_split(body[i], delim), clocks, data_index[i] + 1, delim, dec, file)
    return clocks


def _check_kinds(fields, clocks, line_no, delim, dec, file) -> None:
    """A stamp in a numbers column, a number or another format in a date/time column:
    an error naming line, column and what was expected."""
    how = f"read as {describe_delimiter(delim)}, decimal {'comma' if dec == ',' else 'point'}"
    formats = {c: (fmt, example) for c, fmt, example in clocks}
    for c, f in enumerate(fields):
        cell = f.strip().strip('"').strip()
        if c in formats:
            fmt, example = formats[c]
            got = stamp_format(cell)
            if cell.lower() not in _NA and (got is None or not same_kind(got, fmt)):
                raise RecordError(f"{file}: line {line_no}, column {c + 1}: {cell!r} is not a "
                                  f"date/time of the column's format {fmt} (like {example!r}; "
                                  f"{how}); expected a date/time in every data cell")
        elif not _number(cell, dec):
            raise RecordError(f"{file}: line {line_no}, column {c + 1}: {cell!r} is not a "
                              f"number ({how}); expected numbers in every data cell")


def _count_lines(path) -> int:
    n, last = 0, b"\n"
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 22), b""):
            n += block.count(b"\n")
            last = block[-1:]
    return n + (last != b"\n")


def read_columns(path, dialect: Dialect, columns=None, *, file=None, starts=None) -> np.ndarray:
    """Parse the data rows of ``columns`` (0-based; default all) into a (k, rows) float array.

    Empty cells and NaN spellings become NaN (trailing empty cells of short columns); any
    other non-number is an error naming line, column and dialect. A date/time column
    (``dialect.clocks``) becomes seconds from its first stamp (:mod:`measure.readers.clock`).
    Memory: the array plus one chunk of 65 536 rows.

    Parameters
    ----------
    starts : dict, optional
        Filled with ``{column: {"start_time": ISO 8601}}`` (or ``start_time_of_day``) for each
        date/time column read.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "x.csv"
    >>> _ = p.write_text("1;2,5;3\\n4;5,5;6\\n")
    >>> read_columns(p, sniff(p), [0, 1]).tolist()
    [[1.0, 4.0], [2.5, 5.5]]
    >>> _ = p.write_text("24.11.2026 23:59:59,9;2,5\\n25.11.2026 00:00:00,1;3\\n")
    >>> starts = {}
    >>> read_columns(p, sniff(p), [0, 1], starts=starts).round(6).tolist(), starts
    ([[0.0, 0.2], [2.5, 3.0]], {0: {'start_time': '2026-11-24T23:59:59.900000'}})
    """
    import pandas as pd

    file = file or str(path)
    cols = list(range(dialect.n_columns)) if columns is None else [int(c) for c in columns]
    for c in cols:
        if not 0 <= c < dialect.n_columns:
            raise RecordError(f"{file}: column {c + 1} does not exist; the table has "
                              f"{dialect.n_columns} column(s) ({dialect.describe()})")
    upper = max(_count_lines(path) - dialect.data_start, 0)
    out = np.empty((len(cols), upper), dtype=np.float64)
    if not cols:
        return out
    clocks = {c: (fmt, example) for c, fmt, example in dialect.clocks}
    # whitespace-separated: a date-time stamp is two fields on the line (date, time)
    split = {c for c, (fmt, _) in clocks.items() if dialect.delimiter is None and " " in fmt}

    def field(c):
        return c + sum(1 for s in split if s < c)
    n_fields = dialect.n_columns + len(split)
    used = sorted({field(c) for c in cols} | {field(c) + 1 for c in cols if c in split})
    text_fields = {field(c) for c in clocks} | {field(c) + 1 for c in split}
    kwargs = dict(sep=dialect.delimiter if dialect.delimiter not in (None, "") else r"\s+",
                  decimal=dialect.decimal, header=None, skiprows=dialect.data_start,
                  usecols=used, dtype={f: (str if f in text_fields else np.float64)
                                       for f in used},
                  encoding=dialect.encoding, skip_blank_lines=True, engine="c", comment=None,
                  na_values=["", "nan", "NaN", "NAN", "-nan", "n/a", "N/A", "NA"],
                  keep_default_na=False, names=list(range(n_fields))
                  if dialect.delimiter != "" else [0], index_col=False)
    if dialect.delimiter == "":
        kwargs["sep"] = "\x1f"  # one column: a separator no number contains
    parsers = {}
    for c in cols:
        if c in clocks and c not in parsers:
            name = dialect.names[c] if c < len(dialect.names) and dialect.names[c] else None
            parsers[c] = StampParser(*clocks[c], file=file, label=f"column {c + 1}" + (
                f" ({name!r})" if name else ""))
    row = 0
    try:
        reader = pd.read_csv(path, chunksize=_CHUNK_ROWS, **kwargs)
        for chunk in _chunks(reader, path, dialect, kwargs, file, text_fields):
            m = chunk.shape[0]
            if row + m > out.shape[1]:  # more rows than newlines counted (\r line ends)
                out = np.concatenate([out, np.empty((len(cols), row + m - out.shape[1]))], 1)
            for j, c in enumerate(cols):
                if c in parsers:
                    cells = chunk[field(c)]
                    if c in split:
                        cells = cells + " " + chunk[field(c) + 1]
                    out[j, row:row + m] = parsers[c].seconds(
                        cells, first_line=dialect.data_start + row + 1)
                else:
                    out[j, row:row + m] = chunk[field(c)].to_numpy(dtype=np.float64)
            row += m
    except pd.errors.EmptyDataError:
        row = 0
    if starts is not None:
        starts.update({c: p.start_attrs() for c, p in parsers.items()})
    return out[:, :row]


def _chunks(reader, path, dialect, kwargs, file, text_fields=()):
    """Iterate the reader's chunks, turning parse errors into messages naming line and cell."""
    import pandas as pd

    start = 0
    while True:
        try:
            chunk = next(reader)
        except StopIteration:
            return
        except (ValueError, pd.errors.ParserError) as exc:
            raise _locate(path, dialect, kwargs, start, exc, file, text_fields) from None
        start += chunk.shape[0]
        yield chunk


def _locate(path, dialect, kwargs, start, exc, file, text_fields=()) -> RecordError:
    """The first bad cell at or after data row ``start``, as a RecordError."""
    import pandas as pd

    text = str(exc)
    m = re.search(r"Expected (\d+) fields in line (\d+), saw (\d+)", text)
    if m:
        return RecordError(f"{file}: line {m.group(2)} has {m.group(3)} fields where the table "
                           f"has {m.group(1)} (read as {dialect.describe()}); expected the same "
                           "number of fields on every row")
    loose = dict(kwargs, dtype=str, skiprows=dialect.data_start + start, nrows=_CHUNK_ROWS,
                 na_values=None, keep_default_na=False)
    loose.pop("chunksize", None)
    try:
        frame = pd.read_csv(path, **loose)
    except Exception:  # noqa: BLE001 - the original message is the best we have
        frame = None
    if frame is not None:
        for c in frame.columns:
            if c in text_fields:
                continue  # date/time text: checked by its StampParser
            cells = frame[c].astype(str).to_numpy()
            for i, cell in enumerate(cells):
                if not _number(cell, dialect.decimal):
                    name = dialect.names[c] if c < len(dialect.names) and dialect.names[c] \
                        else None
                    label = f"column {c + 1}" + (f" ({name!r})" if name else "")
                    line = dialect.data_start + start + i + 1
                    return RecordError(
                        f"{file}: line {line}, {label}: {cell!r} is not a number (read as "
                        f"{dialect.describe()}); expected numbers in every data cell")
    return RecordError(f"{file}: the table cannot be read as {dialect.describe()} ({text}); "
                       "expected numbers in every data cell")
