"""Lazy public names for package ``__init__`` modules (no work at import time).

Usage in a package ``__init__.py``::

    _LAZY = {"order_track": "orders", ...}          # public name -> submodule
    __getattr__, __dir__, __all__ = lazy_names(__name__, _LAZY)
"""

from __future__ import annotations

import importlib

__all__ = ["lazy_names"]


def lazy_names(package: str, table: dict[str, str], extra=()):
    """Return ``(__getattr__, __dir__, __all__)`` resolving ``table`` names on first use.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    table : dict
        Public name -> submodule (relative to ``package``) that defines it.
    extra : iterable of str
        Names defined eagerly in the package, listed in ``__all__`` too.
    """
    names = sorted({*table, *extra})

    def __getattr__(name):
        if name in table:
            module = importlib.import_module(f"{package}.{table[name]}")
            return getattr(module, name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__():
        return names

    return __getattr__, __dir__, names
