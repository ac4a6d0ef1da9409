"""Speed-against-error suites behind ``crankbench bench``.

Each suite is a module ``analysis/bench/suite_<topic>.py`` defining

``run(quick: bool) -> list[Row]``

and a module docstring saying what it measures. A :class:`Row` holds one method at one setting:
its error against an independent reference, its median time, and the ratio of that time to a
baseline timed in the same process (``baseline`` names it). ``bound`` is the method's documented
error bound; the bench exits non-zero if ``error > bound``.
"""

from __future__ import annotations

import importlib
import pkgutil
import time
from dataclasses import asdict, dataclass, field

import numpy as np

__all__ = ["Row", "median_time", "suites", "run_suites"]


@dataclass(frozen=True)
class Row:
    """One line of the speed-against-error table.

    Attributes
    ----------
    suite, method, setting : str
        Which suite, which method, which fidelity setting ("max_order=4", "n=1000").
    error : float
        Error against the independent reference, in ``error_kind`` terms.
    error_kind : str
        e.g. "max rel", "rms rel", "abs deg".
    reference : str
        What the error was measured against (closed form, mpmath, dense eigh...).
    time_s : float
        Median wall time of one call, seconds.
    baseline : str
        Name of the baseline timed side by side ("" if none).
    ratio : float
        time_s / baseline time (NaN if no baseline). < 1 means faster than the baseline.
    throughput : float
        Items per second where meaningful (samples/s), else NaN.
    throughput_unit : str
    bound : float
        Documented error bound; ``error > bound`` fails the bench (inf = informational row).
    note : str
    """

    suite: str
    method: str
    setting: str
    error: float
    error_kind: str
    reference: str
    time_s: float
    baseline: str = ""
    ratio: float = float("nan")
    throughput: float = float("nan")
    throughput_unit: str = ""
    bound: float = float("inf")
    note: str = ""
    extra: dict = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        """True unless the error is NaN or exceeds the documented bound."""
        return bool(np.isfinite(self.error) and self.error <= self.bound) or (
            not np.isfinite(self.bound) and not np.isnan(self.error))

    def as_dict(self) -> dict:
        d = asdict(self)
        d["passed"] = self.passed
        return d


def median_time(func, *, repeats: int = 5, min_time: float = 0.0, warmup: int = 1) -> float:
    """Median wall time (s) of ``func()`` over ``repeats`` runs after ``warmup`` runs.

    If one call is shorter than ``min_time`` it is looped so each sample lasts about that long
    (timer resolution), and the per-call time is reported.
    """
    for _ in range(warmup):
        func()
    loops = 1
    if min_time > 0:
        t0 = time.perf_counter()
        func()
        one = max(time.perf_counter() - t0, 1e-9)
        loops = max(1, int(min_time / one))
    samples = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(loops):
            func()
        samples.append((time.perf_counter() - t0) / loops)
    return float(np.median(samples))


def suites() -> list[str]:
    """Names of the available suites (``suite_<name>.py`` modules), sorted."""
    names = [m.name[len("suite_"):] for m in pkgutil.iter_modules(__path__)
             if m.name.startswith("suite_")]
    return sorted(names)


def run_suites(names=None, *, quick: bool = False, progress=None) -> list[Row]:
    """Run the named suites (all by default) and return every row."""
    rows: list[Row] = []
    for name in names or suites():
        module = importlib.import_module(f"{__name__}.suite_{name}")
        if progress:
            progress(name)
        rows.extend(module.run(quick))
    return rows
