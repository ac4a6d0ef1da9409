"""Finite fatigue life and combined bending + torsion fatigue of crank pins, journals and webs.

* **S–N curve (Basquin):** ``σ_a = a N^b`` between the low-cycle point (10³ cycles at f·S_u)
  and the endurance knee (N_e cycles at S_e), i.e. ``N = N_e (S_e/σ_a)^k`` with ``k = −1/b``;
  below S_e the life is infinite (or, with ``haibach=True``, continues with slope 2k − 1).
* **Miner's rule:** damage ``D = Σ nᵢ/Nᵢ`` over the cycles of a rainflow count
  (:func:`predict.fatigue.rainflow`) of a measured or predicted history, each cycle's mean
  stress folded into an equivalent fully reversed amplitude (Goodman ``σ_a/(1 − σ_m/S_u)`` or
  Gerber ``σ_a/(1 − (σ_m/S_u)²)``; compressive means not credited); failure at D = 1.
* **Combined stresses** at a fillet: nominal bending σ = 32 M D/(π (D⁴ − d⁴)) and torsion
  τ = 16 T D/(π (D⁴ − d⁴)) times fillet stress-concentration factors; judged by
  von Mises (σ_eq = √(σ² + 3τ²), alternating and mean parts apart, then the chosen mean-stress
  criterion against the bending endurance limit) or by the Gough–Pollard ellipse quadrant
  ``(σ_a/σ_e)² + (τ_a/τ_e)² = 1/n²`` (endurance limits reduced by the von Mises mean stress
  with Goodman).

References
----------
.. [1] R. G. Budynas, J. K. Nisbett, *Shigley's Mechanical Engineering Design*, 9th ed.,
   §6-7 eq. (6-13)-(6-16) (S–N line from 10³ to 10⁶ cycles; Example 6-2: S_u = 90 kpsi,
   S_e = 45 kpsi, f = 0.86 → a = 133.1 kpsi, b = −0.0785, S_f(10⁴) = 64.6 kpsi,
   N(55 kpsi) ≈ 77 500), §6-15 (Miner's rule), §6-14 (von Mises for combined loading).
.. [2] H. J. Gough, H. V. Pollard, "The strength of metals under combined alternating
   stresses", Proc. IMechE 131 (1935) 3-103 (the ellipse quadrant for ductile steels).
.. [3] IACS UR M53, §2-§6: nominal web bending and pin/journal torsional stresses times the
   stress-concentration factors α_B, α_T (web and pin bases: :mod:`predict.crankshaft_scf`);
   equivalent alternating stress √((σ + σ_add)² + 3τ²).
.. [4] ASTM E1049-85 (2017) §5.4.4 (rainflow).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validate import check_finite_array, check_option, check_positive, check_range
from .errors import ModelError

__all__ = ["SNCurve", "miner_damage", "MinerResult", "fillet_stresses", "combined_safety_factor",
           "COMBINED_CRITERIA"]

COMBINED_CRITERIA = ("von-mises", "gough-pollard")


@dataclass(frozen=True)
class SNCurve:
    """Basquin S–N curve with an endurance knee.

    Parameters
    ----------
    endurance : float
        S_e, alternating stress at the knee, Pa.
    knee_cycles : float
        N_e, cycles at the knee (10⁶ for steels in Shigley's form).
    slope : float
        k in N = N_e (S_e/σ_a)^k (k = −1/b of Basquin's σ_a = a N^b).
    haibach : bool
        Continue below the knee with slope 2k − 1 (instead of infinite life).

    Examples
    --------
    >>> ksi = 6.894757e6                                # Shigley 9th ed. Example 6-2
    >>> sn = SNCurve.from_ultimate(ultimate=90 * ksi, endurance=45 * ksi, fraction=0.86)
    >>> a, b = sn.basquin
    >>> round(float(a) / ksi, 1), round(float(b), 4), round(float(sn.cycles(55 * ksi)), -2)
    (133.1, -0.0785, 77600.0)
    """

    endurance: float
    knee_cycles: float = 1.0e6
    slope: float = 10.0
    haibach: bool = False

    def __post_init__(self):
        check_positive(self.endurance, "endurance", error=ModelError)
        check_positive(self.knee_cycles, "knee_cycles", error=ModelError)
        check_positive(self.slope, "slope", error=ModelError)

    @classmethod
    def from_ultimate(cls, *, ultimate, endurance, fraction=0.9, knee_cycles=1.0e6,
                      haibach=False) -> "SNCurve":
        """The line from (10³, f·S_u) to (N_e, S_e) (Shigley eq. 6-13 to 6-16).

        ``fraction`` is Shigley's f (fig. 6-18: 0.9 for S_u ≤ 490 MPa down to about 0.77
        at 1400 MPa).
        """
        su = check_positive(ultimate, "ultimate", error=ModelError)
        se = check_positive(endurance, "endurance", error=ModelError)
        f = check_range(fraction, "fraction", 0.0, 1.0, inclusive=(False, True),
                        error=ModelError)
        if f * su <= se:
            raise ModelError(f"fraction·ultimate = {f * su:g} Pa must exceed endurance={se:g}")
        b = -np.log10(f * su / se) / np.log10(check_positive(knee_cycles, "knee_cycles",
                                                              error=ModelError) / 1e3)
        return cls(endurance=se, knee_cycles=knee_cycles, slope=-1.0 / b, haibach=haibach)

    @property
    def basquin(self) -> tuple[float, float]:
        """(a, b) of σ_a = a N^b, Pa."""
        b = -1.0 / self.slope
        return float(self.endurance / self.knee_cycles ** b), float(b)

    def strength(self, cycles):
        """Alternating stress (Pa) for a life of ``cycles`` (≤ the knee)."""
        a, b = self.basquin
        return a * np.asarray(cycles, float) ** b

    def cycles(self, alternating):
        """Cycles to failure at fully reversed amplitude ``alternating`` (Pa); inf below the
        knee (unless ``haibach``)."""
        s = check_finite_array(alternating, "alternating", error=ModelError)
        with np.errstate(divide="ignore"):
            n = self.knee_cycles * (self.endurance / s) ** self.slope
            if self.haibach:
                n2 = self.knee_cycles * (self.endurance / s) ** (2 * self.slope - 1)
                n = np.where(s < self.endurance, n2, n)
            else:
                n = np.where(s < self.endurance, np.inf, n)
        return float(n) if n.ndim == 0 else n

    def to_frame(self, n_points: int = 50):
        """Curve points: cycles, alternating (Pa)."""
        import pandas as pd

        n = np.geomspace(1e3, self.knee_cycles * 100, n_points)
        s = np.where(n <= self.knee_cycles, self.strength(np.minimum(n, self.knee_cycles)),
                     self.endurance)
        return pd.DataFrame({"cycles": n, "alternating": s})

    def plot(self, ax=None):
        """Log-log S–N curve (MPa); returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = (plt.subplots() if ax is None else (ax.figure, ax))
        f = self.to_frame()
        ax.loglog(f.cycles, f.alternating / 1e6)
        ax.set_xlabel("cycles")
        ax.set_ylabel("alternating stress (MPa)")
        return fig


@dataclass(frozen=True)
class MinerResult:
    """Miner damage of a load history.

    Attributes
    ----------
    damage : float
        D = Σ n/N for one pass of the history.
    life_repeats : float
        Passes of the history to failure, 1/D (inf for D = 0).
    cycles : pandas.DataFrame
        Per counted cycle: alternating, mean, equivalent (Pa), count, cycles_to_failure,
        damage.
    mean_correction : str
    """

    damage: float
    life_repeats: float
    cycles: object
    mean_correction: str

    def to_frame(self):
        """The per-cycle table."""
        return self.cycles

    def plot(self, ax=None):
        """Damage per cycle against its equivalent amplitude (MPa); returns the figure."""
        import matplotlib.pyplot as plt

        fig, ax = (plt.subplots() if ax is None else (ax.figure, ax))
        ax.scatter(self.cycles["equivalent"] / 1e6, self.cycles["damage"])
        ax.set_xlabel("equivalent amplitude (MPa)")
        ax.set_ylabel("damage")
        ax.set_title(f"Miner: D = {self.damage:.3g}")
        return fig


def miner_damage(history, sn: SNCurve, *, ultimate=None, mean_correction="goodman"):
    """Miner's-rule damage of a stress history (or of already counted cycles).

    Parameters
    ----------
    history : array_like or RainflowCycles
        Stress samples, Pa (rainflow-counted here), or a :class:`~predict.fatigue.RainflowCycles`.
    sn : SNCurve
    ultimate : float, optional
        S_u, Pa (needed for a mean-stress correction).
    mean_correction : {"goodman", "gerber", "none"}

    Returns
    -------
    MinerResult

    Examples
    --------
    >>> sn = SNCurve(endurance=100e6, knee_cycles=1e6, slope=5.0)
    >>> r = miner_damage([0, 200e6, -200e6, 200e6, -200e6, 0], sn, mean_correction="none")
    >>> r.damage   # 3 half cycles at ±200 MPa (N = 10⁶/2⁵) and 2 half cycles of 100 MPa
    4.9e-05
    """
    import pandas as pd

    from .fatigue import RainflowCycles, rainflow

    if not isinstance(sn, SNCurve):
        raise ModelError(f"sn must be an SNCurve, got {type(sn).__name__}")
    mean_correction = check_option(mean_correction, "mean_correction",
                                   ("goodman", "gerber", "none"), error=ModelError)
    cyc = history if isinstance(history, RainflowCycles) else rainflow(history)
    sa, sm, cnt = cyc.alternating, cyc.mean, cyc.count
    if mean_correction == "none":
        eq = sa.copy()
    else:
        su = check_positive(ultimate, "ultimate", error=ModelError)
        pos = np.maximum(sm, 0.0)
        if np.any(pos >= su):
            raise ModelError("a cycle's mean stress reaches the ultimate strength")
        eq = sa / (1 - pos / su) if mean_correction == "goodman" else sa / (1 - (pos / su) ** 2)
    n_f = np.atleast_1d(sn.cycles(eq)) if eq.size else np.zeros(0)
    dmg = np.where(np.isinf(n_f), 0.0, cnt / np.where(np.isinf(n_f), 1.0, n_f))
    total = float(dmg.sum())
    frame = pd.DataFrame({"alternating": sa, "mean": sm, "equivalent": eq, "count": cnt,
                          "cycles_to_failure": n_f, "damage": dmg})
    return MinerResult(damage=total, life_repeats=float(np.inf if total == 0 else 1 / total),
                       cycles=frame, mean_correction=mean_correction)


def fillet_stresses(*, bending_moment, torque, diameter, bore=0.0, bending_scf=1.0,
                    torsion_scf=1.0):
    """Peak fillet stresses of a round pin or journal from bending moment and torque histories.

    σ = α · 32 M D/(π (D⁴ − d⁴)), τ = α_T · 16 T D/(π (D⁴ − d⁴)): both on the pin (or journal)
    section. The torsion factor may be UR M53's α_T or β_T (same nominal basis); the rule's
    bending factors α_B, β_B are defined on the *web* section instead — for them use
    :func:`predict.crankshaft.web_stresses` or :func:`predict.crankshaft_scf.m53_fillet_stresses`.

    Parameters
    ----------
    bending_moment, torque : array_like
        Histories (or single values), N·m.
    diameter, bore : float
        m.
    bending_scf, torsion_scf : float
        Fillet stress-concentration factors (≥ 1) on the pin-section nominal stresses, from
        the engine maker or FE (bending) and FE or UR M53 (torsion,
        :func:`predict.crankshaft_scf.stress_concentration_factors`).

    Returns
    -------
    dict
        ``bending`` and ``torsion`` stress arrays (Pa) and their ``bending_alternating``,
        ``bending_mean``, ``torsion_alternating``, ``torsion_mean`` (half range and mid
        range).

    Examples
    --------
    >>> r = fillet_stresses(bending_moment=[-1000.0, 3000.0], torque=[0.0, 2000.0],
    ...                     diameter=0.1, bending_scf=2.0, torsion_scf=1.5)
    >>> round(r["bending_alternating"] / 1e6, 3), round(r["torsion_mean"] / 1e6, 3)
    (40.744, 7.639)
    """
    m = check_finite_array(bending_moment, "bending_moment", error=ModelError)
    t = check_finite_array(torque, "torque", error=ModelError)
    d = check_positive(diameter, "diameter", error=ModelError)
    di = float(bore)
    if not 0 <= di < d:
        raise ModelError(f"bore={bore!r} must lie in [0, diameter)")
    ab = float(bending_scf)
    at = float(torsion_scf)
    if not (ab >= 1 and at >= 1):
        raise ModelError("bending_scf and torsion_scf must be >= 1")
    k = d / (np.pi * (d ** 4 - di ** 4))
    s = ab * 32 * k * m
    tau = at * 16 * k * t
    return dict(bending=s, torsion=tau,
                bending_alternating=float(np.ptp(s) / 2),
                bending_mean=float((s.max() + s.min()) / 2),
                torsion_alternating=float(np.ptp(tau) / 2),
                torsion_mean=float((tau.max() + tau.min()) / 2))


def combined_safety_factor(*, bending_alternating, torsion_alternating, bending_mean=0.0,
                           torsion_mean=0.0, bending_endurance, torsion_endurance=None,
                           ultimate, criterion="gough-pollard", mean_criterion="goodman"):
    """Fatigue safety factor under combined bending and torsion.

    Parameters
    ----------
    bending_alternating, torsion_alternating : float
        σ_a, τ_a, Pa.
    bending_mean, torsion_mean : float
        σ_m, τ_m, Pa.
    bending_endurance : float
        σ_e (reversed bending), Pa.
    torsion_endurance : float, optional
        τ_e, Pa (default σ_e/√3, the von Mises ratio).
    ultimate : float
        S_u, Pa.
    criterion : {"gough-pollard", "von-mises"}
    mean_criterion : {"goodman", "gerber"}
        How the (von Mises) mean stress reduces the endurance.

    Returns
    -------
    float

    Examples
    --------
    >>> round(combined_safety_factor(bending_alternating=100e6, torsion_alternating=50e6,
    ...                              bending_endurance=300e6, ultimate=800e6), 4)
    2.2678
    """
    sa = float(bending_alternating)
    ta = float(torsion_alternating)
    if sa < 0 or ta < 0:
        raise ModelError("alternating stresses must be >= 0 (amplitudes)")
    se = check_positive(bending_endurance, "bending_endurance", error=ModelError)
    te = se / np.sqrt(3) if torsion_endurance is None else check_positive(
        torsion_endurance, "torsion_endurance", error=ModelError)
    su = check_positive(ultimate, "ultimate", error=ModelError)
    criterion = check_option(criterion, "criterion", COMBINED_CRITERIA, error=ModelError)
    mean_criterion = check_option(mean_criterion, "mean_criterion", ("goodman", "gerber"),
                                  error=ModelError)
    sm = float(np.sqrt(max(float(bending_mean), 0.0) ** 2 + 3 * float(torsion_mean) ** 2))
    if sm >= su:
        raise ModelError("the von Mises mean stress reaches the ultimate strength")
    red = 1 - sm / su if mean_criterion == "goodman" else 1 - (sm / su) ** 2
    if criterion == "von-mises":
        eq = np.sqrt(sa * sa + 3 * ta * ta)
        return float(np.inf if eq == 0 else se * red / eq)
    q = (sa / (se * red)) ** 2 + (ta / (te * red)) ** 2
    return float(np.inf if q == 0 else 1 / np.sqrt(q))
