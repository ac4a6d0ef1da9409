"""Argument types shared by every command: one grammar for lists, checked numbers.

Lists. A list option takes comma-separated items and may be repeated: ``--orders 2,4`` and
``--orders 2 --orders 4`` are the same. An empty item (``2,,4``), items separated by spaces
inside one argument (``"2 4"``, which would otherwise read as 24 or be half-ignored), a
repeated item (``2,2``) and non-finite numbers are refused with a message naming the flag.

Numbers. :func:`number` builds an argparse ``type`` that accepts finite numbers within bounds
and says which (``--gate: 0 must be > 0``), so every argument is checked before any work.
"""

from __future__ import annotations

import argparse
import math
import re

__all__ = ["ListAction", "add_list", "number", "integer", "positive_order", "check_pair"]

_SPACE_INSIDE = re.compile(r"\S\s+\S")


def _split(text: str, flag: str, metavar: str) -> list[str]:
    """Comma-separated items of one argument, refusing empty and space-separated items."""
    items = [t.strip() for t in text.split(",")]
    if not text.strip():
        raise argparse.ArgumentTypeError(f"empty value; expected {metavar}[,{metavar}...]")
    if any(not t for t in items):
        raise argparse.ArgumentTypeError(
            f"{text!r} has an empty item; separate items by single commas ({flag} 2,4) or "
            f"repeat the option ({flag} 2 {flag} 4)")
    for t in items:
        if _SPACE_INSIDE.search(t):
            raise argparse.ArgumentTypeError(
                f"{text!r}: items are separated by commas ({flag} "
                f"{','.join(t.split())}) or given by repeating the option, not by spaces")
    return items


def _parse_float(text: str, *, low=None, high=None, strict_low=False, unit="") -> float:
    try:
        value = float(text)
    except ValueError:
        if not unit:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        from crankbench.predict._units import UnitError, to_unit

        try:  # a quantity with its unit: --imep "22 bar"
            value = to_unit(text, unit)
        except UnitError as exc:
            raise argparse.ArgumentTypeError(str(exc).removeprefix("= ")) from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    _bounds(text, value, low, high, strict_low)
    return value


def _parse_int(text: str, *, low=None, high=None) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    _bounds(text, value, low, high, False)
    return value


def _bounds(text, value, low, high, strict_low):
    if low is not None and (value <= low if strict_low else value < low):
        raise argparse.ArgumentTypeError(f"{text} must be {'>' if strict_low else '>='} {low:g}")
    if high is not None and value > high:
        raise argparse.ArgumentTypeError(f"{text} must be <= {high:g}")


def number(*, low: float | None = None, high: float | None = None, strict_low: bool = False,
           unit: str = ""):
    """An argparse ``type``: a finite float within ``[low, high]`` (``strict_low``: > low);
    with ``unit`` (pint syntax) also a quantity string converted to it (``"22 bar"``).

    Examples
    --------
    >>> gate = number(low=0.0, high=1.0, strict_low=True)
    >>> gate("0.15")
    0.15
    >>> try:
    ...     gate("0")
    ... except argparse.ArgumentTypeError as exc:
    ...     print(exc)
    0 must be > 0
    """
    def parse(text):
        return _parse_float(text, low=low, high=high, strict_low=strict_low, unit=unit)

    parse.__name__ = f"number{' in ' + unit if unit else ''}"
    return parse


def integer(*, low: int | None = None, high: int | None = None):
    """An argparse ``type``: an integer within ``[low, high]``."""
    def parse(text):
        return _parse_int(text, low=low, high=high)

    parse.__name__ = "integer"
    return parse


class ListAction(argparse.Action):
    """Comma-separated items, the option repeatable; duplicates and empty items refused.

    ``item`` converts one item (raising ``argparse.ArgumentTypeError``); the destination
    holds the list in the order given (None when the option is absent).
    """

    def __init__(self, option_strings, dest, *, item=str, unique=True, **kwargs):
        kwargs.setdefault("default", None)
        super().__init__(option_strings, dest, nargs=None, **kwargs)
        self.item = item
        self.unique = unique

    def __call__(self, parser, namespace, values, option_string=None):
        flag = option_string or self.option_strings[0]
        metavar = self.metavar or "X"
        try:
            items = [self.item(t) for t in _split(values, flag, metavar)]
        except argparse.ArgumentTypeError as exc:
            raise argparse.ArgumentError(self, str(exc)) from None
        current = getattr(namespace, self.dest, None)
        current = list(current) if current is not None and current is not self.default else []
        if self.unique:
            seen = list(current)
            for raw, value in zip(_split(values, flag, metavar), items):
                if value in seen:
                    raise argparse.ArgumentError(
                        self, f"{raw} is given twice; list each value once")
                seen.append(value)
        setattr(namespace, self.dest, current + items)


def add_list(parser, *flags, item=str, metavar="X", help="", default=None, required=False,
             unique=True, dest=None):
    """Add a list option with the shared grammar (comma-separated, repeatable, unique)."""
    kwargs = dict(action=ListAction, item=item, metavar=metavar, default=default,
                  required=required, unique=unique,
                  help=f"{help} (comma-separated, or repeat the option)" if help else None)
    if dest:
        kwargs["dest"] = dest
    return parser.add_argument(*flags, **kwargs)


def positive_order(text: str) -> float:
    """One order: a finite number > 0 (``0.5``, ``2``)."""
    return _parse_float(text, low=0.0, strict_low=True)


def check_pair(values, flag: str, *, low: float | None = 0.0, unit: str = ""):
    """Parse ``--flag LOW HIGH`` or ``--flag LOW,HIGH`` (option added with ``nargs="+"``)
    into an increasing (low, high) pair.

    Raises
    ------
    ConfigError
        Naming the flag: not two numbers, not finite, below ``low`` or not increasing.
    """
    from crankbench.predict.errors import ConfigError

    if values is None:
        return None
    tokens = [t for v in values for t in v.replace(",", " ").split()]
    shown = " ".join(values)
    if len(tokens) != 2:
        raise ConfigError(f"{flag} {shown}: expected two numbers LOW HIGH{' ' + unit if unit else ''}"
                          f" (e.g. {flag} 800 6000 or {flag} 800,6000)")
    try:
        lo, hi = (_parse_float(t, low=low) for t in tokens)
    except argparse.ArgumentTypeError as exc:
        raise ConfigError(f"{flag} {shown}: {exc}") from None
    if not lo < hi:
        raise ConfigError(f"{flag} {shown}: LOW must be below HIGH")
    return lo, hi
