"""Renamed keyword arguments kept one release as deprecated aliases.

Usage::

    @renamed(rpm="speed_rpm")
    def order_track(x, *, fs, speed_rpm, orders): ...

``order_track(x, fs=fs, rpm=r, orders=o)`` still works and emits a :class:`FutureWarning`
naming the new keyword; ``inspect.signature`` shows only the new names.
"""

from __future__ import annotations

import functools
import warnings

__all__ = ["renamed"]

#: the release in which the aliases added now are removed
REMOVED_IN = "0.3"


def renamed(**old_to_new: str):
    """Decorator accepting each ``old`` keyword as a deprecated alias of ``new``.

    Parameters
    ----------
    **old_to_new : str
        Old keyword name -> new keyword name.

    Examples
    --------
    >>> import warnings
    >>> @renamed(speed="omega")
    ... def f(*, omega):
    ...     return 2 * omega
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     f(speed=3.0)
    6.0
    >>> print(caught[0].category.__name__, caught[0].message)  # doctest: +ELLIPSIS
    FutureWarning f(speed=...) is deprecated ...; use omega=... (the name says the unit)
    """

    def decorate(func):
        @functools.wraps(func)
        def wrapper(*args, **kwargs):
            for old, new in old_to_new.items():
                if old in kwargs:
                    if new in kwargs:
                        raise TypeError(f"{func.__qualname__}() got both {old}= (deprecated) "
                                        f"and {new}=; pass only {new}=")
                    warnings.warn(f"{func.__qualname__}({old}=...) is deprecated and will be "
                                  f"removed in crankbench {REMOVED_IN}; use {new}=... (the name "
                                  "says the unit)", FutureWarning, stacklevel=2)
                    kwargs[new] = kwargs.pop(old)
            return func(*args, **kwargs)

        wrapper.__renamed_kwargs__ = dict(old_to_new)
        return wrapper

    return decorate
