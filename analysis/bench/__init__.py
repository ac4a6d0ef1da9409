"""Speed-against-error suites behind ``crankbench bench``, and the timing harness they share.

Each suite is a module ``analysis/bench/suite_<topic>.py`` defining

``run(quick: bool) -> list[Row]``

and a module docstring saying what it measures. A :class:`Row` holds one method at one setting:
its error against an independent reference, its median time, and the ratio of that time to a
baseline timed in the same process (``baseline`` names it). ``bound`` is the method's documented
error bound; the bench exits non-zero if ``error > bound``. A speed *target* row
(``target=True``: an issue's speed goal, the paired time ratio as the "error", the goal as the
bound) is reported as met or missed but does not fail the run: a ratio measured on a shared
machine moves with its load, an error bound does not.

How times and ratios are measured (:func:`compare`)
---------------------------------------------------
* **Interleaved rounds after a warm-up.** Every candidate of a comparison (the method, its
  baselines, peers) runs once per round, the order rotating from round to round, each call
  looped to last at least ``min_time``; a slow-down of the shared machine hits all alike.
* **CPU time** of the process (:func:`time.process_time`, every thread) per call; wall time is
  kept beside it (``Timing.wall``).
* **Paired ratios**: a ratio is the median over rounds of the per-round ratio of the two
  candidates' times, with its interquartile range (``ratio_lo``, ``ratio_hi``) as the spread.
* **Same thread settings for both sides**: :func:`run_suites` runs every suite under one BLAS
  thread limit (threadpoolctl, default 1), stated in the output with :func:`machine`.
* Rows whose ratio comes from separately timed medians (:func:`median_time`, kept for suites
  not yet converted) are marked ``paired=False``.
"""

from __future__ import annotations

import importlib
import os
import platform
import pkgutil
import time
from dataclasses import asdict, dataclass, field

import numpy as np

__all__ = ["Row", "Timing", "compare", "children_cpu_time", "median_time", "machine", "suites",
           "run_suites", "BENCH_THREADS"]

#: BLAS threads for both sides of every comparison unless ``crankbench bench --threads`` says
BENCH_THREADS = 1


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
    ratio_lo, ratio_hi : float
        Interquartile range of the per-round paired ratios (NaN if unpaired or no baseline).
    paired : bool
        True when ``ratio`` comes from interleaved rounds (:func:`compare`).
    clock : str
        ``"cpu"`` (process CPU time) or ``"wall"``.
    rounds : int
        Interleaved rounds behind ``time_s`` and ``ratio`` (0 for a single run).
    target : bool
        True for a speed-target row: ``passed`` says whether the target is met, and a miss is
        reported, not counted as an exceeded error bound (:attr:`fails_run`).
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
    ratio_lo: float = float("nan")
    ratio_hi: float = float("nan")
    paired: bool = False
    clock: str = "cpu"
    rounds: int = 0
    target: bool = False

    @property
    def passed(self) -> bool:
        """True unless the error is NaN or exceeds the documented bound (for a target row:
        the target is met)."""
        return bool(np.isfinite(self.error) and self.error <= self.bound) or (
            not np.isfinite(self.bound) and not np.isnan(self.error))

    @property
    def fails_run(self) -> bool:
        """True when this row makes ``crankbench bench`` exit non-zero: an error row past its
        bound (a missed speed target is reported, not failed)."""
        return not self.passed and not self.target

    @property
    def versus(self) -> str:
        """The comparison in words: ``"1.38x slower than <baseline> (1.36-1.41)"``, or
        ``"2.5x faster ..."``; ``"unpaired"`` flags ratios of separately timed medians."""
        if not self.baseline or not np.isfinite(self.ratio) or self.ratio <= 0:
            return ""
        if self.ratio >= 1:
            word, value, lo, hi = "slower", self.ratio, self.ratio_lo, self.ratio_hi
        else:
            word, value = "faster", 1 / self.ratio
            lo, hi = 1 / self.ratio_hi, 1 / self.ratio_lo
        text = f"{value:.3g}x {word} than {self.baseline}"
        if np.isfinite(lo) and np.isfinite(hi):
            text += f" ({lo:.3g}-{hi:.3g})"
        if not self.paired:
            text += ", unpaired"
        return text

    def as_dict(self) -> dict:
        d = asdict(self)
        d["passed"] = self.passed
        d["fails_run"] = self.fails_run
        d["versus"] = self.versus
        return d


@dataclass(frozen=True)
class Timing:
    """Per-round times of the candidates of one :func:`compare` call.

    Attributes
    ----------
    cpu, wall : dict of name -> ndarray (rounds,)
        Seconds per call in each round: process CPU time and wall time.
    loops : dict of name -> int
        Calls per round (each round of a candidate lasts at least ``min_time``).
    """

    cpu: dict
    wall: dict
    loops: dict

    @property
    def rounds(self) -> int:
        """Number of interleaved rounds."""
        return len(next(iter(self.cpu.values())))

    def time(self, name: str, *, clock: str = "cpu") -> float:
        """Median seconds per call of ``name``."""
        return float(np.median((self.cpu if clock == "cpu" else self.wall)[name]))

    def ratio(self, name: str, baseline: str, *, clock: str = "cpu") -> tuple[float, float,
                                                                               float]:
        """Paired ratio time(name)/time(baseline): (median, 25th, 75th percentile) over rounds.

        Examples
        --------
        >>> t = Timing({"a": np.array([2.0, 4.0, 3.0]), "b": np.array([1.0, 2.0, 1.0])},
        ...            {}, {"a": 1, "b": 1})
        >>> t.ratio("a", "b")
        (2.0, 2.0, 2.5)
        """
        times = self.cpu if clock == "cpu" else self.wall
        r = np.asarray(times[name]) / np.asarray(times[baseline])
        return float(np.median(r)), float(np.percentile(r, 25)), float(np.percentile(r, 75))

    def row(self, suite, method, name, baseline, setting, error, error_kind, reference, *,
            throughput_items=None, throughput_unit="", bound=float("inf"), note="",
            extra=None, target=False) -> "Row":
        """A :class:`Row` for candidate ``name`` against candidate ``baseline`` (None: none);
        ``baseline`` may also be ``(candidate, label)`` to print a longer label."""
        t = self.time(name)
        label = ""
        ratio = lo = hi = float("nan")
        if baseline is not None:
            key, label = baseline if isinstance(baseline, tuple) else (baseline, baseline)
            ratio, lo, hi = self.ratio(name, key)
        thr = throughput_items / t if throughput_items else float("nan")
        return Row(suite, method, setting, float(error), error_kind, reference, t, label, ratio,
                   thr, throughput_unit, bound, note, dict(extra or {}), lo, hi,
                   baseline is not None, "cpu", self.rounds, bool(target))


def compare(candidates: dict, *, rounds: int = 7, warmup: int = 1,
            min_time: float = 0.02, cpu_clock=time.process_time) -> Timing:
    """Time every callable of ``candidates`` in interleaved rounds (module docstring).

    Parameters
    ----------
    candidates : dict of name -> callable
        Zero-argument callables; all are warmed up, then timed once per round each, the order
        rotating by one per round.
    rounds : int
        Timed rounds (>= 1).
    warmup : int
        Untimed calls of each candidate first (imports, caches, page faults, JIT).
    min_time : float
        Each candidate's sample lasts at least this long, s (short calls are looped; the time
        per call is reported).
    cpu_clock : callable
        CPU-time clock, s (default this process's; :func:`children_cpu_time` adds the child
        processes a candidate starts and waits for).

    Returns
    -------
    Timing

    Examples
    --------
    Two loops that burn 4 ms and 2 ms of this thread's CPU time, timed by the same clock (a
    CPU-time clock, so a busy machine — or busy threads elsewhere in the process — does not
    change the ratio):

    >>> import time
    >>> def spin(seconds):
    ...     def run():
    ...         t0 = time.thread_time()
    ...         while time.thread_time() - t0 < seconds:
    ...             pass
    ...     return run
    >>> t = compare({"double": spin(0.004), "single": spin(0.002)}, rounds=5, min_time=0.0,
    ...             cpu_clock=time.thread_time)
    >>> 1.5 < t.ratio("double", "single")[0] < 2.7
    True
    """
    names = list(candidates)
    loops = {}
    for name in names:
        func = candidates[name]
        for _ in range(max(warmup, 1)):
            c0 = cpu_clock()
            w0 = time.perf_counter()
            func()
            one = max(cpu_clock() - c0, time.perf_counter() - w0, 1e-7)
        loops[name] = max(1, int(np.ceil(min_time / one))) if min_time > 0 else 1
    cpu = {name: np.empty(rounds) for name in names}
    wall = {name: np.empty(rounds) for name in names}
    for r in range(rounds):
        shift = r % len(names)
        for name in names[shift:] + names[:shift]:
            func, n = candidates[name], loops[name]
            c0 = cpu_clock()
            w0 = time.perf_counter()
            for _ in range(n):
                func()
            cpu[name][r] = (cpu_clock() - c0) / n
            wall[name][r] = (time.perf_counter() - w0) / n
    return Timing(cpu, wall, loops)


def children_cpu_time() -> float:
    """CPU time (s) of this process plus its terminated, waited-for children (``getrusage``,
    microsecond resolution; this process's alone where ``resource`` is missing)."""
    try:
        import resource
    except ImportError:  # pragma: no cover - Windows
        return time.process_time()
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def median_time(func, *, repeats: int = 5, min_time: float = 0.0, warmup: int = 1) -> float:
    """Median CPU time (s, :func:`time.process_time`) of ``func()`` over ``repeats`` runs after
    ``warmup`` runs -- one candidate alone; ratios of two such medians are *unpaired* (prefer
    :func:`compare`).

    If one call is shorter than ``min_time`` it is looped so each sample lasts about that long
    (timer resolution), and the per-call time is reported.
    """
    for _ in range(warmup):
        func()
    loops = 1
    if min_time > 0:
        t0 = time.process_time()
        func()
        one = max(time.process_time() - t0, 1e-9)
        loops = max(1, int(min_time / one))
    samples = []
    for _ in range(repeats):
        t0 = time.process_time()
        for _ in range(loops):
            func()
        samples.append((time.process_time() - t0) / loops)
    return float(np.median(samples))


def machine() -> dict:
    """What the figures were measured on: CPU, cores, load, memory, Python, numpy/SciPy and
    their BLAS builds (threadpoolctl), and the BLAS threads in force now.

    Examples
    --------
    >>> info = machine()
    >>> sorted(k for k in info if k.startswith("cpu"))
    ['cpu', 'cpus_available', 'cpus_logical']
    """
    import numpy
    import scipy
    import scipy.linalg  # noqa: F401 - load SciPy's BLAS so threadpoolctl lists it

    cpu = platform.processor() or platform.machine()
    memory = None
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
        with open("/proc/meminfo") as f:
            memory = int(f.readline().split()[1]) * 1024
    except OSError:
        pass
    try:
        available = len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        available = os.cpu_count()
    try:
        load = [round(v, 2) for v in os.getloadavg()]
    except OSError:
        load = None
    blas = []
    try:
        from threadpoolctl import threadpool_info

        blas = [{k: lib.get(k) for k in ("internal_api", "version", "architecture",
                                          "num_threads", "filepath")}
                for lib in threadpool_info() if lib.get("user_api") == "blas"]
    except ImportError:  # pragma: no cover
        pass
    from crankbench.analysis._kernels import accelerated

    return {"cpu": cpu, "cpus_logical": os.cpu_count(), "cpus_available": available,
            "load_average_1_5_15min": load, "memory_bytes": memory,
            "python": platform.python_version(), "platform": platform.platform(),
            "numpy": numpy.__version__, "scipy": scipy.__version__, "blas": blas,
            "compiled_kernels": accelerated()}


def suites() -> list[str]:
    """Names of the available suites (``suite_<name>.py`` modules), sorted."""
    names = [m.name[len("suite_"):] for m in pkgutil.iter_modules(__path__)
             if m.name.startswith("suite_")]
    return sorted(names)


def run_suites(names=None, *, quick: bool = False, progress=None,
               threads: int | None = BENCH_THREADS) -> list[Row]:
    """Run the named suites (all by default) and return every row.

    Every suite runs under one BLAS thread limit (``threads``; None keeps the BLAS default),
    the same for a method and its baselines.
    """
    from contextlib import nullcontext

    from threadpoolctl import threadpool_limits

    rows: list[Row] = []
    for name in names or suites():
        module = importlib.import_module(f"{__name__}.suite_{name}")
        if progress:
            progress(name)
        limit = nullcontext() if threads is None else threadpool_limits(limits=int(threads))
        with limit:
            rows.extend(module.run(quick))
    return rows
