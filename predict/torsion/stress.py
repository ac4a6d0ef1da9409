"""Vibratory shear stress against continuous and transient limits; barred speed ranges.

Classification rules give two limits for the torsional vibration stress of shafts as
functions of speed: a *continuous* limit τ_c (steady running) and a *transient* limit τ_t
(passing through quickly). The limits come either from the rule data in the model
(:class:`predict.torsion.rules.RuleLimits`: IACS UR M68 for shafting, the engine maker's
figure for the crankshaft) or from user-given curves (:class:`StressLimits`, speed in rpm,
stress in MPa). A speed where the superposed stress exceeds τ_c is *barred* (to be passed
quickly); exceeding τ_t is not acceptable.

References
----------
.. [1] 交通大学内燃机教研组, 内燃机动力学、构造与计算 (上册), 1958, 第二篇 第四章 §4
   (临界转速时曲轴的附加应力).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import check_finite_array
from ..errors import ModelError

__all__ = ["StressLimits", "StressCheck", "check_stress"]


@dataclass(frozen=True)
class StressLimits:
    """Continuous and transient shear-stress limit curves vs speed.

    Attributes
    ----------
    speed_rpm : ndarray
        Ascending speeds, rpm.
    continuous : ndarray
        Continuous-running limit, Pa.
    transient : ndarray
        Transient limit, Pa (≥ continuous).
    sections : tuple of str
        Section names the limits apply to (empty = every section with a diameter).
    source : str
        Where the curves came from (rule, edition), for the report.

    Examples
    --------
    >>> lim = StressLimits([0, 1000], [40e6, 30e6], [100e6, 80e6])
    >>> print(lim.at([500.0])[0] / 1e6)
    [35.]
    """

    speed_rpm: np.ndarray
    continuous: np.ndarray
    transient: np.ndarray
    sections: tuple = ()
    source: str = "user-given"

    def __init__(self, speed_rpm, continuous, transient, sections=(), source="user-given"):
        s = check_finite_array(speed_rpm, "speed_rpm", ndim=1, min_length=1, error=ModelError)
        c = check_finite_array(continuous, "continuous", ndim=1, error=ModelError)
        t = check_finite_array(transient, "transient", ndim=1, error=ModelError)
        if not (c.size == t.size == s.size):
            raise ModelError(f"limits: speed_rpm ({s.size}), continuous ({c.size}) and "
                             f"transient ({t.size}) must have the same length")
        if np.any(np.diff(s) <= 0):
            raise ModelError("limits: speed_rpm must be strictly ascending")
        if np.any(c <= 0) or np.any(t < c):
            raise ModelError("limits: need 0 < continuous <= transient at every speed")
        object.__setattr__(self, "speed_rpm", s)
        object.__setattr__(self, "continuous", c)
        object.__setattr__(self, "transient", t)
        object.__setattr__(self, "sections", tuple(sections))
        object.__setattr__(self, "source", str(source))

    def at(self, speed_rpm):
        """(continuous, transient) limits at the speeds, Pa (linear interpolation, held
        constant outside the table)."""
        x = np.asarray(speed_rpm, float)
        return (np.interp(x, self.speed_rpm, self.continuous),
                np.interp(x, self.speed_rpm, self.transient))

    def limits_for(self, section, speed_rpm, *, diameter=None):
        """(continuous, transient, rule text) for ``section`` at the speeds, Pa."""
        if self.sections and section not in self.sections:
            raise ModelError(f"limits have no curve for section {section!r}")
        c, t = self.at(speed_rpm)
        return c, t, f"user-given curves: {self.source}"

    def to_frame(self):
        import pandas as pd

        return pd.DataFrame({"speed_rpm": self.speed_rpm,
                             "continuous_mpa": self.continuous / 1e6,
                             "transient_mpa": self.transient / 1e6})

    def plot(self, ax=None):
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots()
        else:
            fig = ax.figure
        ax.plot(self.speed_rpm, self.continuous / 1e6, "g--", label="continuous limit")
        ax.plot(self.speed_rpm, self.transient / 1e6, "r--", label="transient limit")
        ax.set_xlabel("speed [rpm]")
        ax.set_ylabel("shear stress [MPa]")
        ax.legend()
        return fig


@dataclass(frozen=True)
class StressCheck:
    """Result of :func:`check_stress`.

    Attributes
    ----------
    speed_rpm : ndarray
    worst_stress : ndarray
        Largest superposed stress over the checked sections at each speed, Pa.
    worst_section : tuple of str
    continuous, transient : ndarray
        Limits at each speed, Pa.
    barred_ranges_rpm : list of (float, float)
        Speed ranges where the continuous limit is exceeded (interpolated crossings).
    transient_exceeded_rpm : list of (float, float)
        Ranges where even the transient limit is exceeded.
    """

    speed_rpm: np.ndarray
    worst_stress: np.ndarray
    worst_section: tuple
    continuous: np.ndarray
    transient: np.ndarray
    barred_ranges_rpm: list
    transient_exceeded_rpm: list
    rules: dict = None

    @property
    def passed(self) -> bool:
        """True if the transient limit is never exceeded."""
        return not self.transient_exceeded_rpm

    def to_frame(self):
        import pandas as pd

        return pd.DataFrame({"speed_rpm": self.speed_rpm,
                             "stress_mpa": self.worst_stress / 1e6,
                             "section": list(self.worst_section),
                             "continuous_mpa": self.continuous / 1e6,
                             "transient_mpa": self.transient / 1e6})

    def plot(self, ax=None):
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots(figsize=(7, 4))
        else:
            fig = ax.figure
        ax.plot(self.speed_rpm, self.worst_stress / 1e6, "k", label="superposed stress")
        ax.plot(self.speed_rpm, self.continuous / 1e6, "g--", label="continuous limit")
        ax.plot(self.speed_rpm, self.transient / 1e6, "r--", label="transient limit")
        for lo, hi in self.barred_ranges_rpm:
            ax.axvspan(lo, hi, color="orange", alpha=0.3)
        ax.set_xlabel("speed [rpm]")
        ax.set_ylabel("shear stress [MPa]")
        ax.legend(fontsize=8)
        fig.tight_layout()
        return fig


def _ranges(speed, excess):
    """Speed intervals where ``excess`` > 0, crossings linearly interpolated."""
    from .rules import barred_ranges

    return barred_ranges(speed, excess, np.zeros(len(excess)))


def check_stress(response, limits, *, diameters=None) -> StressCheck:
    """Compare a :class:`~predict.torsion.forced.ForcedResponse`'s superposed stresses with
    the limits of each section; return the barred speed ranges.

    Parameters
    ----------
    response : ForcedResponse
        Or any object with ``speed_rpm``, ``stress_total`` (n_speeds, n_sections, Pa) and
        ``edge_names``.
    limits : StressLimits or predict.torsion.rules.RuleLimits
        Limits per section (a StressLimits without sections applies to every section with a
        diameter).
    diameters : array_like, optional
        Outer diameter of every section, m (``system.section_diameters[:, 0]``): the M68 size
        factor of a section whose rule data gives none.

    Returns
    -------
    StressCheck
        At each speed the section closest to (or furthest beyond) its continuous limit.

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> r = SimpleNamespace(speed_rpm=np.array([100., 200., 300.]),
    ...                     stress_total=np.array([[10e6], [50e6], [10e6]]), edge_names=("s",))
    >>> c = check_stress(r, StressLimits([0, 400], [30e6, 30e6], [60e6, 60e6]))
    >>> print([tuple(round(v, 1) for v in b) for b in c.barred_ranges_rpm])
    [(150.0, 250.0)]
    """
    names = list(response.edge_names)
    stress_all = np.asarray(response.stress_total, float)
    speed = np.asarray(response.speed_rpm, float)
    sections = tuple(getattr(limits, "sections", ()))
    if sections:
        missing = [s for s in sections if s not in names]
        if missing:
            raise ModelError(f"limits.sections {missing} are not sections of the system "
                             f"({', '.join(names)})")
        cols = [names.index(s) for s in sections]
    else:
        cols = [i for i in range(len(names)) if np.any(np.isfinite(stress_all[:, i]))]
    if not cols:
        raise ModelError("no shaft section has a diameter: stresses cannot be checked "
                         "(give diameter= for the shafts)")
    if diameters is None and getattr(response, "system", None) is not None:
        diameters = response.system.section_diameters[:, 0]
    cont, trans, rules = [], [], {}
    for c in cols:
        d = None if diameters is None else float(np.asarray(diameters, float).ravel()[c])
        tc, tt, rule = limits.limits_for(names[c], speed, diameter=d)
        cont.append(tc)
        trans.append(tt)
        rules[names[c]] = rule
    cont, trans = np.stack(cont, axis=1), np.stack(trans, axis=1)
    stress = stress_all[:, cols]
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio_c = np.nan_to_num(stress / cont, nan=-np.inf)
        ratio_t = np.nan_to_num(stress / trans, nan=-np.inf)
    k = np.argmax(ratio_c, axis=1)
    rows = np.arange(len(k))
    worst = np.nan_to_num(stress[rows, k], nan=0.0)
    sec = tuple(names[cols[i]] for i in k)
    return StressCheck(speed, worst, sec, cont[rows, k], trans[rows, k],
                       _ranges(speed, ratio_c.max(axis=1) - 1.0),
                       _ranges(speed, ratio_t.max(axis=1) - 1.0), rules)
