"""Rotor balancing from trial-weight runs (influence coefficients) and ISO 21940-11 grades.

Measurements are the complex 1st-order vibration phasors V = A e^{iφ} (amplitude in any
consistent unit — µm, mm/s — and phase) at each measurement plane, for the initial run and for
each trial run. Trial and correction masses are complex too: m e^{iθ} (kg at the balancing
radius, angle θ). The method assumes a linear rotor: V = V₀ + A U with A the influence matrix
(measurement planes × correction planes). Phase and mass angles must be measured in the same
sense (e.g. both against the rotation from the key mark, the usual field convention); then
the algebra is complex-linear and the correction is U = −A⁺ V₀.

Accuracy: exact for a linear rotor and noise-free data. With a relative measurement error ε
the relative error of the correction is bounded to first order by
κ(A) (ε + max_j ε (|V₀| + |V_j|) / |V_j − V₀|) — large when the trial weights changed the
response little (warned) or the planes are nearly dependent (κ(A) large, warned).

References
----------
.. [1] Shi Zhiqing, *Applied Mechanics vol. 2: Engine Dynamics*, ch. 3 §11 "experimental
   balancing of rotors" (trial weights in the balancing machine).
.. [2] M. I. Friswell et al., *Dynamics of Rotating Machines* (2010), §8.4-8.5 (influence
   coefficient balancing, least squares, conditioning).
.. [3] ISO 21940-11:2016, *Mechanical vibration — Rotor balancing — Part 11: Procedures and
   tolerances for rotors with rigid behaviour*, §5 (balance grades G = e_per Ω), §7
   (allocation to correction planes).
"""

from __future__ import annotations

import logging
import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from crankbench.predict._deprecate import renamed

from ._threads import single_threaded_blas
from ._validate import check_finite_array, check_positive, check_range
from .errors import AnalysisError, ModelError

__all__ = [
    "BalanceWarning",
    "BalanceResult",
    "single_plane",
    "two_plane",
    "influence_balance",
    "phasor",
    "ISO_GRADES",
    "permissible_unbalance",
    "GradeCheck",
    "grade_check",
]

log = logging.getLogger("crankbench")

#: balance quality grades of ISO 21940-11 Table 1, G in mm/s
ISO_GRADES = (0.4, 1.0, 2.5, 6.3, 16.0, 40.0, 100.0, 250.0, 630.0, 1600.0, 4000.0)


class BalanceWarning(UserWarning):
    """The balancing data are poorly suited (trial weights too small, ill-conditioned)."""


def phasor(amplitude, phase_deg) -> np.ndarray:
    """Complex phasor(s) from amplitude and phase in degrees: A e^{iφ}.

    Examples
    --------
    >>> complex(np.round(phasor(2.0, 90.0), 12))
    2j
    """
    a = check_finite_array(amplitude, "amplitude", error=ModelError)
    p = check_finite_array(phase_deg, "phase_deg", error=ModelError)
    if np.any(a < 0):
        raise ModelError("amplitude must be >= 0 (put the sign into the phase)")
    return a * np.exp(1j * np.radians(p))


def _complex(values, name, ndim):
    arr = np.asarray(values)
    if arr.dtype.kind not in "biufc":
        raise ModelError(f"{name} must be numeric (complex phasors), got {arr.dtype}")
    arr = arr.astype(complex)
    if arr.ndim != ndim:
        raise ModelError(f"{name} must be {ndim}-dimensional, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ModelError(f"{name} contains NaN/inf")
    return arr


@dataclass(frozen=True)
class BalanceResult:
    """Correction masses from influence-coefficient balancing.

    Attributes
    ----------
    corrections : ndarray
        Complex correction masses per correction plane, kg at the trial-weight radius
        (magnitude = mass, angle = where to put it).
    influence : ndarray
        Influence matrix A, response unit per kg, shape (n_measurements, n_planes).
    initial : ndarray
        Initial-run phasors V₀.
    residual : ndarray
        Predicted vibration after correction V₀ + A U (zero for a square system).
    condition_number : float
        2-norm condition number κ(A) (after scaling each column to unit norm).
    trial_condition : float
        Condition number of the trial-mass matrix with each plane's column scaled to unit norm
        (1 for one trial per plane).
    response_change : ndarray
        |V_j − V₀| / |V₀| for each trial run (norms over the measurement planes).
    warnings : tuple of str
        Messages of the warnings issued.
    """

    corrections: np.ndarray
    influence: np.ndarray
    initial: np.ndarray
    residual: np.ndarray
    condition_number: float
    trial_condition: float
    response_change: np.ndarray
    warnings: tuple = field(default=())

    @property
    def correction_mass(self) -> np.ndarray:
        """Correction masses, kg."""
        return np.abs(self.corrections)

    @property
    def correction_angle(self) -> np.ndarray:
        """Correction angles, rad in [0, 2π)."""
        return np.mod(np.angle(self.corrections), 2 * np.pi)

    def error_bound(self, relative_noise: float) -> float:
        """First-order bound of the corrections' relative error for a relative measurement
        error ``relative_noise`` (see the module notes)."""
        eps = check_range(relative_noise, "relative_noise", 0.0, error=ModelError)
        change = np.where(self.response_change > 0, self.response_change, np.nan)
        eps_a = eps * (2 + change) / change  # (|V0| + |Vj|)/|ΔV| with |Vj| <= |V0|(1 + c)
        return float(self.condition_number * (eps + np.nanmax(eps_a)))

    def residual_unbalance(self, check_run=None) -> np.ndarray:
        """Residual unbalance per plane, complex kg at the trial radius.

        From a check run after correction (phasors at the measurement planes) when given:
        U_res = −A⁺ V_check; otherwise the least-squares remainder of the prediction.
        """
        v = self.residual if check_run is None else _complex(check_run, "check_run", 1)
        if v.shape != self.initial.shape:
            raise ModelError(f"check_run has {v.size} planes, expected {self.initial.size}")
        return -np.linalg.lstsq(self.influence, v, rcond=None)[0]

    def to_frame(self):
        """Table per correction plane: plane, mass (kg), angle_deg."""
        import pandas as pd

        return pd.DataFrame({"plane": np.arange(1, self.corrections.size + 1),
                             "mass": self.correction_mass,
                             "angle_deg": np.degrees(self.correction_angle)})

    def influence_frame(self):
        """Influence matrix as a table: measurement, plane, amplitude per kg, phase_deg."""
        import pandas as pd

        i, j = np.indices(self.influence.shape)
        return pd.DataFrame({"measurement": i.ravel() + 1, "plane": j.ravel() + 1,
                             "amplitude_per_kg": np.abs(self.influence).ravel(),
                             "phase_deg": np.degrees(np.angle(self.influence)).ravel()})

    def plot(self, ax=None):
        """Polar plot: initial and predicted residual vibration, correction masses."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots(subplot_kw={"projection": "polar"})
        else:
            fig = ax.figure
        for k, v in enumerate(self.initial):
            ax.annotate("", xy=(np.angle(v), abs(v)), xytext=(0, 0),
                        arrowprops=dict(arrowstyle="->", color="tab:red"))
            ax.plot(np.angle(v), abs(v), "o", color="tab:red", label=f"V0 plane {k + 1}")
        scale = np.abs(self.initial).max() / max(self.correction_mass.max(), 1e-300)
        for k, u in enumerate(self.corrections):
            ax.plot(np.angle(u), abs(u) * scale, "s", color="tab:blue",
                    label=f"correction {k + 1}: {abs(u):.3g} kg")
        ax.set_title("initial vibration and corrections (scaled)")
        ax.legend(fontsize="small", loc="lower left")
        return fig


@single_threaded_blas  # small least-squares solves (issue 21)
def influence_balance(initial, trial_runs, trial_masses, *, min_response_change=0.25,
                      max_condition=30.0) -> BalanceResult:
    """Influence-coefficient balancing with any number of planes (least squares).

    Parameters
    ----------
    initial : array_like of complex
        Initial-run phasors at the measurement planes, shape (n_meas,).
    trial_runs : array_like of complex
        Phasors of each trial run, shape (n_trials, n_meas).
    trial_masses : array_like of complex
        Trial masses m e^{iθ} (kg): shape (n_trials,) for one trial mass per run in plane
        j = run index (the usual procedure, weight removed before the next run), or
        (n_trials, n_planes) for the masses present in each run relative to the initial run.
    min_response_change : float
        Warn (:class:`BalanceWarning`) when a trial changed the response by less than this
        fraction of |V₀| — the trial weight was too small for the measurement to resolve.
    max_condition : float
        Warn when κ(A) or the trial-mass matrix condition exceeds this.

    Returns
    -------
    BalanceResult

    References
    ----------
    Friswell et al., *Dynamics of Rotating Machines* §8.4-8.5; Shi, *Engine Dynamics* ch. 3 §11.

    Examples
    --------
    >>> A = np.array([[2.0 + 1j, 0.5], [0.3j, 1.5 - 0.5j]])
    >>> u0 = np.array([0.010 * np.exp(0.3j), 0.006 * np.exp(2.0j)])
    >>> v0 = A @ u0
    >>> trials = np.array([v0 + A @ [0.02, 0], v0 + A @ [0, 0.02j]])
    >>> r = influence_balance(v0, trials, [0.02, 0.02j])
    >>> np.allclose(r.corrections, -u0)
    True
    """
    v0 = _complex(initial, "initial", 1)
    runs = _complex(trial_runs, "trial_runs", 2)
    masses = np.asarray(trial_masses)
    masses = _complex(masses, "trial_masses", masses.ndim if masses.ndim in (1, 2) else 1)
    n_meas = v0.size
    if runs.shape[1] != n_meas:
        raise ModelError(f"trial_runs has {runs.shape[1]} measurement planes per run, but "
                         f"initial has {n_meas}")
    n_trials = runs.shape[0]
    if masses.ndim == 1:
        if masses.size != n_trials:
            raise ModelError(f"trial_masses has {masses.size} values for {n_trials} trial runs")
        masses = np.diag(masses)
    if masses.shape[0] != n_trials:
        raise ModelError(f"trial_masses has {masses.shape[0]} rows for {n_trials} trial runs")
    n_planes = masses.shape[1]
    if n_trials < n_planes:
        raise ModelError(f"{n_trials} trial runs cannot identify {n_planes} correction planes")
    if n_meas < n_planes:
        raise ModelError(f"{n_meas} measurement planes cannot balance {n_planes} correction "
                         "planes (need at least as many measurements)")
    if np.any(np.abs(masses).sum(axis=1) == 0):
        raise ModelError("every trial run needs a non-zero trial mass")
    if np.any(np.abs(masses).sum(axis=0) == 0):
        raise ModelError("every correction plane needs a trial mass in some run")
    if not np.any(v0):
        raise ModelError("initial vibration is zero: nothing to balance")
    min_change = check_range(min_response_change, "min_response_change", 0.0, error=ModelError)
    max_cond = check_positive(max_condition, "max_condition", error=ModelError)

    delta = runs - v0[None, :]  # ΔV = ΔU Aᵀ
    msgs = []
    change = np.linalg.norm(delta, axis=1) / np.linalg.norm(v0)
    for j, c in enumerate(change):
        if c < min_change:
            msgs.append(f"trial run {j + 1} changed the vibration by only {100 * c:.3g} % of "
                        f"the initial run (< {100 * min_change:g} %): the trial weight was too "
                        "small; the influence coefficients are unreliable — use a heavier trial")
    # per-plane scaling: unequal trial sizes in different planes are fine, dependence is not
    trial_cond = float(np.linalg.cond(masses / np.linalg.norm(masses, axis=0)[None, :]))
    if trial_cond > max_cond:
        msgs.append(f"trial-mass matrix condition {trial_cond:.3g} > {max_cond:g}: the trial "
                    "weight sets are nearly dependent; place them in different planes/angles")
    a_t, *_ = np.linalg.lstsq(masses, delta, rcond=None)
    influence = a_t.T
    col = np.linalg.norm(influence, axis=0)
    if np.any(col == 0):
        raise AnalysisError("a correction plane has no influence on any measurement")
    cond = float(np.linalg.cond(influence / col[None, :]))
    if cond > max_cond:
        msgs.append(f"influence matrix condition number {cond:.3g} > {max_cond:g}: the "
                    "correction planes act almost alike on the measurements; corrections will "
                    "be sensitive to noise")
    corrections = -np.linalg.lstsq(influence, v0, rcond=None)[0]
    residual = v0 + influence @ corrections
    for msg in msgs:
        log.warning(msg)
        warnings.warn(msg, BalanceWarning, stacklevel=3)
    return BalanceResult(corrections=corrections, influence=influence, initial=v0,
                         residual=residual, condition_number=cond, trial_condition=trial_cond,
                         response_change=change, warnings=tuple(msgs))


def single_plane(initial, trial_run, trial_mass, **options) -> BalanceResult:
    """Single-plane balancing: U = −V₀ / α with α = (V₁ − V₀) / U_t.

    Parameters
    ----------
    initial, trial_run : complex
        Phasors of the initial and trial runs at one measurement plane.
    trial_mass : complex
        Trial mass m e^{iθ}, kg.
    **options
        ``min_response_change``, ``max_condition`` of :func:`influence_balance`.

    Returns
    -------
    BalanceResult

    Examples
    --------
    >>> r = single_plane(phasor(100.0, 30.0), phasor(60.0, 120.0), phasor(0.01, 0.0))
    >>> round(float(r.correction_mass[0]) * 1e3, 3), round(float(np.degrees(r.correction_angle[0])), 2)
    (8.575, 30.96)
    """
    return influence_balance(np.atleast_1d(initial), np.atleast_2d(trial_run),
                             np.atleast_1d(trial_mass), **options)


def two_plane(initial, trial_runs, trial_masses, **options) -> BalanceResult:
    """Two-plane balancing from an initial run and two trial runs.

    Parameters
    ----------
    initial : array_like of complex, shape (2,)
        Phasors at the two measurement planes (bearings), initial run.
    trial_runs : array_like of complex, shape (2, 2)
        Row j: phasors with the trial mass in correction plane j.
    trial_masses : array_like of complex, shape (2,) or (2, 2)
        Trial masses, kg (see :func:`influence_balance`).
    **options
        ``min_response_change``, ``max_condition``.

    Returns
    -------
    BalanceResult
        Correction masses and angles, influence matrix, condition number, residual.

    References
    ----------
    Friswell et al. §8.5 (two-plane balancing); ISO 21940-11 §7.

    Examples
    --------
    >>> r = two_plane(phasor([80.0, 60.0], [30.0, 200.0]),
    ...               [phasor([50.0, 70.0], [80.0, 210.0]), phasor([90.0, 30.0], [20.0, 250.0])],
    ...               [phasor(0.01, 0.0), phasor(0.01, 0.0)])
    >>> r.corrections.shape
    (2,)
    """
    v0 = _complex(initial, "initial", 1)
    runs = _complex(trial_runs, "trial_runs", 2)
    if v0.size != 2 or runs.shape != (2, 2):
        raise ModelError(f"two_plane needs 2 measurement planes and 2 trial runs, got initial "
                         f"{v0.shape} and trial_runs {runs.shape}; use influence_balance")
    return influence_balance(v0, runs, trial_masses, **options)


@renamed(max_speed="max_omega")
def permissible_unbalance(grade, *, rotor_mass, max_omega) -> float:
    """Permissible residual unbalance U_per = G · m / Ω (ISO 21940-11 §5), kg·m.

    Parameters
    ----------
    grade : float
        Balance grade G, mm/s (6.3 for G 6.3).
    rotor_mass : float
        kg.
    max_omega : float
        Maximum service speed Ω, rad/s.

    Returns
    -------
    float
        kg·m (1 g·mm = 1e-6 kg·m).

    Examples
    --------
    >>> round(permissible_unbalance(6.3, rotor_mass=100.0, max_omega=3000 * np.pi / 30) * 1e6)
    2005
    """
    g = check_positive(grade, "grade", error=ModelError)
    m = check_positive(rotor_mass, "rotor_mass", error=ModelError)
    w = check_positive(max_omega, "max_omega", error=ModelError)
    return g * 1e-3 * m / w


@dataclass(frozen=True)
class GradeCheck:
    """Residual unbalance against an ISO 21940-11 balance grade.

    Attributes
    ----------
    residual : ndarray
        |residual unbalance| per correction plane, kg·m.
    permissible : ndarray
        Permissible unbalance per plane for ``grade``, kg·m.
    achieved_grade : float
        e·Ω of the total residual, mm/s (e = ΣU/m).
    smallest_grade : float
        Smallest standard grade met (inf if worse than G 4000).
    grade : float
        Required grade, mm/s.
    """

    residual: np.ndarray
    permissible: np.ndarray
    achieved_grade: float
    smallest_grade: float
    grade: float

    @property
    def passed(self) -> bool:
        """True when every plane's residual is within its permissible share."""
        return bool(np.all(self.residual <= self.permissible))

    def to_frame(self):
        """Table per plane: residual and permissible (g·mm), passed."""
        import pandas as pd

        return pd.DataFrame({"plane": np.arange(1, self.residual.size + 1),
                             "residual_g_mm": self.residual * 1e6,
                             "permissible_g_mm": self.permissible * 1e6,
                             "passed": self.residual <= self.permissible})

    def plot(self, ax=None):
        """Bar chart of residual against permissible unbalance per plane."""
        import matplotlib.pyplot as plt

        fig, ax = (plt.subplots() if ax is None else (ax.figure, ax))
        x = np.arange(1, self.residual.size + 1)
        ax.bar(x - 0.2, self.residual * 1e6, 0.4, label="residual")
        ax.bar(x + 0.2, self.permissible * 1e6, 0.4, label=f"permissible G {self.grade:g}")
        ax.set_xticks(x)
        ax.set_xlabel("correction plane")
        ax.set_ylabel("unbalance (g·mm)")
        ax.legend()
        return fig


@renamed(max_speed="max_omega")
def grade_check(residual, *, rotor_mass, max_omega, grade=6.3, plane_shares=None) -> GradeCheck:
    """Compare residual unbalances with the permissible unbalance of a balance grade.

    Parameters
    ----------
    residual : array_like
        Residual unbalance per correction plane, kg·m (complex or magnitudes).
    rotor_mass : float
        kg.
    max_omega : float
        Maximum service speed, rad/s.
    grade : float
        Required grade G, mm/s.
    plane_shares : array_like, optional
        Fraction of U_per allotted to each plane (sum 1). Default equal shares — ISO
        21940-11 §7.2 for a rotor with its centre of mass midway between the planes; use
        the §7 bearing-distance rules otherwise.

    Returns
    -------
    GradeCheck

    Examples
    --------
    >>> g = grade_check([1.0e-3, 0.8e-3], rotor_mass=100.0, max_omega=314.159, grade=6.3)
    >>> g.passed, g.smallest_grade
    (True, 6.3)
    """
    res = np.abs(np.atleast_1d(np.asarray(residual)))
    if not np.all(np.isfinite(res)):
        raise ModelError("residual contains NaN/inf")
    m = check_positive(rotor_mass, "rotor_mass", error=ModelError)
    w = check_positive(max_omega, "max_omega", error=ModelError)
    g = check_positive(grade, "grade", error=ModelError)
    if plane_shares is None:
        shares = np.full(res.size, 1.0 / res.size)
    else:
        shares = check_finite_array(plane_shares, "plane_shares", ndim=1, error=ModelError)
        if shares.size != res.size or np.any(shares <= 0) or not math.isclose(shares.sum(), 1.0):
            raise ModelError(f"plane_shares={shares.tolist()} must be {res.size} positive "
                             "fractions summing to 1")
    achieved = float(res.sum() / m * w * 1e3)
    # a plane-wise check: the grade is met when each plane is within its share
    needed = float(np.max(res / shares) / m * w * 1e3)
    smallest = next((s for s in ISO_GRADES if s >= needed * (1 - 1e-12)), math.inf)
    return GradeCheck(residual=res, permissible=shares * permissible_unbalance(
        g, rotor_mass=m, max_omega=w), achieved_grade=achieved, smallest_grade=smallest,
        grade=g)
