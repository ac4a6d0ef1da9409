"""Argument validation shared by every package (one place, exact messages tested).

Each checker returns the validated value (converted to float / ndarray where stated) so it can be
used inline: ``crank_radius = check_positive(crank_radius, "crank_radius")``.
"""

from __future__ import annotations

import difflib
import importlib
from collections.abc import Iterable
from typing import Any

import numpy as np

from .errors import MissingDependencyError

__all__ = [
    "check_positive",
    "check_nonnegative",
    "check_range",
    "check_option",
    "check_finite_array",
    "check_int",
    "suggest",
    "require",
]


def _as_float(value: Any, name: str, error: type[Exception]) -> float:
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise error(f"{name}={value!r} must be a real number") from None
    if not np.isfinite(out):
        raise error(f"{name}={value!r} must be finite")
    return out


def check_positive(value: Any, name: str, *, error: type[Exception] = ValueError) -> float:
    """Return ``value`` as float, raising ``error`` unless it is finite and > 0."""
    out = _as_float(value, name, error)
    if out <= 0:
        raise error(f"{name}={value!r} must be > 0")
    return out


def check_nonnegative(value: Any, name: str, *, error: type[Exception] = ValueError) -> float:
    """Return ``value`` as float, raising ``error`` unless it is finite and >= 0."""
    out = _as_float(value, name, error)
    if out < 0:
        raise error(f"{name}={value!r} must be >= 0")
    return out


def check_range(
    value: Any,
    name: str,
    low: float | None = None,
    high: float | None = None,
    *,
    inclusive: tuple[bool, bool] = (True, True),
    error: type[Exception] = ValueError,
) -> float:
    """Return ``value`` as float, raising ``error`` unless low <= value <= high.

    ``inclusive`` selects closed (True) or open (False) ends.
    """
    out = _as_float(value, name, error)
    lo_ok = low is None or (out >= low if inclusive[0] else out > low)
    hi_ok = high is None or (out <= high if inclusive[1] else out < high)
    if not (lo_ok and hi_ok):
        left = "[" if inclusive[0] else "("
        right = "]" if inclusive[1] else ")"
        lo = "-inf" if low is None else f"{low:g}"
        hi = "inf" if high is None else f"{high:g}"
        raise error(f"{name}={value!r} must lie in {left}{lo}, {hi}{right}")
    return out


def check_int(
    value: Any, name: str, *, minimum: int | None = None, error: type[Exception] = ValueError
) -> int:
    """Return ``value`` as int, raising ``error`` unless it is an integer >= ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        if isinstance(value, (float, np.floating)) and float(value).is_integer():
            value = int(value)
        else:
            raise error(f"{name}={value!r} must be an integer")
    value = int(value)
    if minimum is not None and value < minimum:
        raise error(f"{name}={value!r} must be >= {minimum}")
    return value


def suggest(value: str, valid: Iterable[str]) -> str:
    """Return ``" (did you mean 'x'?)"`` for the closest valid name, or ``""``."""
    close = difflib.get_close_matches(str(value), [str(v) for v in valid], n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def check_option(
    value: Any, name: str, valid: Iterable[str], *, error: type[Exception] = ValueError
) -> str:
    """Return ``value`` unless it is not one of ``valid``; the error lists the valid names."""
    valid = list(valid)
    if value not in valid:
        listing = ", ".join(repr(v) for v in valid)
        raise error(f"{name}={value!r} is not one of {listing}{suggest(value, valid)}")
    return value


def check_finite_array(
    values: Any,
    name: str,
    *,
    ndim: int | None = None,
    min_length: int = 0,
    error: type[Exception] = ValueError,
) -> np.ndarray:
    """Return ``values`` as a float64 array, raising ``error`` on NaN/inf, wrong ndim or length."""
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise error(f"{name} must be numeric, got {type(values).__name__}") from None
    if ndim is not None and arr.ndim != ndim:
        raise error(f"{name} must be {ndim}-dimensional, got shape {arr.shape}")
    if arr.ndim >= 1 and arr.shape[0] < min_length:
        raise error(f"{name} must have at least {min_length} values, got {arr.shape[0]}")
    bad = ~np.isfinite(arr)
    if bad.any():
        first = int(np.flatnonzero(bad.ravel())[0])
        raise error(f"{name} contains {int(bad.sum())} NaN/inf value(s), first at index {first}")
    return arr


def require(module: str, *, extra: str, feature: str):
    """Import an optional module or raise :class:`MissingDependencyError` naming the extra.

    Parameters
    ----------
    module : str
        Importable module name, e.g. ``"weasyprint"``.
    extra : str
        The pip extra providing it, e.g. ``"pdf"`` (``pip install 'crankbench[pdf]'``).
    feature : str
        What the user asked for, for the message.
    """
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise MissingDependencyError(
            f"{feature} needs the optional package {module!r}, which is not installed "
            f"({exc}); install it with: pip install 'crankbench[{extra}]'"
        ) from None
