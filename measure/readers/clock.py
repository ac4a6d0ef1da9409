"""Date/time text in a table's time column: recognised, then parsed to seconds from the first
stamp.

Test-bench loggers stamp each row with a clock time instead of seconds. The forms recognised
(a fraction of a second after ``.`` or ``,`` is optional in each):

* ISO 8601 date-time: ``2026-11-24 10:00:00.301`` or ``2026-11-24T10:00:00.301``, optionally
  with a UTC offset (``Z``, ``+01:00``, ``+0100``): every stamp is converted to UTC first, so a
  daylight-saving change inside the record does not make a jump;
* European date-time: ``24.11.2026 10:00:00,301``;
* year-first with slashes: ``2026/11/24 10:00:00.301``;
* time of day: ``10:00:00.301``; a stamp more than 12 h earlier than the one before is the next
  day (midnight roll-over), so the seconds keep increasing.

A date alone (``2026-11-24``) is not a clock: it cannot time samples. Day-first and month-first
slashed dates (``11/24/2026``) are not recognised (they are ambiguous). Parsing uses pandas'
vectorised ``to_datetime`` with the explicit format, chunk by chunk
(:class:`StampParser` carries the first stamp and the day count across chunks).
"""

from __future__ import annotations

import re

import numpy as np

from crankbench.predict.errors import RecordError

__all__ = ["stamp_format", "same_kind", "join_split_stamps", "StampParser"]

_FRACTION = r"(?:(?P<frac>[.,])\d{1,9})?"
_TZ = r"(?P<tz>Z|[+-]\d{2}:?\d{2})?"
_TIME = r"\d{1,2}:\d{2}(?P<sec>:\d{2}" + _FRACTION + ")?"
#: family -> (regex of a stamp, strftime of its date part)
_FAMILIES = {
    "iso": (re.compile(r"^\d{4}-\d{2}-\d{2}(?P<sep>[T ])" + _TIME + _TZ + "$"), "%Y-%m-%d"),
    "dmy": (re.compile(r"^\d{1,2}\.\d{1,2}\.\d{4}(?P<sep> )" + _TIME + "$"), "%d.%m.%Y"),
    "ymd": (re.compile(r"^\d{4}/\d{2}/\d{2}(?P<sep> )" + _TIME + "$"), "%Y/%m/%d"),
    "time": (re.compile(r"^" + _TIME + "$"), ""),
}
_DAY_NS = 86_400 * 10**9
_NA = {"", "nan", "na", "n/a", "-nan", "nat"}


def stamp_format(token) -> str | None:
    """The strftime format of one date/time cell, or None when it is not one.

    Parameters
    ----------
    token : str
        One table cell (outer spaces and quotes ignored).

    Returns
    -------
    str or None
        E.g. ``"%Y-%m-%d %H:%M:%S.%f"``; the fraction separator is the one written
        (``"%d.%m.%Y %H:%M:%S,%f"``), ``%z`` marks a UTC offset.

    Examples
    --------
    >>> stamp_format("2026-11-24 10:00:00.301000"), stamp_format("24.11.2026 10:00:00,301")
    ('%Y-%m-%d %H:%M:%S.%f', '%d.%m.%Y %H:%M:%S,%f')
    >>> stamp_format("10:00:00"), stamp_format("2026-11-24"), stamp_format("1.5")
    ('%H:%M:%S', None, None)
    """
    tok = str(token).strip().strip('"').strip("'").strip()
    if len(tok) < 4 or ":" not in tok:
        return None
    for regex, date in _FAMILIES.values():
        m = regex.match(tok)
        if m is None:
            continue
        fmt = (date + m.group("sep")) if date else ""
        fmt += "%H:%M" + (":%S" if m.group("sec") else "")
        if m.group("frac"):
            fmt += m.group("frac") + "%f"
        if "tz" in m.groupdict() and m.group("tz"):
            fmt += "%z"
        return fmt
    return None


_DATE_ONLY = re.compile(r"^(?:\d{4}-\d{2}-\d{2}|\d{1,2}\.\d{1,2}\.\d{4}|\d{4}/\d{2}/\d{2})$")
_TIME_START = re.compile(r"^\d{1,2}:\d{2}")


def join_split_stamps(fields: list) -> list:
    """Whitespace-split fields with each date and the time after it joined into one stamp.

    Examples
    --------
    >>> join_split_stamps("2026-11-24 10:00:00.301 1230.1 0.46".split())
    ['2026-11-24 10:00:00.301', '1230.1', '0.46']
    """
    fields = list(fields)
    for i in range(len(fields) - 2, -1, -1):
        if _DATE_ONLY.match(fields[i]) and _TIME_START.match(fields[i + 1]):
            fields[i:i + 2] = [fields[i] + " " + fields[i + 1]]
    return fields


def same_kind(fmt_a: str, fmt_b: str) -> bool:
    """Two cells' formats are one column's (they differ at most by a fraction or offset)."""
    def base(f):
        return f.replace(",%f", "").replace(".%f", "").replace("%z", "").replace("T", " ")
    return base(fmt_a) == base(fmt_b)


class StampParser:
    """Date/time cells of one column to seconds from the column's first stamp, chunk by chunk.

    Parameters
    ----------
    fmt : str
        The column's format (:func:`stamp_format` of its first cell).
    example : str
        A cell as written, quoted in error messages.
    file, label : str
        For messages: the file and ``column 1 ('Timestamp')``.

    Examples
    --------
    >>> import pandas as pd
    >>> p = StampParser("%H:%M:%S.%f", "23:59:59.5", file="x.csv", label="column 1")
    >>> p.seconds(pd.Series(["23:59:59.5", "23:59:59.75", "00:00:00.0", None]), first_line=2)
    array([0.  , 0.25, 0.5 ,  nan])
    >>> p.start_attrs()
    {'start_time_of_day': '23:59:59.500000'}
    """

    def __init__(self, fmt: str, example: str, *, file: str, label: str):
        self.format = fmt
        self.example = example
        self.file = file
        self.label = label
        self.time_of_day = not fmt.startswith(("%Y", "%d"))
        self.has_zone = fmt.endswith("%z")
        self.first = None       # int64 ns of the first stamp
        self._start = None      # the first stamp as a Timestamp (its own offset kept)
        self._last = None       # int64 ns of the last stamp read (roll-over check)
        self._days = 0

    def _parse(self, text):
        import pandas as pd

        fmt = self.format.replace(",%f", ".%f").replace("T", " ")
        if fmt.startswith("%Y-%m-%d"):
            # pandas' ISO 8601 parser: a missing fraction, 'T' or ' ', any offset
            return pd.to_datetime(text, format="ISO8601", errors="coerce", utc=self.has_zone)
        out = pd.to_datetime(text, format=fmt, errors="coerce")
        short = fmt.replace(".%f", "")
        if short != fmt and out.isna().any():  # a stamp on a whole second without fraction
            miss = out.isna()
            out[miss] = pd.to_datetime(text[miss], format=short, errors="coerce")
        return out

    def seconds(self, cells, *, first_line: int) -> np.ndarray:
        """Seconds from the first stamp (float64, NaN for empty cells).

        Parameters
        ----------
        cells : pandas.Series of str
            The column's cells of one chunk (NaN for empty ones).
        first_line : int
            1-based line number of the chunk's first cell (for messages).

        Returns
        -------
        numpy.ndarray
            s.

        Raises
        ------
        RecordError
            A cell that is not a date/time of the column's format, naming line, column and the
            format expected.
        """
        import pandas as pd

        text = cells.astype(object).where(cells.notna(), "").astype(str).str.strip()
        text = text.str.strip('"').str.strip()
        missing = text.str.lower().isin(_NA).to_numpy()
        if "," in self.format:
            text = text.str.replace(",", ".", regex=False)
        parsed = self._parse(text.where(~missing, None))
        bad = parsed.isna().to_numpy() & ~missing
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise RecordError(
                f"{self.file}: line {first_line + i}, {self.label}: {str(cells.iloc[i])!r} is "
                f"not a date/time of the column's format {self.format} (like "
                f"{self.example!r}); expected a date/time in every data cell")
        if self.has_zone:
            parsed = parsed.dt.tz_convert(None)
        ns = parsed.to_numpy(dtype="datetime64[ns]").view(np.int64).copy()
        ok = ~parsed.isna().to_numpy()
        if self.time_of_day and ok.any():
            # midnight roll-over: a stamp more than 12 h before the previous one is a day later
            stamps = ns[ok]
            prev = stamps[0] if self._last is None else self._last
            back = np.diff(stamps, prepend=prev) < -_DAY_NS // 2
            days = self._days + np.cumsum(back)
            self._days = int(days[-1])
            ns[ok] = stamps + days * _DAY_NS
        if ok.any():
            if self.first is None:
                j = int(np.flatnonzero(ok)[0])
                self.first = int(ns[j])
                # the first stamp as written: with its own UTC offset, if it has one
                self._start = pd.to_datetime(text.iloc[j], format="ISO8601") \
                    if self.has_zone else parsed.iloc[j]
            self._last = int(ns[ok][-1])
        out = np.full(ns.size, np.nan)
        if self.first is not None:
            out[ok] = (ns[ok] - self.first) / 1e9
        return out

    def start_attrs(self) -> dict:
        """``{"start_time": ISO 8601}`` of the first stamp (with its UTC offset, if written), or
        ``{"start_time_of_day": "hh:mm:ss.ffffff"}`` for time-of-day stamps; {} before any."""
        if self._start is None:
            return {}
        if self.time_of_day:
            return {"start_time_of_day": self._start.strftime("%H:%M:%S.%f")}
        return {"start_time": self._start.isoformat()}
