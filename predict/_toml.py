"""Reading model TOML files with errors that name the file, the key and what was expected.

A :class:`Table` wraps one TOML table and remembers where it came from, so every accessor can
say ``engines/i4.toml: [engine] crank_radius = -0.04 must be > 0``. Unknown keys are an error
(with a did-you-mean), because a typo silently ignored is a model silently wrong.
"""

from __future__ import annotations

import tomllib
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from ._validate import suggest
from .errors import ModelError

__all__ = ["Table", "load_toml"]


def load_toml(path: str | Path, *, error: type[Exception] = ModelError) -> "Table":
    """Parse a TOML file into a :class:`Table`, raising ``error`` with the file name on failure."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such model file")
    if path.is_dir():
        raise error(f"{path}: is a directory, expected a TOML file")
    try:
        with path.open("rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: not valid TOML ({exc})") from None
    except UnicodeDecodeError:
        raise error(f"{path}: not a UTF-8 text file, expected TOML") from None
    return Table(data, source=str(path), prefix="", error=error)


class Table:
    """A TOML table with key-naming accessors.

    Parameters
    ----------
    data : dict
        The parsed table.
    source : str
        File name, for messages.
    prefix : str
        Dotted key path of this table (``"engine"``, ``"shaft.elements[2]"``).
    error : type
        Exception type raised on bad values (a :class:`~predict.errors.CrankbenchError`).
    """

    def __init__(self, data: dict, *, source: str, prefix: str = "", error=ModelError):
        self.data = dict(data)
        self.source = source
        self.prefix = prefix
        self.error = error
        self._used: set[str] = set()

    # -- naming -------------------------------------------------------------------------
    def where(self, key: str | None = None) -> str:
        """Return ``"file: key.path"`` for messages."""
        path = ".".join(p for p in (self.prefix, key) if p)
        return f"{self.source}: {path}" if path else self.source

    def fail(self, key: str | None, message: str):
        """Raise the table's error naming ``key``."""
        raise self.error(f"{self.where(key)} {message}")

    # -- access -------------------------------------------------------------------------
    def __contains__(self, key: str) -> bool:
        return key in self.data

    def keys(self):
        return self.data.keys()

    def raw(self, key: str, default: Any = ..., *, required: bool | None = None) -> Any:
        """Return the raw value; missing and no default -> error naming the key."""
        self._used.add(key)
        if key in self.data:
            return self.data[key]
        if default is ... or required:
            unread = [k for k in self.data if k not in self._used]
            hint = suggest(key, unread)
            if hint:  # a present key that looks like a misspelling of this one
                hint = f"; found {hint[len(' (did you mean '):-2]} — a misspelling of {key!r}?"
            self.fail(key, f"is missing (required){hint}")
        return default

    def table(self, key: str, default: Any = ...) -> "Table":
        """Return a sub-table."""
        value = self.raw(key, {} if default is ... else default)
        if value is None:
            return None
        if not isinstance(value, dict):
            self.fail(key, f"must be a table, got {type(value).__name__}")
        return Table(value, source=self.source, prefix=self._join(key), error=self.error)

    def tables(self, key: str, default: Any = ...) -> list["Table"]:
        """Return an array of tables (``[[key]]``)."""
        value = self.raw(key, default)
        if value is None:
            return []
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            self.fail(key, "must be an array of tables ([[...]])")
        return [
            Table(v, source=self.source, prefix=f"{self._join(key)}[{i}]", error=self.error)
            for i, v in enumerate(value)
        ]

    def number(self, key: str, default: Any = ..., *, low=None, high=None, strict_low=False):
        """Return a finite float, optionally bounded (``strict_low`` makes ``low`` exclusive)."""
        value = self.raw(key, default)
        if value is None:
            return None
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.fail(key, f"= {value!r} must be a number")
        value = float(value)
        if not np.isfinite(value):
            self.fail(key, f"= {value!r} must be finite")
        if low is not None and (value <= low if strict_low else value < low):
            self.fail(key, f"= {value!r} must be {'>' if strict_low else '>='} {low:g}")
        if high is not None and value > high:
            self.fail(key, f"= {value!r} must be <= {high:g}")
        return value

    def positive(self, key: str, default: Any = ...):
        """Return a float > 0."""
        return self.number(key, default, low=0.0, strict_low=True)

    def integer(self, key: str, default: Any = ..., *, minimum: int | None = None):
        """Return an int, optionally >= ``minimum``."""
        value = self.raw(key, default)
        if value is None:
            return None
        if isinstance(value, bool) or not isinstance(value, int):
            self.fail(key, f"= {value!r} must be an integer")
        if minimum is not None and value < minimum:
            self.fail(key, f"= {value!r} must be >= {minimum}")
        return value

    def string(self, key: str, default: Any = ..., *, options: Iterable[str] | None = None):
        """Return a string, optionally one of ``options``."""
        value = self.raw(key, default)
        if value is None:
            return None
        if not isinstance(value, str):
            self.fail(key, f"= {value!r} must be a string")
        if options is not None:
            options = list(options)
            if value not in options:
                listing = ", ".join(repr(o) for o in options)
                self.fail(key, f"= {value!r} is not one of {listing}{suggest(value, options)}")
        return value

    def numbers(self, key: str, default: Any = ..., *, length: int | None = None, low=None,
                strict_low=False) -> np.ndarray | None:
        """Return a 1-D float array from a TOML array of numbers."""
        value = self.raw(key, default)
        if value is None:
            return None
        if not isinstance(value, list) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value
        ):
            self.fail(key, f"= {value!r} must be an array of numbers")
        arr = np.asarray(value, dtype=float)
        if not np.all(np.isfinite(arr)):
            self.fail(key, "must contain only finite numbers")
        if length is not None and arr.size != length:
            self.fail(key, f"has {arr.size} values, expected {length}")
        if low is not None:
            bad = arr <= low if strict_low else arr < low
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                self.fail(f"{key}[{i}]",
                          f"= {float(arr[i]):g} must be {'>' if strict_low else '>='} {low:g}")
        return arr

    def check_unknown(self, extra_allowed: Iterable[str] = ()) -> None:
        """Raise if the table has keys never read (typos), suggesting the closest known key."""
        known = self._used | set(extra_allowed)
        for key in self.data:
            if key not in known:
                self.fail(key, f"is not a known key{suggest(key, sorted(known))}; "
                               f"expected one of: {', '.join(sorted(known))}")

    def _join(self, key: str) -> str:
        return ".".join(p for p in (self.prefix, key) if p)
