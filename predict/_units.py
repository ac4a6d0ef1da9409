"""Quantities with units in model files: ``"260 mm"``, ``"81 GPa"``, ``"720 rpm"`` (pint).

A model key has one unit, named by the accessor that reads it (:class:`predict._toml.Table`):
SI unless the key's name says otherwise (``speed_rpm``, ``angle_deg``, ``continuous_mpa``). A
plain number is in that unit; a string is a quantity with its own unit, converted by pint
(https://pint.readthedocs.io), so ``diameter = "260 mm"`` reads as 0.26 m and
``shear_modulus = "81 GPa"`` as 8.1e10 Pa. A string without a unit is refused (``"81"`` says
nothing about what was meant).

Rotation. pint counts a radian as dimensionless and ``Hz`` as ``1/s``, so by pint alone
``12 Hz`` would be 114.6 rpm. For a shaft, a frequency in Hz (or 1/min) is cycles per time:
12 Hz is 12 revolutions per second, 720 rpm. :func:`to_unit` applies that rule whenever source
and target differ only by one angle per cycle (Hz ↔ rpm ↔ rad/s); everything else is pint's
conversion.

Plausibility. Each key also states a plausible range of magnitudes (in its unit).
:func:`slip_message` finds the unit a value outside it was most likely written in
(``shear_modulus = 81 Pa: did you mean 81 GPa?``), for a :class:`PlausibilityWarning`.

pint is imported on first use only (a plain-number model never pays for it).
"""

from __future__ import annotations

import functools
import math
import re

from .errors import CrankbenchError

__all__ = ["PlausibilityWarning", "UnitError", "registry", "to_unit", "pretty_unit",
           "slip_message", "is_quantity_string", "format_bytes", "parse_bytes"]


class PlausibilityWarning(UserWarning):
    """A model value lies outside its key's plausible range (likely a unit slip)."""


class UnitError(CrankbenchError, ValueError):
    """A quantity string could not be read or has the wrong dimension (message without the
    key: the caller prefixes it)."""


@functools.lru_cache(maxsize=1)
def registry():
    """The shared pint ``UnitRegistry`` (created on first call)."""
    import pint

    ureg = pint.UnitRegistry(autoconvert_offset_to_baseunit=True)
    return ureg


@functools.lru_cache(maxsize=256)
def pretty_unit(unit: str) -> str:
    """``"kg*m^2"`` → ``"kg·m²"`` (pint's short pretty form); ``"1"`` → ``""``.

    Examples
    --------
    >>> pretty_unit("N*m/rad"), pretty_unit("rpm"), pretty_unit("1")
    ('N·m/rad', 'rpm', '')
    """
    if unit in ("1", ""):
        return ""
    text = re.sub(r"\bu(?=[a-zA-Z])", "µ", unit)          # um -> µm, us -> µs
    text = text.replace("^2", "²").replace("^3", "³").replace("*", "·")
    return text.replace("inch", "in")


def is_quantity_string(value) -> bool:
    """True for a string (a candidate quantity such as ``"260 mm"``)."""
    return isinstance(value, str)


# What a quantity string may look like: a decimal number, then a unit expression of unit names
# joined by spaces, *, / or · with small integer powers (^2, **-1, ²). Anything else (pint
# would evaluate arithmetic such as 10**10**10 without bound) is refused before pint sees it.
_NUMBER = r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?"
_NAME = r"[A-Za-zµμΩ°%][A-Za-z0-9_µμΩ°]*(?:\s*(?:\^|\*\*)\s*[+-]?\d{1,2}|[²³])?"
_UNIT = rf"(?:1\s*/\s*)?{_NAME}(?:(?:\s*[*/·]\s*|\s+){_NAME}){{0,15}}"
_QUANTITY = re.compile(rf"\s*{_NUMBER}\s*(?:{_UNIT})?\s*")


def _radian_power(q) -> int:
    return int(round(q.to_root_units()._units.get("radian", 0)))


def to_unit(text: str, unit: str) -> float:
    """Convert the quantity string ``text`` to the magnitude in ``unit``.

    Parameters
    ----------
    text : str
        A number with a unit, e.g. ``"260 mm"``, ``"81 GPa"``, ``"12 Hz"``.
    unit : str
        Target unit (pint syntax), e.g. ``"m"``, ``"Pa"``, ``"rpm"``, ``"1"`` (dimensionless).

    Returns
    -------
    float

    Raises
    ------
    UnitError
        The string is not a number with a known unit, has no unit, or the wrong dimension.

    Examples
    --------
    >>> to_unit("260 mm", "m"), to_unit("81 GPa", "Pa"), to_unit("12 Hz", "rpm")
    (0.26, 81000000000.0, 720.0)
    >>> round(to_unit("720 rpm", "rad/s"), 4), to_unit("1500 rpm", "Hz")
    (75.3982, 25.0)
    """
    import pint

    expected = _expected(unit)
    if len(text) > 200 or not _QUANTITY.fullmatch(text):
        raise UnitError(f"= {text[:60]!r} is not a number followed by a unit (such as '260 mm' "
                        f"or '81 GPa'); {expected}")
    ureg = registry()
    try:
        q = ureg.Quantity(text.strip())
    except (pint.errors.UndefinedUnitError, pint.errors.DefinitionSyntaxError) as exc:
        raise UnitError(f"= {text!r}: unknown unit ({exc}); {expected}") from None
    except Exception:  # noqa: BLE001 - pint's parser raises many kinds on garbage
        raise UnitError(f"= {text!r} is not a number with a unit; {expected}") from None
    if not isinstance(q, ureg.Quantity) or not isinstance(q.magnitude, (int, float)):
        raise UnitError(f"= {text!r} is not a number with a unit; {expected}")
    if not q._units:
        raise UnitError(f"= {text!r} has no unit: write a plain number (in "
                        f"{pretty_unit(unit) or 'no unit'}) or a quantity with its unit; "
                        f"{expected}")
    target = ureg.Unit("dimensionless" if unit in ("", "1") else unit)
    try:
        q_root, t_root = q.to_root_units(), ureg.Quantity(1.0, target).to_root_units()
        if q_root.dimensionality == t_root.dimensionality:
            shift = _radian_power(t_root) - _radian_power(q_root)
            frequency = q_root.dimensionality == ureg.Quantity(1, "Hz").dimensionality
            if shift != 0 and frequency and abs(shift) == 1:
                # a shaft frequency: one turn per cycle (12 Hz = 720 rpm, not 114.6)
                q = q * ureg.turn if shift > 0 else q / ureg.turn
            elif shift != 0:
                raise pint.errors.DimensionalityError(q.units, target)
        return float(q.to(target).magnitude)
    except pint.errors.DimensionalityError:
        raise UnitError(f"= {text!r} has the wrong dimension; {expected}") from None


def _expected(unit: str) -> str:
    if unit in ("", "1"):
        return "expected a dimensionless number (e.g. 0.02 or '2 %')"
    return f"expected a quantity in {pretty_unit(unit)} (a plain number is in {pretty_unit(unit)})"


#: units in which values of each dimension are commonly written, most likely slip first
_COMMON = {
    "[length]": ("mm", "cm", "um", "km", "inch", "ft"),
    "[mass]": ("g", "t", "lb"),
    "[mass] / [length] / [time] ** 2": ("MPa", "GPa", "bar", "kPa", "psi"),
    "[mass] * [length] ** 2": ("kg*cm^2", "g*cm^2", "kg*mm^2", "t*m^2"),
    "[mass] * [length] ** 2 / [time] ** 2": ("kN*m", "MN*m", "N*mm", "kJ", "MJ"),
    "[mass] * [length] ** 2 / [time]": ("kN*m*s", "MN*m*s"),
    "[mass] / [time] ** 2": ("kN/m", "MN/m", "N/mm", "kN/mm"),
    "[mass] / [time]": ("kN*s/m", "N*s/mm"),
    "[mass] / [length] ** 3": ("g/cm^3", "t/m^3"),
    "[mass] * [length]": ("g*mm", "g*m", "kg*mm"),
    "[mass] * [length] / [time] ** 2": ("kN", "MN"),
    "[time]": ("ms", "us", "min", "h", "ns"),
    "1 / [time]": ("rpm", "rad/s", "kHz", "MHz"),
    "[length] / [time]": ("mm/s", "km/h"),
    "[length] / [time] ** 2": ("mm/s^2",),
    "": ("%", "rad", "deg"),
}


@functools.lru_cache(maxsize=256)
def _candidates(unit: str) -> tuple[tuple[str, float], ...]:
    """(unit name, factor to ``unit``) of the units a value of this dimension is often written
    in: SI prefixes of a simple unit, plus the common ones of its dimension."""
    ureg = registry()
    target = ureg.Unit("dimensionless" if unit in ("", "1") else unit)
    dim = str(ureg.Quantity(1.0, target).dimensionality)
    dim = "" if dim == "dimensionless" else dim
    names = list(_COMMON.get(dim, ()))
    if unit.isalpha() and unit not in ("rpm", "deg", "m", "s", "kg", "g", "MPa", "GPa", "kPa"):
        names += [p + unit for p in ("m", "k", "M", "G")]   # N -> kN, MN; Hz -> kHz ...
    out = []
    for name in dict.fromkeys(names):
        if name == unit:
            continue
        try:
            factor = to_unit(f"1 {name}", unit)
        except UnitError:
            continue
        if factor > 0 and not math.isclose(factor, 1.0):
            out.append((name, factor))
    return tuple(out)


def slip_message(value: float, unit: str, plausible: tuple[float, float]) -> str:
    """The likely slip of a value outside its plausible range, for a warning.

    The candidates are the units values of the key's dimension are commonly written in, most
    likely first (bar before psi); the first that puts the value well inside the range (not
    at its edge: 1e-7 m is no slip of 1e-7 km) is named.

    Parameters
    ----------
    value : float
        The value as read (in ``unit``).
    unit : str
        The key's unit.
    plausible : (float, float)
        Plausible magnitudes, in ``unit``.

    Returns
    -------
    str
        ``"81 Pa: did you mean 81 GPa?"``, or ``"... is outside the plausible range"`` without
        a candidate.

    Examples
    --------
    >>> slip_message(81.0, "Pa", (1e9, 3e11))
    '81 Pa: did you mean 81 GPa? (plausible 1e+09 to 3e+11 Pa; plain numbers are in Pa)'
    >>> slip_message(260.0, "m", (1e-3, 3.0))
    '260 m: did you mean 260 mm? (plausible 0.001 to 3 m; plain numbers are in m)'
    """
    lo, hi = plausible
    shown = pretty_unit(unit)
    centre = 0.5 * (math.log10(lo) + math.log10(hi))
    # a candidate must put the value well inside the range (not at its edge: 1e-7 m is no
    # slip of 1e-7 km)
    reach = 0.8 * 0.5 * (math.log10(hi) - math.log10(lo))
    best = None
    for name, factor in _candidates(unit):
        v = abs(value) * factor
        if v > 0 and abs(math.log10(v) - centre) <= reach:
            best = name
            break
    head = f"{value:g} {shown}".rstrip()
    tail = (f"(plausible {lo:g} to {hi:g} {shown}".rstrip()
            + (f"; plain numbers are in {shown})" if shown else ")"))
    if best is not None:
        return f"{head}: did you mean {value:g} {pretty_unit(best)}? {tail}"
    return f"{head} is outside the plausible range, check its unit {tail}"


_BYTE_UNITS = (("PiB", 2**50), ("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10))


def format_bytes(nbytes: float) -> str:
    """Human-readable binary size: ``80e9`` → ``'74.5 GiB'``.

    Examples
    --------
    >>> format_bytes(8e10), format_bytes(2.88e16), format_bytes(512)
    ('74.5 GiB', '25.6 PiB', '512 B')
    """
    nbytes = float(nbytes)
    if nbytes >= 2**60:
        return f"{nbytes / 2**60:.3g} EiB"
    for name, size in _BYTE_UNITS:
        if nbytes >= size:
            return f"{nbytes / size:.3g} {name}"
    return f"{nbytes:.0f} B"


def parse_bytes(text: str) -> float:
    """``"4 GiB"`` / ``"500MB"`` / ``"1e9"`` → bytes (pint; a plain number is bytes).

    Examples
    --------
    >>> parse_bytes("4 GiB"), parse_bytes("1e9")
    (4294967296.0, 1000000000.0)
    """
    text = str(text).strip()
    try:
        return float(text)
    except ValueError:
        pass
    ureg = registry()
    try:
        return float(ureg.Quantity(text).to("byte").magnitude)
    except Exception:  # noqa: BLE001
        raise UnitError(f"{text!r} is not a memory size such as '4 GiB'") from None
