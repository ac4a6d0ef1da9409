"""Fatigue of shafts: endurance limits, stress cycles, endurance diagrams and safety factors.

Stresses are in Pa (normal or shear — keep one kind per call: for torsion pass shear
stresses with the shear ultimate/endurance/yield strengths). A load point is its alternating
(amplitude) stress σ_a ≥ 0 and mean stress σ_m; safety factors are along the proportional load
line (σ_a/σ_m fixed), the classical assumption of the endurance diagram.

Criteria (failure line in the Haigh σ_m-σ_a plane):

==================  =========================================  ===========================
goodman             σ_a/S_e + σ_m/S_u = 1                      straight line (seed eq. 5a)
gerber              σ_a/S_e + (σ_m/S_u)² = 1                   parabola (seed eq. 5b)
soderberg           σ_a/S_e + σ_m/S_y = 1                      conservative, needs S_y
asme-elliptic       (σ_a/S_e)² + (σ_m/S_y)² = 1                needs S_y
==================  =========================================  ===========================

A compressive mean stress is taken as not harmful (n = S_e/σ_a), as usual for ductile steels;
the first-cycle yield check n_y = S_y/(σ_a + |σ_m|) covers the other side. With a yield
strength the endurance diagram is cut by the yield line σ_a + σ_m = S_y (seed fig. 1, points
y₁, y₂).

References
----------
.. [1] Shi Zhiqing, *Applied Mechanics vol. 2: Engine Dynamics*, pre-reading 1 "simple
   varying stress" §(2)-(4): eq. (1) endurance limits, eq. (2a,b) endurance at stress ratio r,
   eq. (5a) straight-line and (5b) parabolic endurance diagrams, worked shaft example
   (S.A.E. 1055).
.. [2] R. G. Budynas, J. K. Nisbett, *Shigley's Mechanical Engineering Design*, 10th ed.,
   §6-7 (endurance limit), §6-9 (Marin factors), §6-12 (fluctuating stresses, Table 6-7 and
   6-8 safety factors).
.. [3] ASTM E1049-85 (2017), *Standard Practices for Cycle Counting in Fatigue Analysis*,
   §5.4.4 (rainflow counting).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from ._validate import check_finite_array, check_nonnegative, check_option, check_positive
from .errors import ModelError

__all__ = [
    "CRITERIA",
    "endurance_limit",
    "shear_strength",
    "max_stress_at_ratio",
    "StressPoint",
    "torsional_stress",
    "RainflowCycles",
    "rainflow",
    "safety_factor",
    "first_cycle_yield",
    "EnduranceDiagram",
    "FatigueAssessment",
    "assess",
]

log = logging.getLogger("crankbench")

CRITERIA = ("goodman", "gerber", "soderberg", "asme-elliptic")
_NEEDS_YIELD = ("soderberg", "asme-elliptic")


def endurance_limit(ultimate, *, loading="bending", rule="shi", surface_factor=1.0,
                    size_factor=1.0, reliability_factor=1.0, temperature_factor=1.0) -> float:
    """Estimate the endurance limit from the ultimate tensile strength.

    Parameters
    ----------
    ultimate : float
        Ultimate tensile strength S_u, Pa.
    loading : {"bending", "axial", "torsion"}
        Kind of alternating stress. Torsion returns a shear endurance limit.
    rule : {"shi", "shigley"}
        ``"shi"`` — the seed text, eq. (1) and its worked example: S_e = S_u/2 in reversed
        bending, 2/3 of that in axial push-pull, 0.55 of it in torsion (Maleev).
        ``"shigley"`` — S_e' = 0.5 S_u (at most 700 MPa) with load factors 1, 0.85, 0.59.
        Both are rough: ±20 % against tests is typical.
    surface_factor, size_factor, reliability_factor, temperature_factor : float
        Marin factors k_a, k_b, k_e, k_d (0 < k <= 1.2) multiplying the estimate.

    Returns
    -------
    float
        Endurance limit, Pa.

    References
    ----------
    Shi, *Engine Dynamics*, pre-reading 1 §(2) eq. (1); Shigley §6-7, §6-9.

    Examples
    --------
    >>> psi = 6894.757
    >>> round(endurance_limit(78_500 * psi, loading="torsion") / psi)  # seed example: 22,000
    21588
    """
    su = check_positive(ultimate, "ultimate", error=ModelError)
    loading = check_option(loading, "loading", ("bending", "axial", "torsion"), error=ModelError)
    rule = check_option(rule, "rule", ("shi", "shigley"), error=ModelError)
    factors = 1.0
    for name, k in (("surface_factor", surface_factor), ("size_factor", size_factor),
                    ("reliability_factor", reliability_factor),
                    ("temperature_factor", temperature_factor)):
        k = check_positive(k, name, error=ModelError)
        if k > 1.2:
            raise ModelError(f"{name}={k!r} must be <= 1.2 (a Marin factor)")
        factors *= k
    if rule == "shi":
        base = 0.5 * su
        load = {"bending": 1.0, "axial": 2.0 / 3.0, "torsion": 0.55}[loading]
    else:
        base = min(0.5 * su, 700e6)
        load = {"bending": 1.0, "axial": 0.85, "torsion": 0.59}[loading]
    return base * load * factors


def shear_strength(tensile) -> float:
    """Shear strength from the tensile one (ultimate or yield): 0.6 × tensile, Pa.

    References
    ----------
    Shi, *Engine Dynamics*, pre-reading 1, worked example ("second method"): q_u = 0.6 S_u,
    q_yp = 0.6 S_yp.

    Examples
    --------
    >>> round(shear_strength(78_500.0))
    47100
    """
    return 0.6 * check_positive(tensile, "tensile", error=ModelError)


def max_stress_at_ratio(ratio, *, endurance, ultimate=None, form="2a") -> float:
    """Endurance limit (largest maximum stress) at stress ratio r = σ_min/σ_max.

    Both forms pass through S_r = S_e at r = −1 (fully reversed) and S_r = S_u at r = +1
    (static). Seed eq. (2a) is hyperbolic, S_r = S_u / (A + B r) with A = (1 + S_u/S_e)/2,
    B = (1 − S_u/S_e)/2; eq. (2b) is linear, S_r = ((S_u + S_e) + (S_u − S_e) r)/2. With the
    seed's S_u = 2 S_e they read S_r = 4 S_e/(3 − r) and S_r = (3 + r) S_e/2. (The printed
    second form of (2a), "4/(3+r)", is a misprint: the derivation above it, A = 3/2,
    B = −1/2, and the worked example's 4/(3½) at r = −½ both give 3 − r.)

    Parameters
    ----------
    ratio : float
        r in [−1, 1].
    endurance : float
        Fully reversed endurance limit S_e, Pa.
    ultimate : float, optional
        S_u, Pa (default 2 S_e, the seed's eq. (1)).
    form : {"2a", "2b"}

    Returns
    -------
    float
        Pa.

    References
    ----------
    Shi, *Engine Dynamics*, pre-reading 1 §(3)(a), eq. (2a), (2b), exercises 2-3 (eq. 3a, 3b).

    Examples
    --------
    >>> round(max_stress_at_ratio(-0.5, endurance=22_000.0))  # seed example, printed 25,000
    25143
    """
    if not -1.0 <= float(ratio) <= 1.0:
        raise ModelError(f"ratio={ratio!r} must lie in [-1, 1]")
    se = check_positive(endurance, "endurance", error=ModelError)
    su = 2 * se if ultimate is None else check_positive(ultimate, "ultimate", error=ModelError)
    if su < se:
        raise ModelError(f"ultimate={su:g} Pa must be >= endurance={se:g} Pa")
    form = check_option(form, "form", ("2a", "2b"), error=ModelError)
    r = float(ratio)
    if form == "2a":
        k = su / se
        return su / ((1 + k) / 2 + (1 - k) / 2 * r)
    return ((su + se) + (su - se) * r) / 2


@dataclass(frozen=True)
class StressPoint:
    """A fluctuating stress: alternating (amplitude) and mean parts, Pa.

    Examples
    --------
    >>> p = StressPoint.from_extremes(80.0, -40.0)
    >>> p.alternating, p.mean, p.ratio
    (60.0, 20.0, -0.5)
    """

    alternating: float
    mean: float

    def __post_init__(self):
        object.__setattr__(self, "alternating",
                           check_nonnegative(self.alternating, "alternating", error=ModelError))
        mean = float(self.mean)
        if not math.isfinite(mean):
            raise ModelError(f"mean={self.mean!r} must be finite")
        object.__setattr__(self, "mean", mean)

    @classmethod
    def from_extremes(cls, maximum, minimum) -> "StressPoint":
        """From the largest and smallest stress of the cycle, Pa."""
        hi, lo = float(maximum), float(minimum)
        if hi < lo:
            raise ModelError(f"maximum={maximum!r} must be >= minimum={minimum!r}")
        return cls(alternating=(hi - lo) / 2, mean=(hi + lo) / 2)

    @property
    def maximum(self) -> float:
        """σ_max = σ_m + σ_a, Pa."""
        return self.mean + self.alternating

    @property
    def minimum(self) -> float:
        """σ_min = σ_m − σ_a, Pa."""
        return self.mean - self.alternating

    @property
    def ratio(self) -> float:
        """Stress ratio r = σ_min/σ_max (NaN if σ_max = 0)."""
        return self.minimum / self.maximum if self.maximum else float("nan")

    def to_frame(self):
        """One-row table of alternating, mean, maximum, minimum, ratio (Pa)."""
        import pandas as pd

        return pd.DataFrame([{"alternating": self.alternating, "mean": self.mean,
                              "maximum": self.maximum, "minimum": self.minimum,
                              "ratio": self.ratio}])

    def plot(self, ax=None):
        """Draw one cycle of the stress against the cycle fraction; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = (plt.subplots() if ax is None else (ax.figure, ax))
        t = np.linspace(0, 1, 101)
        ax.plot(t, (self.mean + self.alternating * np.sin(2 * np.pi * t)) / 1e6)
        ax.axhline(self.mean / 1e6, ls="--", color="k", lw=0.8)
        ax.set_xlabel("cycle fraction")
        ax.set_ylabel("stress (MPa)")
        return fig


def torsional_stress(*, mean_torque, vibratory_torque, diameter, inner_diameter=0.0,
                     stress_concentration=1.0) -> StressPoint:
    """Shear stresses of a round shaft from a mean and a vibratory (amplitude) torque.

    τ = K_t · 16 T D / (π (D⁴ − d⁴)).

    Parameters
    ----------
    mean_torque : float
        Steady torque, N·m.
    vibratory_torque : float
        Amplitude of the alternating torque, N·m (>= 0).
    diameter, inner_diameter : float
        Outer diameter and bore, m.
    stress_concentration : float
        Fatigue stress-concentration factor K_f >= 1 applied to both parts.

    Returns
    -------
    StressPoint
        Shear stresses, Pa.

    Examples
    --------
    >>> p = torsional_stress(mean_torque=1000.0, vibratory_torque=500.0, diameter=0.05)
    >>> round(p.mean / 1e6, 3), round(p.alternating / 1e6, 3)
    (40.744, 20.372)
    """
    d = check_positive(diameter, "diameter", error=ModelError)
    di = check_nonnegative(inner_diameter, "inner_diameter", error=ModelError)
    if di >= d:
        raise ModelError(f"inner_diameter={inner_diameter!r} must be < diameter={diameter!r}")
    kf = float(stress_concentration)
    if not (math.isfinite(kf) and kf >= 1.0):
        raise ModelError(f"stress_concentration={stress_concentration!r} must be >= 1")
    tv = check_nonnegative(vibratory_torque, "vibratory_torque", error=ModelError)
    tm = float(mean_torque)
    if not math.isfinite(tm):
        raise ModelError(f"mean_torque={mean_torque!r} must be finite")
    per_torque = kf * 16 * d / (math.pi * (d**4 - di**4))
    return StressPoint(alternating=tv * per_torque, mean=tm * per_torque)


@dataclass(frozen=True)
class RainflowCycles:
    """Cycles counted from a stress history (ASTM E1049 rainflow).

    Attributes
    ----------
    alternating, mean : ndarray
        Amplitude (half range) and mean of each cycle, Pa.
    count : ndarray
        1.0 for a full cycle, 0.5 for a half cycle (residue).
    """

    alternating: np.ndarray
    mean: np.ndarray
    count: np.ndarray

    @property
    def total_cycles(self) -> float:
        """Number of cycles counted (half cycles count 0.5)."""
        return float(self.count.sum())

    def largest(self) -> StressPoint:
        """The cycle with the largest amplitude (the governing one for an endurance check)."""
        if self.count.size == 0:
            raise ModelError("the history has no cycles (constant stress)")
        i = int(np.argmax(self.alternating))
        return StressPoint(float(self.alternating[i]), float(self.mean[i]))

    def to_frame(self):
        """Table: alternating, mean, count (Pa, cycles), largest amplitude first."""
        import pandas as pd

        order = np.argsort(-self.alternating, kind="stable")
        return pd.DataFrame({"alternating": self.alternating[order], "mean": self.mean[order],
                             "count": self.count[order]})

    def plot(self, ax=None):
        """Scatter of the cycles in the mean-amplitude plane (MPa); returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = (plt.subplots() if ax is None else (ax.figure, ax))
        ax.scatter(self.mean / 1e6, self.alternating / 1e6, s=20 * self.count)
        ax.set_xlabel("mean stress (MPa)")
        ax.set_ylabel("alternating stress (MPa)")
        ax.set_title(f"rainflow: {self.total_cycles:g} cycles")
        return fig


def rainflow(history) -> RainflowCycles:
    """Rainflow cycle counting of a stress history (ASTM E1049-85 §5.4.4).

    Parameters
    ----------
    history : array_like
        Stress samples, Pa (only the reversals matter).

    Returns
    -------
    RainflowCycles

    References
    ----------
    ASTM E1049-85 (2017) §5.4.4 and its Fig. 6 example.

    Examples
    --------
    >>> c = rainflow([-2, 1, -3, 5, -1, 3, -4, 4, -2])  # ASTM E1049 Fig. 6
    >>> sorted(zip((2 * c.alternating).tolist(), c.count.tolist()))
    [(3.0, 0.5), (4.0, 0.5), (4.0, 1.0), (6.0, 0.5), (8.0, 0.5), (8.0, 0.5), (9.0, 0.5)]
    """
    x = check_finite_array(history, "history", ndim=1, min_length=1, error=ModelError)
    # reversals: drop repeated values and points that do not change slope direction
    x = x[np.concatenate([[True], np.diff(x) != 0])]
    if x.size > 2:
        d = np.diff(x)
        keep = np.concatenate([[True], d[1:] * d[:-1] < 0, [True]])
        x = x[keep]
    amps, means, counts = [], [], []
    stack: list[float] = []
    for point in x:
        stack.append(float(point))
        while len(stack) >= 3:
            y_rng = abs(stack[-2] - stack[-3])
            x_rng = abs(stack[-1] - stack[-2])
            if x_rng < y_rng:
                break
            a, b = stack[-3], stack[-2]
            if len(stack) == 3:  # Y contains the starting point: half cycle, drop the start
                amps.append(y_rng / 2)
                means.append((a + b) / 2)
                counts.append(0.5)
                stack.pop(0)
            else:
                amps.append(y_rng / 2)
                means.append((a + b) / 2)
                counts.append(1.0)
                last = stack.pop()
                stack.pop()
                stack.pop()
                stack.append(last)
    for a, b in zip(stack[:-1], stack[1:]):
        amps.append(abs(b - a) / 2)
        means.append((a + b) / 2)
        counts.append(0.5)
    return RainflowCycles(np.asarray(amps, dtype=float), np.asarray(means, dtype=float),
                          np.asarray(counts, dtype=float))


def _strengths(ultimate, endurance, yield_strength, criterion):
    su = check_positive(ultimate, "ultimate", error=ModelError)
    se = check_positive(endurance, "endurance", error=ModelError)
    criterion = check_option(criterion, "criterion", CRITERIA, error=ModelError)
    sy = None
    if yield_strength is not None:
        sy = check_positive(yield_strength, "yield_strength", error=ModelError)
        if sy > su:
            raise ModelError(f"yield_strength={sy:g} Pa must not exceed ultimate={su:g} Pa")
    if criterion in _NEEDS_YIELD and sy is None:
        raise ModelError(f"criterion={criterion!r} needs yield_strength (Pa)")
    if se > su:
        raise ModelError(f"endurance={se:g} Pa must not exceed ultimate={su:g} Pa")
    return su, se, sy, criterion


def _fatigue_factor(sa, sm, su, se, sy, criterion):
    """Safety factor along the load line for σ_m >= 0 (arrays)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        if criterion == "goodman":
            n = 1.0 / (sa / se + sm / su)
        elif criterion == "soderberg":
            n = 1.0 / (sa / se + sm / sy)
        elif criterion == "asme-elliptic":
            n = 1.0 / np.sqrt((sa / se) ** 2 + (sm / sy) ** 2)
        else:  # gerber: n σa/Se + (n σm/Su)² = 1, Shigley Table 6-7
            ratio = 2 * sm * se / (su * np.where(sa > 0, sa, 1.0))
            n = np.where(sm > 0, 0.5 * (su / np.where(sm > 0, sm, 1.0)) ** 2 * sa / se
                         * (-1 + np.sqrt(1 + ratio**2)), se / np.where(sa > 0, sa, 1.0))
            n = np.where(sa > 0, n, su / np.where(sm > 0, sm, 1.0))
    return n


def safety_factor(alternating, mean, *, ultimate, endurance, yield_strength=None,
                  criterion="goodman"):
    """Fatigue safety factor of load point(s) against an endurance criterion.

    The factor n scales the load point along its load line (σ_a/σ_m fixed) onto the failure
    line of ``criterion``. With ``yield_strength`` the result is min(n_fatigue, n_yield),
    n_yield = S_y/(σ_a + |σ_m|) (first-cycle yield), i.e. the endurance diagram cut by the
    yield line. A compressive mean gives n_fatigue = S_e/σ_a.

    Parameters
    ----------
    alternating : float or array_like
        Alternating stress σ_a >= 0, Pa.
    mean : float or array_like
        Mean stress σ_m, Pa (broadcast with ``alternating``).
    ultimate, endurance : float
        S_u and the (corrected) endurance limit S_e, Pa (shear values for torsion).
    yield_strength : float, optional
        S_y, Pa (required by "soderberg" and "asme-elliptic").
    criterion : {"goodman", "gerber", "soderberg", "asme-elliptic"}

    Returns
    -------
    float or ndarray
        Safety factor (inf for a zero load).

    References
    ----------
    Shi, *Engine Dynamics*, pre-reading 1 §(4) eq. (5a), (5b) and fig. 1; Shigley §6-12,
    Tables 6-7, 6-8.

    Examples
    --------
    >>> round(safety_factor(100e6, 100e6, ultimate=600e6, endurance=300e6), 4)
    2.0
    >>> round(safety_factor(100e6, 100e6, ultimate=600e6, endurance=300e6,
    ...                     criterion="gerber"), 4)
    2.4853
    """
    su, se, sy, criterion = _strengths(ultimate, endurance, yield_strength, criterion)
    sa = check_finite_array(alternating, "alternating", error=ModelError)
    sm = check_finite_array(mean, "mean", error=ModelError)
    if np.any(sa < 0):
        raise ModelError("alternating stress must be >= 0 (it is an amplitude)")
    sa, sm = np.broadcast_arrays(sa, sm)
    with np.errstate(divide="ignore"):
        n = np.where(sm > 0, _fatigue_factor(sa, np.maximum(sm, 0.0), su, se, sy, criterion),
                     se / np.where(sa > 0, sa, 0.0))
        if sy is not None:
            n = np.minimum(n, sy / (sa + np.abs(sm)))
    n = np.where((sa == 0) & (sm == 0), np.inf, n)
    return float(n) if n.ndim == 0 else n


def first_cycle_yield(alternating, mean, *, yield_strength):
    """First-cycle yield safety factor n_y = S_y / (σ_a + |σ_m|).

    Examples
    --------
    >>> first_cycle_yield(100e6, -50e6, yield_strength=450e6)
    3.0
    """
    sy = check_positive(yield_strength, "yield_strength", error=ModelError)
    sa = check_finite_array(alternating, "alternating", error=ModelError)
    sm = check_finite_array(mean, "mean", error=ModelError)
    if np.any(sa < 0):
        raise ModelError("alternating stress must be >= 0 (it is an amplitude)")
    with np.errstate(divide="ignore"):
        n = sy / (sa + np.abs(sm))
    return float(n) if np.ndim(n) == 0 else n


@dataclass(frozen=True)
class EnduranceDiagram:
    """Endurance (Haigh) diagram of one material and criterion.

    Parameters
    ----------
    ultimate, endurance : float
        S_u and S_e, Pa.
    yield_strength : float, optional
        S_y, Pa: cuts the diagram with the yield line σ_a + σ_m = S_y.
    criterion : {"goodman", "gerber", "soderberg", "asme-elliptic"}

    Examples
    --------
    >>> d = EnduranceDiagram(ultimate=47_000.0, endurance=22_000.0, yield_strength=26_400.0)
    >>> p = d.limit_point(alternating=60_000.0, mean=20_000.0)  # seed worked example
    >>> round(p.mean), round(p.alternating)  # printed (read off the graph): 6,400, 20,000
    (6344, 19031)
    """

    ultimate: float
    endurance: float
    yield_strength: float | None = None
    criterion: str = "goodman"

    def __post_init__(self):
        su, se, sy, crit = _strengths(self.ultimate, self.endurance, self.yield_strength,
                                      self.criterion)
        for name, value in (("ultimate", su), ("endurance", se), ("yield_strength", sy),
                            ("criterion", crit)):
            object.__setattr__(self, name, value)

    def allowable_alternating(self, mean):
        """Largest alternating stress (Pa) the diagram allows at mean stress ``mean`` (Pa)."""
        sm = check_finite_array(mean, "mean", error=ModelError)
        su, se, sy = self.ultimate, self.endurance, self.yield_strength
        pos = np.maximum(sm, 0.0)
        if self.criterion == "goodman":
            sa = se * (1 - pos / su)
        elif self.criterion == "gerber":
            sa = se * (1 - (pos / su) ** 2)
        elif self.criterion == "soderberg":
            sa = se * (1 - pos / sy)
        else:
            sa = se * np.sqrt(np.clip(1 - (pos / sy) ** 2, 0.0, None))
        if sy is not None:
            sa = np.minimum(sa, sy - np.abs(sm))
        sa = np.clip(sa, 0.0, None)
        return float(sa) if sa.ndim == 0 else sa

    def safety_factor(self, alternating, mean):
        """:func:`safety_factor` with this diagram's strengths and criterion."""
        return safety_factor(alternating, mean, ultimate=self.ultimate, endurance=self.endurance,
                             yield_strength=self.yield_strength, criterion=self.criterion)

    def limit_point(self, *, alternating, mean) -> StressPoint:
        """Point where the load line through (σ_m, σ_a) meets the diagram's boundary."""
        n = self.safety_factor(alternating, mean)
        if not np.isfinite(n):
            raise ModelError("a zero load point has no load line")
        return StressPoint(alternating=float(alternating) * n, mean=float(mean) * n)

    def crossover(self) -> StressPoint:
        """Where the fatigue line meets the yield (Langer) line σ_a + σ_m = S_y.

        Load lines steeper than the one through this point fail by fatigue first, flatter ones
        by first-cycle yield. Closed forms (Shigley 9th ed. Tables 6-6 to 6-8):
        Goodman σ_m = (S_y − S_e) S_u/(S_u − S_e); Gerber
        σ_m = S_u²/(2S_e)·[1 − √(1 + (2S_e/S_u)²(1 − S_y/S_e))]; ASME elliptic
        σ_a = 2 S_e² S_y/(S_e² + S_y²); Soderberg meets it only at (S_y, 0).

        Raises ModelError without a yield strength, or when S_y ≤ S_e (the yield line then
        lies below the fatigue line everywhere: yield governs every load line).

        Examples
        --------
        >>> d = EnduranceDiagram(ultimate=600e6, endurance=250e6, yield_strength=450e6,
        ...                      criterion="gerber")
        >>> p = d.crossover()
        >>> round(p.mean / 1e6, 2), round(p.alternating / 1e6, 2)
        (240.0, 210.0)
        """
        su, se, sy = self.ultimate, self.endurance, self.yield_strength
        if sy is None:
            raise ModelError("crossover needs yield_strength (Pa)")
        if sy <= se:
            raise ModelError(f"yield_strength={sy:g} Pa <= endurance={se:g} Pa: the yield line "
                             "governs every load line, there is no crossover")
        if self.criterion == "goodman":
            sm = (sy - se) * su / (su - se)
        elif self.criterion == "gerber":
            sm = su * su / (2 * se) * (1 - math.sqrt(1 + (2 * se / su) ** 2 * (1 - sy / se)))
        elif self.criterion == "asme-elliptic":
            sm = sy - 2 * se * se * sy / (se * se + sy * sy)
        else:
            sm = sy
        return StressPoint(alternating=max(sy - sm, 0.0), mean=sm)

    def to_frame(self, n_points: int = 101):
        """Boundary of the diagram: columns mean, allowable_alternating (Pa)."""
        import pandas as pd

        top = self.yield_strength or self.ultimate
        sm = np.linspace(-top, top, n_points) if self.yield_strength else np.linspace(
            0.0, self.ultimate, n_points)
        return pd.DataFrame({"mean": sm, "allowable_alternating": self.allowable_alternating(sm)})

    def plot(self, ax=None, *, points=()):
        """Haigh diagram in MPa with optional load points ``[(alternating, mean), ...]``."""
        import matplotlib.pyplot as plt

        fig, ax = (plt.subplots() if ax is None else (ax.figure, ax))
        frame = self.to_frame()
        ax.plot(frame["mean"] / 1e6, frame["allowable_alternating"] / 1e6,
                label=f"{self.criterion}" + (" + yield" if self.yield_strength else ""))
        for sa, sm in points:
            lim = self.limit_point(alternating=sa, mean=sm)
            ax.plot([0, lim.mean / 1e6], [0, lim.alternating / 1e6], "k:", lw=0.8)
            ax.plot(sm / 1e6, sa / 1e6, "ko")
        ax.set_xlabel("mean stress (MPa)")
        ax.set_ylabel("alternating stress (MPa)")
        ax.set_xlim(left=min(0.0, ax.get_xlim()[0]))
        ax.set_ylim(bottom=0.0)
        ax.legend()
        ax.set_title("endurance diagram")
        return fig


@dataclass(frozen=True)
class FatigueAssessment:
    """Safety factors of one load point under every applicable criterion.

    Attributes
    ----------
    point : StressPoint
    factors : dict
        criterion -> safety factor (fatigue, cut by yield when S_y is known).
    yield_factor : float
        First-cycle yield factor (NaN without S_y).
    diagram : EnduranceDiagram
        Diagram of the governing (lowest-factor) criterion, for plotting.
    """

    point: StressPoint
    factors: dict
    yield_factor: float
    diagram: EnduranceDiagram

    @property
    def governing(self) -> str:
        """Criterion with the lowest safety factor."""
        return min(self.factors, key=self.factors.get)

    def to_frame(self):
        """Table: criterion, safety_factor (plus 'first-cycle yield')."""
        import pandas as pd

        rows = [{"criterion": k, "safety_factor": v} for k, v in self.factors.items()]
        rows.append({"criterion": "first-cycle yield", "safety_factor": self.yield_factor})
        return pd.DataFrame(rows)

    def plot(self, ax=None):
        """Every criterion's diagram with the load point; returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = (plt.subplots() if ax is None else (ax.figure, ax))
        d = self.diagram
        for crit in self.factors:
            EnduranceDiagram(d.ultimate, d.endurance, d.yield_strength, crit).plot(ax)
        ax.plot(self.point.mean / 1e6, self.point.alternating / 1e6, "ko")
        return fig


def assess(alternating, mean, *, ultimate, endurance, yield_strength=None,
           criteria=CRITERIA) -> FatigueAssessment:
    """Safety factors of one load point under several criteria (those needing S_y skipped
    when it is not given).

    Examples
    --------
    >>> a = assess(100e6, 100e6, ultimate=600e6, endurance=300e6, yield_strength=450e6)
    >>> a.governing, round(a.factors["soderberg"], 3)
    ('soderberg', 1.8)
    """
    point = StressPoint(float(alternating), float(mean))
    factors = {}
    for crit in criteria:
        check_option(crit, "criteria", CRITERIA, error=ModelError)
        if crit in _NEEDS_YIELD and yield_strength is None:
            continue
        factors[crit] = safety_factor(point.alternating, point.mean, ultimate=ultimate,
                                      endurance=endurance, yield_strength=yield_strength,
                                      criterion=crit)
    if not factors:
        raise ModelError("no criterion applies: give yield_strength for soderberg/asme-elliptic")
    ny = (first_cycle_yield(point.alternating, point.mean, yield_strength=yield_strength)
          if yield_strength is not None else float("nan"))
    gov = min(factors, key=factors.get)
    return FatigueAssessment(point, factors, ny,
                             EnduranceDiagram(ultimate, endurance, yield_strength, gov))
