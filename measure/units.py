"""Unit spellings of test-bench files, converted to SI once, at ingest.

Every channel inside crankbench carries one of the canonical SI spellings in
:data:`SI_UNITS`. Files come with whatever their logger wrote (``g``, ``mm/s``, ``µm``, ``rpm``,
``bar``, ``kN·m``...); :func:`to_si` recognises the usual spellings, scales the values and says
which quantity the unit suggests. Sensor sensitivities (``mV/g``, ``V/(mm/s)``) are converted the
same way by :func:`sensitivity_to_si`, which :func:`to_si` also handles.

Conversions are exact scalings (no offsets): 1 g = 9.80665 m/s² (standard gravity, CGPM 1901),
1 in = 0.0254 m, 1 psi = 6894.757293168361 Pa, 1 rpm = 2π/60 rad/s. A frequency in Hz given as a
channel unit is read as a rotational speed in revolutions per second (1 Hz = 2π rad/s), which is
what test-bench speed channels mean by it.
"""

from __future__ import annotations

import difflib
import math
import re

import numpy as np

from crankbench.predict.errors import RecordError

__all__ = [
    "SI_UNITS",
    "QUANTITIES",
    "QUANTITY_UNITS",
    "known_units",
    "to_si",
    "sensitivity_to_si",
    "unit_factor",
    "to_si_owned",
]

#: Canonical SI spellings allowed in a Record's ``units`` attribute.
SI_UNITS = ("m/s^2", "m/s", "m", "rad", "rad/s", "Pa", "V", "N", "N*m", "1", "s")

#: The quantity each channel may declare, and the SI unit it must carry (None: any SI unit).
QUANTITY_UNITS = {
    "acceleration": "m/s^2",
    "velocity": "m/s",
    "displacement": "m",
    "angle": "rad",
    "angular_velocity": "rad/s",
    "rotational_speed": "rad/s",
    "pressure": "Pa",
    "voltage": "V",
    "force": "N",
    "torque": "N*m",
    "pulse_times": "s",
    "other": None,
}

#: Valid ``quantity`` names.
QUANTITIES = tuple(QUANTITY_UNITS)

_G0 = 9.80665            # standard gravity, m/s^2
_INCH = 0.0254           # m
_PSI = 6894.757293168361  # Pa (lbf/in^2)
_RPM = 2.0 * math.pi / 60.0
_DEG = math.pi / 180.0

# spelling -> (factor to SI, SI spelling, quantity hint or None when the unit is ambiguous)
_TABLE: dict[str, tuple[float, str, str | None]] = {}


def _add(spellings: str, factor: float, si: str, hint: str | None) -> None:
    for s in spellings.split():
        _TABLE[s] = (factor, si, hint)


_add("m/s^2 m/s2 m*s^-2", 1.0, "m/s^2", "acceleration")
_add("mm/s^2 mm/s2", 1e-3, "m/s^2", "acceleration")
_add("g g0 gn", _G0, "m/s^2", "acceleration")
_add("mg", 1e-3 * _G0, "m/s^2", "acceleration")
_add("in/s^2 in/s2", _INCH, "m/s^2", "acceleration")
_add("m/s", 1.0, "m/s", "velocity")
_add("mm/s", 1e-3, "m/s", "velocity")
_add("um/s", 1e-6, "m/s", "velocity")
_add("in/s ips", _INCH, "m/s", "velocity")
_add("m", 1.0, "m", "displacement")
_add("mm", 1e-3, "m", "displacement")
_add("um micron", 1e-6, "m", "displacement")
_add("nm", 1e-9, "m", "displacement")
_add("in", _INCH, "m", "displacement")
_add("mil mils", 1e-3 * _INCH, "m", "displacement")
_add("rad", 1.0, "rad", "angle")
_add("mrad", 1e-3, "rad", "angle")
_add("deg degree degrees °", _DEG, "rad", "angle")
_add("rad/s", 1.0, "rad/s", None)
_add("deg/s °/s", _DEG, "rad/s", "angular_velocity")
# rig spellings of speed: U/min (German), n [1/s] for revolutions per second
_add("rpm r/min 1/min min^-1 min-1 rev/min U/min", _RPM, "rad/s", "rotational_speed")
_add("Hz rev/s rps r/s 1/s s^-1 s-1 U/s", 2.0 * math.pi, "rad/s", "rotational_speed")
_add("Pa N/m^2", 1.0, "Pa", "pressure")
_add("hPa mbar", 100.0, "Pa", "pressure")
_add("kPa", 1e3, "Pa", "pressure")
_add("bar", 1e5, "Pa", "pressure")
_add("MPa N/mm^2", 1e6, "Pa", "pressure")
_add("psi", _PSI, "Pa", "pressure")
_add("V volt volts", 1.0, "V", "voltage")
_add("mV", 1e-3, "V", "voltage")
_add("uV", 1e-6, "V", "voltage")
_add("N", 1.0, "N", "force")
_add("kN", 1e3, "N", "force")
_add("N*m Nm N.m m*N", 1.0, "N*m", "torque")
_add("kN*m kNm kN.m", 1e3, "N*m", "torque")
_add("1 - %", 1.0, "1", None)
_TABLE["%"] = (0.01, "1", None)
_add("s sec", 1.0, "s", None)
_add("ms", 1e-3, "s", None)
_add("us", 1e-6, "s", None)

# numerators of a sensitivity (electrical output per physical input)
_ELECTRICAL = {"V": (1.0, "V"), "mV": (1e-3, "V"), "uV": (1e-6, "V"),
               "C": (1.0, "C"), "pC": (1e-12, "C"), "nC": (1e-9, "C")}

_LOWER: dict[str, str] = {}
for _s in _TABLE:
    _LOWER.setdefault(_s.lower(), _s)
_AMBIGUOUS = {s.lower() for s in _TABLE if sum(t.lower() == s.lower() for t in _TABLE) > 1}


def _normalise(unit: str) -> str:
    """Canonical typography: no spaces, ^ powers, * products, u for micro."""
    s = str(unit).strip()
    if s.startswith("[") and s.endswith("]"):
        s = s[1:-1].strip()
    s = (s.replace("²", "^2").replace("³", "^3").replace("µ", "u").replace("μ", "u")
         .replace("·", "*").replace("⋅", "*").replace("×", "*").replace("**", "^")
         .replace("⁻¹", "^-1").replace("º", "°"))
    s = re.sub(r"\s+", "", s)
    return s


def known_units() -> list[str]:
    """Every unit spelling :func:`to_si` accepts (after typographic normalisation).

    Examples
    --------
    >>> "mm/s" in known_units() and "rpm" in known_units()
    True
    """
    return sorted(_TABLE)


def _unknown(unit: str, channel: str | None, what: str = "unit") -> RecordError:
    close = difflib.get_close_matches(_normalise(unit), list(_TABLE), n=5, cutoff=0.5)
    where = f"channel {channel!r}: " if channel is not None else ""
    hint = f"; close known spellings: {', '.join(close)}" if close else (
        f"; known spellings include: {', '.join(sorted(set(s for _, s, _ in _TABLE.values())))}")
    return RecordError(f"{where}unknown {what} {unit!r}{hint}")


def _lookup(unit: str) -> tuple[float, str, str | None] | None:
    s = _normalise(unit)
    if s in _TABLE:
        return _TABLE[s]
    low = s.lower()
    if low in _LOWER and low not in _AMBIGUOUS:
        return _TABLE[_LOWER[low]]
    return None


def unit_factor(unit: str, *, channel: str | None = None) -> tuple[float, str, str | None]:
    """Return ``(factor, si_unit, quantity_hint)`` with ``value_si = factor * value``.

    Parameters
    ----------
    unit : str
        Unit spelling as found in a file (``"mm/s"``, ``"µm"``, ``"kN·m"``...).
    channel : str, optional
        Channel name, used in the error message.

    Returns
    -------
    factor : float
        Multiplier to SI.
    si_unit : str
        Canonical SI spelling (one of :data:`SI_UNITS`).
    quantity_hint : str or None
        The quantity the unit suggests; None when it is ambiguous (rad/s, s, 1).

    Raises
    ------
    RecordError
        Unknown unit; the message names the channel and lists close known spellings.

    Examples
    --------
    >>> unit_factor("mm/s")
    (0.001, 'm/s', 'velocity')
    """
    if not isinstance(unit, str):
        raise RecordError(f"channel {channel!r}: unit must be a string, got {unit!r}")
    found = _lookup(unit)
    if found is None:
        raise _unknown(unit, channel)
    return found


def sensitivity_to_si(value: float, unit: str, *, channel: str | None = None) -> tuple[float, str]:
    """Convert a transducer sensitivity such as ``100 mV/g`` to SI (``V/(m/s^2)``).

    Parameters
    ----------
    value : float
        Sensitivity in ``unit``.
    unit : str
        ``"<electrical>/<physical>"``: numerator V, mV, uV, C, pC or nC; denominator any unit
        :func:`to_si` knows, optionally in parentheses (``"V/(mm/s)"``).
    channel : str, optional
        Channel name for error messages.

    Returns
    -------
    value_si : float
        Sensitivity in SI units.
    si_unit : str
        E.g. ``"V/(m/s^2)"``, ``"C/(m/s^2)"``, ``"V/m"``.

    Examples
    --------
    >>> v, u = sensitivity_to_si(100.0, "mV/g")
    >>> print(f"{v:.6f} {u}")
    0.010197 V/(m/s^2)
    """
    s = _normalise(unit)
    num, sep, den = s.partition("/")
    if not sep or num not in _ELECTRICAL:
        raise _unknown(unit, channel, "sensitivity unit")
    if den.startswith("(") and den.endswith(")"):
        den = den[1:-1]
    found = _lookup(den)
    if found is None:
        raise _unknown(unit, channel, "sensitivity unit")
    f_num, si_num = _ELECTRICAL[num]
    f_den, si_den, _ = found
    si = f"{si_num}/({si_den})" if "/" in si_den or "*" in si_den else f"{si_num}/{si_den}"
    return float(value) * f_num / f_den, si


def to_si(values, unit: str, *, channel: str | None = None):
    """Convert ``values`` given in ``unit`` to SI.

    Parameters
    ----------
    values : array_like or float
        Values in ``unit`` (copied, never modified in place).
    unit : str
        Unit spelling. Accepted: every entry of :func:`known_units` after typographic
        normalisation (``²``→``^2``, ``·``→``*``, ``µ``→``u``, spaces dropped, ``[...]`` stripped,
        case-insensitive where unambiguous), and sensitivities ``<V|mV|pC...>/<unit>``.
    channel : str, optional
        Channel name used in error messages.

    Returns
    -------
    values_si : ndarray or float
        Values in SI (float64; float32 input stays float32).
    si_unit : str
        Canonical SI spelling.
    quantity_hint : str or None
        The quantity the unit suggests (``"sensitivity"`` for sensitivities); None if ambiguous.

    Raises
    ------
    RecordError
        Unknown unit, naming the channel and the unit and listing close known spellings.

    Examples
    --------
    >>> v, u, q = to_si([1.0, 2.0], "g")
    >>> print(v, u, q)
    [ 9.80665 19.6133 ] m/s^2 acceleration
    >>> print(to_si(3000.0, "rpm")[0])
    314.1592653589793
    """
    found = _lookup(unit) if isinstance(unit, str) else None
    if found is None and isinstance(unit, str) and "/" in _normalise(unit):
        try:
            value, si = sensitivity_to_si(1.0, unit, channel=channel)
        except RecordError:
            raise _unknown(unit, channel) from None
        return _scale(values, value), si, "sensitivity"
    factor, si, hint = unit_factor(unit, channel=channel)
    return _scale(values, factor), si, hint


def to_si_owned(values, unit: str, *, channel: str | None = None):
    """:func:`to_si` for arrays the caller owns: scales in place, no copy when factor is 1.

    Falls back to :func:`to_si` (a copy) for sensitivities, non-float, read-only or non-numpy
    input.

    Examples
    --------
    >>> x = np.array([1.0, 2.0])
    >>> y, unit, _ = to_si_owned(x, "mm")
    >>> y is x, unit, x.tolist()
    (True, 'm', [0.001, 0.002])
    """
    found = _lookup(unit) if isinstance(unit, str) else None
    if (found is None or not isinstance(values, np.ndarray) or values.dtype.kind != "f"
            or not values.flags.writeable):
        return to_si(values, unit, channel=channel)
    factor, si, hint = found
    if factor != 1.0:
        values *= values.dtype.type(factor)
    return values, si, hint


def _scale(values, factor: float):
    if np.ndim(values) == 0 and not isinstance(values, np.ndarray):
        return float(values) * factor
    if hasattr(values, "__dask_graph__"):  # lazy channel: stay lazy
        arr = values if values.dtype.kind in "fc" else values.astype(np.float64)
        return arr if factor == 1.0 else (arr * arr.dtype.type(factor)).astype(arr.dtype)
    arr = np.asarray(values)
    if arr.dtype.kind not in "fc":
        arr = arr.astype(np.float64)
    if factor == 1.0:
        return arr.copy()
    return (arr * arr.dtype.type(factor)).astype(arr.dtype, copy=False)
