"""Reading model TOML files with errors that name the file, the key and what was expected.

A :class:`Table` wraps one TOML table and remembers where it came from, so every accessor can
say ``engines/i4.toml: [engine] crank_radius = -0.04 must be > 0 m``. Unknown keys are an error
(with a did-you-mean), because a typo silently ignored is a model silently wrong.

Units. The quantity accessors (:meth:`Table.number`, :meth:`Table.positive`,
:meth:`Table.numbers`) take the key's unit (``unit="Pa"``) and plausible range
(``plausible=(1e9, 3e11)``): a plain number is in that unit (SI unless the key's name says
otherwise), a string such as ``"81 GPa"`` or ``"260 mm"`` is converted by pint
(:mod:`predict._units`), and a value outside the plausible range warns with the likely slip
(``shear_modulus = 81 Pa: did you mean 81 GPa?``).
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

    def _scalar(self, key: str, value, unit: str | None) -> float:
        """One value as a float in ``unit``: a number as is, a string through pint."""
        if isinstance(value, str) and unit is not None:
            from ._units import UnitError, to_unit

            try:
                return to_unit(value, unit)
            except UnitError as exc:
                self.fail(key, str(exc))
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.fail(key, f"= {value!r} must be a number{_in_unit(unit)}")
        return float(value)

    def _plausible(self, key: str, values, unit: str | None, plausible) -> None:
        """Warn (PlausibilityWarning) for the first nonzero value outside ``plausible``."""
        if plausible is None:
            return
        lo, hi = plausible
        for i, v in enumerate(np.atleast_1d(values)):
            if v != 0 and not lo <= abs(v) <= hi:
                import warnings

                from ._units import PlausibilityWarning, slip_message

                name = key if np.ndim(values) == 0 else f"{key}[{i}]"
                warnings.warn(f"{self.where(name)} = {slip_message(float(v), unit or '1', plausible)}",
                              PlausibilityWarning, stacklevel=4)
                return

    def number(self, key: str, default: Any = ..., *, unit: str | None = None,
               plausible: tuple[float, float] | None = None, low=None, high=None,
               strict_low=False):
        """Return a finite float in ``unit``, optionally bounded (``strict_low`` makes ``low``
        exclusive).

        Parameters
        ----------
        key : str
        default
            Returned when the key is absent (``...``: required).
        unit : str, optional
            The key's unit in pint syntax (``"m"``, ``"Pa"``, ``"kg*m^2"``, ``"N*m/rad"``,
            ``"rpm"``, ``"deg"``, ``"1"`` for a ratio): SI unless the key's name says another
            (``speed_rpm``). A plain number is in this unit; a string such as ``"260 mm"`` is
            converted to it (:func:`predict._units.to_unit`). ``None``: numbers only (a value
            whose unit depends on something else, e.g. noise in channel units).
        plausible : (float, float), optional
            Plausible magnitudes in ``unit``; a nonzero value outside warns
            (:class:`~predict._units.PlausibilityWarning`) with the likely slip.
        low, high : float, optional
            Hard bounds in ``unit`` (an error outside).
        """
        value = self.raw(key, default)
        if value is None:
            return None
        given = key in self.data
        value = self._scalar(key, value, unit)
        if not np.isfinite(value):
            self.fail(key, f"= {value!r} must be finite")
        if low is not None and (value <= low if strict_low else value < low):
            self.fail(key, f"= {value!r} must be {'>' if strict_low else '>='} {low:g}"
                           f"{_paren_unit(unit)}")
        if high is not None and value > high:
            self.fail(key, f"= {value!r} must be <= {high:g}{_paren_unit(unit)}")
        if given:
            self._plausible(key, value, unit, plausible)
        return value

    def positive(self, key: str, default: Any = ..., *, unit: str | None = None,
                 plausible: tuple[float, float] | None = None):
        """Return a float > 0 in ``unit`` (see :meth:`number`).

        Examples
        --------
        >>> t = Table({"diameter": "260 mm"}, source="line.toml", prefix="shaftline.shaft[0]")
        >>> t.positive("diameter", unit="m", plausible=(1e-3, 3.0))
        0.26
        """
        return self.number(key, default, unit=unit, plausible=plausible, low=0.0,
                           strict_low=True)

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

    def numbers(self, key: str, default: Any = ..., *, unit: str | None = None,
                plausible: tuple[float, float] | None = None, length: int | None = None,
                low=None, strict_low=False) -> np.ndarray | None:
        """Return a 1-D float array in ``unit`` from a TOML array of numbers or quantity
        strings (``["200 rpm", "800 rpm"]``); ``unit``, ``plausible`` and ``low`` as in
        :meth:`number`, per element."""
        value = self.raw(key, default)
        if value is None:
            return None
        given = key in self.data
        if not isinstance(value, list) or not all(
            (isinstance(v, (int, float)) and not isinstance(v, bool))
            or (unit is not None and isinstance(v, str)) for v in value
        ):
            self.fail(key, f"= {value!r} must be an array of numbers{_in_unit(unit)}")
        arr = np.asarray([self._scalar(f"{key}[{i}]", v, unit) for i, v in enumerate(value)],
                         dtype=float)
        if not np.all(np.isfinite(arr)):
            self.fail(key, "must contain only finite numbers")
        if length is not None and arr.size != length:
            self.fail(key, f"has {arr.size} values, expected {length}")
        if low is not None:
            bad = arr <= low if strict_low else arr < low
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                self.fail(f"{key}[{i}]",
                          f"= {float(arr[i]):g} must be {'>' if strict_low else '>='} {low:g}"
                          f"{_paren_unit(unit)}")
        if given:
            self._plausible(key, arr, unit, plausible)
        return arr

    def quantity(self, key: str, value, *, unit: str) -> float:
        """Convert one value found inside a raw structure (e.g. an element of ``segments``)
        to ``unit``; ``key`` names it in messages (``"segments[2][1]"``)."""
        out = self._scalar(key, value, unit)
        if not np.isfinite(out):
            self.fail(key, f"= {out!r} must be finite")
        return out

    def check_unknown(self, extra_allowed: Iterable[str] = ()) -> None:
        """Raise if the table has keys never read (typos), suggesting the closest known key."""
        known = self._used | set(extra_allowed)
        for key in self.data:
            if key not in known:
                self.fail(key, f"is not a known key{suggest(key, sorted(known))}; "
                               f"expected one of: {', '.join(sorted(known))}")

    def _join(self, key: str) -> str:
        return ".".join(p for p in (self.prefix, key) if p)


def _in_unit(unit: str | None) -> str:
    """`` in Pa (or a quantity string such as '81 GPa')`` for messages."""
    if unit is None:
        return ""
    if unit in ("", "1"):
        return " (dimensionless, or a string such as '2 %')"
    from ._units import pretty_unit

    return f" in {pretty_unit(unit)} (or a string with its unit, e.g. '1.5 {pretty_unit(unit)}')"


def _paren_unit(unit: str | None) -> str:
    if unit in (None, "", "1"):
        return ""
    from ._units import pretty_unit

    return f" {pretty_unit(unit)}"
