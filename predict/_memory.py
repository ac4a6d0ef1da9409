"""Sizes checked before allocation: a request that cannot fit in memory is refused up front.

A model, scene or analysis request states how much memory its dense arrays would take before
any of them is allocated; :func:`check_allocation` compares that with :func:`memory_budget`
and raises the caller's error naming the key (or option) that sets the size, the memory it
would need and what to change — instead of minutes of work and then numpy's
"Unable to allocate 74.5 GiB".

The budget is the memory available to this process (``MemAvailable`` of ``/proc/meminfo``, or
the physical memory), or ``CRANKBENCH_MEMORY_LIMIT`` (``"4 GiB"``, ``"500 MB"``, bytes) when
set — a batch on a shared machine sets it lower, a test sets it to make the check
reproducible.
"""

from __future__ import annotations

import os

from ._units import format_bytes, parse_bytes
from .errors import ConfigError

__all__ = ["ENV", "memory_budget", "check_allocation", "format_bytes"]

#: environment variable overriding the memory budget
ENV = "CRANKBENCH_MEMORY_LIMIT"


def _available() -> float:
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):  # not POSIX: assume a small machine
        return 8.0 * 2**30


def memory_budget() -> float:
    """Bytes a single request may allocate: ``CRANKBENCH_MEMORY_LIMIT`` or the available
    memory.

    Raises
    ------
    ConfigError
        If ``CRANKBENCH_MEMORY_LIMIT`` is not a memory size.

    Examples
    --------
    >>> import os
    >>> os.environ["CRANKBENCH_MEMORY_LIMIT"] = "4 GiB"
    >>> memory_budget()
    4294967296.0
    >>> del os.environ["CRANKBENCH_MEMORY_LIMIT"]
    """
    text = os.environ.get(ENV, "").strip()
    if text:
        try:
            value = parse_bytes(text)
        except ValueError:
            raise ConfigError(f"{ENV}={text!r} is not a memory size such as '4 GiB'") from None
        if not value > 0:
            raise ConfigError(f"{ENV}={text!r} must be a positive memory size")
        return value
    return _available()


def check_allocation(nbytes: float, *, what: str, hint: str,
                     error: type[Exception] = ConfigError) -> float:
    """Raise ``error`` unless ``nbytes`` fits in :func:`memory_budget`.

    Parameters
    ----------
    nbytes : float
        Estimated peak memory of the request, bytes.
    what : str
        The request and the key or option that sets its size, e.g.
        ``"rotor.max_element_length = 1e-07 m: 15000000 elements"``.
    hint : str
        What to change, e.g. ``"raise max_element_length"``.
    error : type
        Exception class (the caller's: ModelError, ConfigError, AnalysisError).

    Returns
    -------
    float
        ``nbytes`` (so the estimate can be logged).

    Examples
    --------
    >>> import os
    >>> os.environ["CRANKBENCH_MEMORY_LIMIT"] = "1 GiB"
    >>> try:
    ...     check_allocation(8e10, what="100000 masses: dense mode shapes", hint="fewer masses")
    ... except ConfigError as exc:
    ...     print(exc)
    100000 masses: dense mode shapes would need 74.5 GiB, more than the 1 GiB of memory available (CRANKBENCH_MEMORY_LIMIT); fewer masses
    >>> del os.environ["CRANKBENCH_MEMORY_LIMIT"]
    """
    budget = memory_budget()
    if nbytes > budget:
        source = f"({ENV})" if os.environ.get(ENV, "").strip() else "now"
        raise error(f"{what} would need {format_bytes(nbytes)}, more than the "
                    f"{format_bytes(budget)} of memory available {source}; {hint}")
    return nbytes
