"""BLAS thread limits around small dense solves.

OpenBLAS splits a matrix operation over all cores once it passes a size threshold, which for
the least-squares fits, banded factorizations and batched small solves of crankbench is
mostly synchronisation: on a 2-core machine shared with other work, threaded BLAS made
``find_resonances`` 6x and the Vold-Kalman filter 6-10x slower in CPU and wall time than one
thread (issue 21). :func:`limit_blas` runs a block with a BLAS thread limit;
:func:`single_threaded_blas` decorates a function the same way. Problems large enough to gain
from threads (dense models of more than a few hundred degrees of freedom) pass ``size`` and
keep the default.

The limit is process-wide while it holds (BLAS has one thread setting), so a solve running at
the same moment in another Python thread also runs single-threaded; nested limits restore
the outer setting on exit. Without :mod:`threadpoolctl` (a core dependency) both are no-ops.
"""

from __future__ import annotations

import contextlib
import functools
import threading

__all__ = ["limit_blas", "single_threaded_blas", "SMALL_SIZE"]

#: problems up to this many unknowns count as small (threads cost more than they gain)
SMALL_SIZE = 400

_LOCK = threading.Lock()
_CONTROLLER: list = []   # [ThreadpoolController or None] once tried


def _controller():
    """The threadpoolctl controller over the BLAS libraries numpy and SciPy load (cached)."""
    if not _CONTROLLER:
        with _LOCK:
            if not _CONTROLLER:
                try:
                    import numpy  # noqa: F401 - both BLAS builds must be loaded before
                    import scipy.linalg  # noqa: F401 - the controller scans the process
                    from threadpoolctl import ThreadpoolController

                    _CONTROLLER.append(ThreadpoolController())
                except ImportError:  # pragma: no cover - threadpoolctl is a core dependency
                    _CONTROLLER.append(None)
    return _CONTROLLER[0]


def limit_blas(threads: int = 1, *, size: int | None = None):
    """Context manager: BLAS limited to ``threads`` inside the block.

    Parameters
    ----------
    threads : int
        BLAS threads inside the block (default 1).
    size : int, optional
        Number of unknowns of the problem; above :data:`SMALL_SIZE` the block keeps the
        default threading (large dense solves gain from it).

    Examples
    --------
    >>> import numpy as np
    >>> from threadpoolctl import threadpool_info
    >>> with limit_blas():
    ...     print({lib["num_threads"] for lib in threadpool_info()
    ...            if lib["user_api"] == "blas"})
    {1}
    >>> with limit_blas(size=5000):   # a large model keeps its threads
    ...     pass
    """
    if size is not None and size > SMALL_SIZE:
        return contextlib.nullcontext()
    ctl = _controller()
    if ctl is None:  # pragma: no cover - threadpoolctl is a core dependency
        return contextlib.nullcontext()
    return ctl.limit(limits=int(threads), user_api="blas")


def single_threaded_blas(func):
    """Decorator: run ``func`` under :func:`limit_blas` (one BLAS thread).

    Examples
    --------
    >>> @single_threaded_blas
    ... def fit(a, b):
    ...     return np.linalg.lstsq(a, b, rcond=None)[0]
    >>> import numpy as np
    >>> print(fit(np.eye(2), np.array([1.0, 2.0])))
    [1. 2.]
    """

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with limit_blas():
            return func(*args, **kwargs)

    return wrapper
