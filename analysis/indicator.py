"""Thermodynamics of indicator diagrams on a crank-angle grid.

The functions here take cylinder pressure already resampled to crank angle (``crank_angle`` in
rad from the cylinder's firing TDC, evenly spaced, one working cycle: ``[-2π, 2π)`` for a
4-stroke, ``[-π, π)`` for a 2-stroke; ``pressure`` in Pa, one row per cycle) and the cylinder
geometry of a :class:`predict.engine.Engine` (bore, crank radius, rod, pin offset, compression
ratio give the exact volume ``V(ψ)`` and its slope ``dV/dψ`` from ``Engine.piston_motion``).

* **Mean effective pressures** (Heywood 1988, §2.4 and §5.4): net ``imep_n = ∮ p dV / V_s`` over
  the whole cycle, gross ``imep_g = ∫ p dV / V_s`` over compression and expansion (BDC to BDC,
  ψ ∈ [-π, π]), pumping ``pmep = imep_g − imep_n`` (positive when the gas exchange costs work,
  Heywood's sign). The net integral is a rectangle rule on a periodic integrand (spectrally
  accurate for a smooth trace); the gross one a trapezoid rule, O(h²) with h the grid step.
* **Pegging** (absolute level of a piezoelectric, i.e. relative, transducer; Randolph, SAE
  900170, 1990; Brunt & Pond, SAE 970036, 1997): ``"bdc"`` sets the mean pressure within ±10° of
  the intake BDC (ψ = −180°) to a given absolute pressure (the intake manifold pressure);
  ``"polytropic"`` fits ``p + Δp = C V^{-n}`` to the compression between ``window_deg`` (default
  −100° to −35°, after intake closing and before combustion), with ``n`` fitted on the mean
  cycle and ``Δp`` then found per cycle (a linear least-squares fit for fixed ``n``).
* **TDC check** (the thermodynamic loss angle): a wrong TDC shifts the whole diagram. The
  compression is fitted by ``p + Δp = C V(ψ − δ)^{-n}`` with ``n``, ``δ`` (and ``Δp``, ``C``)
  free (variable projection, Gauss–Newton), motored or fired; the standard error of ``δ``
  follows from the residual and the Jacobian. A motored cycle also gets the classical second
  estimate ``δ = ψ_peak + loss angle`` (the motored peak leads TDC by the loss angle, a few
  tenths of a degree to about one degree from heat transfer and blow-by; Pipitone & Beccari,
  Applied Thermal Engineering 30, 2010). A polytropic model has no heat transfer, so on real
  data the fitted ``δ`` carries a bias of the order of the loss angle besides its stated
  random error.
* **Heat release** (single zone, apparent, constant ratio of specific heats γ; Heywood §10.2,
  eq. 10.4): ``dQ/dψ = γ/(γ−1) p dV/dψ + 1/(γ−1) V dp/dψ``; cumulative release and mass fraction
  burnt (MFB) between the minimum before the peak and the maximum after it.

References
----------
J. B. Heywood, *Internal Combustion Engine Fundamentals*, McGraw-Hill 1988, §2.4 (indicated work
and mean effective pressure), §9.4 (cyclic variability, COV of imep), §10.2 (heat-release
analysis).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from crankbench.predict._validate import check_finite_array, check_int, check_range
from crankbench.predict.errors import AnalysisError

__all__ = ["chamber_volume", "mean_effective_pressures", "peg_bdc", "peg_polytropic",
           "thermodynamic_tdc", "TdcCheck", "heat_release", "HeatRelease", "cycle_peaks"]

log = logging.getLogger("crankbench")

DEG = np.pi / 180.0


# ------------------------------------------------------------------------------ geometry
def _cylinder_index(engine, cylinder) -> int:
    c = check_int(cylinder, "cylinder", minimum=1, error=AnalysisError)
    if c > engine.n_cylinders:
        raise AnalysisError(f"cylinder={c} but the engine {engine.name!r} has "
                            f"{engine.n_cylinders} cylinder(s)")
    return c - 1


def _check_engine(engine):
    missing = [k for k in ("bore", "compression_ratio") if getattr(engine, k, None) is None]
    if missing:
        raise AnalysisError(f"engine {engine.name!r} has no {' and no '.join(missing)}; the "
                            "indicator analysis needs the cylinder geometry (bore, stroke or "
                            "crank_radius, rod_length, compression_ratio in the [engine] table)")


def _volume_and_slope(engine, crank_angle, cylinder=1):
    """V (m³) and dV/dψ (m³/rad) of ``cylinder`` at ψ from its own firing TDC."""
    _check_engine(engine)
    i = _cylinder_index(engine, cylinder)
    psi = np.asarray(crank_angle, float)
    fire = np.deg2rad(engine.firing_angles_deg()[i])
    theta = engine.shaft_angle(psi.reshape(-1) + fire)
    v = engine.cylinder_volume(theta)[i]
    _, dx, _ = engine.piston_motion(theta)
    return v.reshape(psi.shape), (-engine.piston_area * dx[i]).reshape(psi.shape)


def chamber_volume(engine, crank_angle, *, cylinder=1):
    """Cylinder volume at crank angles from the cylinder's own firing TDC, m³.

    Parameters
    ----------
    engine : predict.engine.Engine
        With ``bore`` and ``compression_ratio``.
    crank_angle : array_like
        ψ, rad from the firing TDC of ``cylinder``.
    cylinder : int
        1-based cylinder number.

    Returns
    -------
    ndarray
        m³, shape of ``crank_angle``.

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
    ...            reciprocating_mass=1.0, bore=0.1, compression_ratio=11.0)
    >>> [round(float(v) * 1e6, 3) for v in chamber_volume(e, [0.0, np.pi])]   # cm³
    [78.54, 863.938]
    """
    return _volume_and_slope(engine, crank_angle, cylinder)[0]


def _grid(crank_angle, cycle):
    psi = check_finite_array(crank_angle, "crank_angle", ndim=1, min_length=16,
                             error=AnalysisError)
    h = np.diff(psi)
    period = np.pi * cycle
    if np.any(h <= 0) or np.ptp(h) > 1e-6 * h.mean():
        raise AnalysisError("crank_angle must be an evenly spaced ascending grid (rad)")
    if abs(psi.size * h.mean() - period) > 1e-6 * period:
        raise AnalysisError(f"crank_angle must cover one {cycle}-stroke cycle "
                            f"({np.rad2deg(period):g} deg) exactly; it covers "
                            f"{np.rad2deg(psi.size * h.mean()):.6g} deg")
    return psi, float(h.mean())


def _rows(pressure, n):
    p = np.asarray(pressure, float)
    p2 = np.atleast_2d(p)
    if p2.ndim != 2 or p2.shape[1] != n:
        raise AnalysisError(f"pressure must have shape ({n},) or (n_cycles, {n}) on the "
                            f"crank-angle grid, got {p.shape}")
    if not np.all(np.isfinite(p2)):
        raise AnalysisError("pressure contains NaN or inf")
    return p2


# ------------------------------------------------------------------------------ MEP
def mean_effective_pressures(engine, crank_angle, pressure, *, cylinder=1):
    """Net and gross indicated and pumping mean effective pressures, Pa.

    Parameters
    ----------
    engine : predict.engine.Engine
    crank_angle : array_like
        Evenly spaced grid over one cycle, rad from firing TDC (see module docstring).
    pressure : array_like
        Absolute pressure, Pa: (n,) one cycle or (n_cycles, n).
    cylinder : int

    Returns
    -------
    dict
        ``imep_net``, ``imep_gross``, ``pmep`` (Pa; arrays for 2-D input); for a 2-stroke
        gross = net and ``pmep`` is 0.

    References
    ----------
    Heywood 1988, §2.4 eq. (2.19) and §5.4.

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
    ...            reciprocating_mass=1.0, bore=0.1, compression_ratio=11.0)
    >>> psi = np.linspace(-2 * np.pi, 2 * np.pi, 7200, endpoint=False)
    >>> p = np.select([(psi > 0) & (psi < np.pi), psi > np.pi], [20e5, 1.2e5], 1e5)
    >>> m = mean_effective_pressures(e, psi, p)     # rectangles: 19 bar - (1.2 - 1.0) bar
    >>> [round(float(m[k]) / 1e5, 3) for k in ("imep_net", "imep_gross", "pmep")]
    [18.8, 19.0, 0.2]
    """
    cycle = engine.cycle
    psi, h = _grid(crank_angle, cycle)
    p = _rows(pressure, psi.size)
    _, dv = _volume_and_slope(engine, psi, cylinder)
    vs = engine.swept_volume
    net = p @ dv * h / vs
    if cycle == 4:
        inside = np.abs(psi) <= np.pi + 1e-9 * h
        w = np.where(inside, h, 0.0)
        ends = np.flatnonzero(inside)[[0, -1]]
        w[ends] *= 0.5                                    # trapezoid end weights
        gross = p @ (dv * w) / vs
    else:
        gross = net
    out = {"imep_net": net, "imep_gross": gross, "pmep": gross - net}
    if np.ndim(pressure) == 1:
        out = {k: float(v[0]) for k, v in out.items()}
    return out


# ------------------------------------------------------------------------------ peaks
def cycle_peaks(crank_angle, pressure, *, window_deg=3.0):
    """Peak pressure (Pa) and its angle (rad) of each cycle, by a local polynomial fit.

    Around the highest point of each cycle (found on the trace smoothed over ±1°), a quartic
    is fitted by least squares to the samples within ``±window_deg`` and its maximum taken
    (evaluated at 0.001° steps). A quartic follows an asymmetric combustion peak without the
    bias of a parabola, and the fit averages sample noise: on a 0.1° grid the angle's noise is
    about a quarter of the three-point vertex's. ``window_deg=0`` uses the three-point
    parabola through the highest sample (no smoothing).

    Returns
    -------
    dict
        ``pressure`` and ``angle`` arrays, one value per row of ``pressure``.

    Examples
    --------
    >>> psi = np.deg2rad(np.arange(-30.0, 30.0, 0.1))
    >>> pk = cycle_peaks(psi, 5e6 - 1e7 * (psi - np.deg2rad(10.23)) ** 2)
    >>> round(float(np.rad2deg(pk["angle"][0])), 3), round(float(pk["pressure"][0]), 3)
    (10.23, 5000000.0)
    """
    psi = check_finite_array(crank_angle, "crank_angle", ndim=1, min_length=3,
                             error=AnalysisError)
    p = _rows(pressure, psi.size)
    h = float(np.median(np.diff(psi)))
    m = int(round(check_range(window_deg, "window_deg", 0.0, 30.0, error=AnalysisError)
                  * DEG / h))
    r = np.arange(p.shape[0])
    if m < 3 or psi.size < 2 * m + 1:
        i = np.clip(np.argmax(p, axis=1), 1, psi.size - 2)
        y0, y1, y2 = p[r, i - 1], p[r, i], p[r, i + 1]
        den = y0 - 2 * y1 + y2
        frac = np.where(den < 0, 0.5 * (y0 - y2) / np.where(den < 0, den, -1.0), 0.0)
        frac = np.clip(frac, -0.5, 0.5)
        return {"pressure": y1 - 0.25 * (y0 - y2) * frac, "angle": psi[i] + frac * h}
    k = max(1, int(round(DEG / h)))
    from scipy.ndimage import uniform_filter1d

    smooth = uniform_filter1d(p, 2 * k + 1, axis=1, mode="nearest")
    i = np.clip(np.argmax(smooth, axis=1), m, psi.size - 1 - m)
    offs = np.arange(-m, m + 1)
    x = offs / m                                             # scaled abscissa
    basis = np.vander(x, 5, increasing=True)                 # 1, x, ..., x⁴
    coef = np.linalg.lstsq(basis, p[r[:, None], i[:, None] + offs[None, :]].T,
                           rcond=None)[0]                     # (5, n_cycles)
    fine = np.linspace(-1.0, 1.0, 2 * int(round(m * h / (0.001 * DEG))) + 1)
    values = np.vander(fine, 5, increasing=True) @ coef       # (n_fine, n_cycles)
    j = np.argmax(values, axis=0)
    return {"pressure": values[j, r], "angle": psi[i] + fine[j] * m * h}


# ------------------------------------------------------------------------------ pegging
def peg_bdc(crank_angle, pressure, *, level, window_deg=10.0):
    """Offsets (Pa) that bring the mean pressure around intake BDC to ``level``.

    Parameters
    ----------
    crank_angle : array_like
        Grid, rad from firing TDC (must contain ψ = −π).
    pressure : array_like
        (n,) or (n_cycles, n), Pa (relative or absolute).
    level : float
        Absolute pressure at BDC (the intake manifold pressure), Pa.
    window_deg : float
        Half-width of the averaging window around BDC, deg.

    Returns
    -------
    ndarray
        Offset per cycle, Pa: the absolute pressure is ``pressure + offset``.

    Examples
    --------
    >>> psi = np.linspace(-2 * np.pi, 2 * np.pi, 720, endpoint=False)
    >>> peg_bdc(psi, np.full(720, 0.3e5), level=1.0e5).round(3).tolist()
    [70000.0]
    """
    psi = check_finite_array(crank_angle, "crank_angle", ndim=1, min_length=3,
                             error=AnalysisError)
    p = _rows(pressure, psi.size)
    w = check_range(window_deg, "window_deg", 0.0, 90.0, inclusive=(False, True),
                    error=AnalysisError) * DEG
    sel = np.abs(psi + np.pi) <= w
    if not sel.any():
        raise AnalysisError("the crank-angle grid has no point near intake BDC (-180 deg)")
    return float(level) - p[:, sel].mean(axis=1)


def _fit_compression(v, p, *, n=None, delta_bound=0.7, fit_offset=True):
    """Least squares p + Δp = C V^{-n}, optionally with an angle shift (Gauss–Newton).

    ``v`` is a callable δ -> V(ψ − δ) when the shift is fitted, else an array. Returns dict
    with n, delta (rad), C, offset, residual rms and standard errors.
    """
    from scipy.optimize import least_squares

    def design(nn, d):
        vv = v(d) if callable(v) else v
        cols = [vv ** -nn]
        if fit_offset:
            cols.append(-np.ones_like(vv))
        return np.column_stack(cols)

    scale = float(np.max(np.abs(p))) or 1.0

    def inner(nn, d):
        a = design(nn, d)
        coef, *_ = np.linalg.lstsq(a / scale, p / scale, rcond=None)
        return a @ coef - p, coef

    free = [n is None, callable(v)]
    x0 = np.array([1.3, 0.0])[free]

    def unpack(x):
        it = iter(x)
        nn = next(it) if free[0] else n
        d = next(it) if free[1] else 0.0
        return nn, d

    if not any(free):
        res, coef = inner(n, 0.0)
        return {"n": n, "delta": 0.0, "C": coef[0], "offset": coef[1] if fit_offset else 0.0,
                "rms": float(np.sqrt(np.mean(res ** 2))), "delta_se": np.nan, "n_se": np.nan}
    lo = np.array([1.0, -delta_bound])[free]
    hi = np.array([1.8, delta_bound])[free]
    sol = least_squares(lambda x: inner(*unpack(x))[0] / scale, x0=x0, bounds=(lo, hi),
                        x_scale=np.array([0.05, 0.02])[free], method="trf")
    nn, d = unpack(sol.x)
    res, coef = inner(nn, d)
    dof = max(p.size - sol.x.size - coef.size, 1)
    se = np.full(2, np.nan)
    try:
        cov = np.linalg.inv(sol.jac.T @ sol.jac) * np.sum(sol.fun ** 2) / dof
        se[np.flatnonzero(free)] = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    except np.linalg.LinAlgError:
        pass
    return {"n": float(nn), "delta": float(d), "C": float(coef[0]),
            "offset": float(coef[1]) if fit_offset else 0.0,
            "rms": float(np.sqrt(np.mean(res ** 2))), "n_se": float(se[0]),
            "delta_se": float(se[1])}


def peg_polytropic(engine, crank_angle, pressure, *, cylinder=1, window_deg=(-100.0, -35.0),
                   exponent=None):
    """Offsets (Pa) that make the compression polytropic, and the exponent used.

    Fits ``p + Δp = C V^{-n}`` over the compression window: ``n`` (unless given) on the mean of
    the cycles, then ``Δp`` and ``C`` of each cycle for that ``n`` (linear least squares).

    Parameters
    ----------
    engine : predict.engine.Engine
    crank_angle : array_like
        Grid, rad from firing TDC.
    pressure : array_like
        (n,) or (n_cycles, n), Pa.
    cylinder : int
    window_deg : (float, float)
        Compression window, deg from firing TDC (after intake closing, before combustion).
    exponent : float, optional
        Polytropic exponent n; default fitted.

    Returns
    -------
    dict
        ``offset`` (Pa per cycle: absolute = pressure + offset), ``exponent``,
        ``exponent_se`` (standard error of the fitted n), ``rms`` (fit residual of the mean
        cycle, Pa), ``window_deg``.

    References
    ----------
    Randolph, SAE 900170 (1990); Brunt & Pond, SAE 970036 (1997).

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
    ...            reciprocating_mass=1.0, bore=0.1, compression_ratio=11.0)
    >>> psi = np.linspace(-2 * np.pi, 2 * np.pi, 1440, endpoint=False)
    >>> v = chamber_volume(e, psi)
    >>> p = 1e5 * (v.max() / v) ** 1.32 - 0.4e5              # polytropic, 0.4 bar low
    >>> r = peg_polytropic(e, psi, p)
    >>> round(float(r["offset"][0]), 2), round(r["exponent"], 6)
    (40000.0, 1.32)
    """
    psi = check_finite_array(crank_angle, "crank_angle", ndim=1, min_length=3,
                             error=AnalysisError)
    p = _rows(pressure, psi.size)
    sel = _window(psi, window_deg)
    v, _ = _volume_and_slope(engine, psi[sel], cylinder)
    fit = _fit_compression(v, p[:, sel].mean(axis=0), n=exponent)
    n = fit["n"]
    a = np.column_stack([v ** -n, -np.ones_like(v)])
    col = np.abs(a).max(axis=0)
    coef, *_ = np.linalg.lstsq(a / col, p[:, sel].T, rcond=None)
    return {"offset": coef[1] / col[1], "exponent": float(n), "exponent_se": fit["n_se"],
            "rms": fit["rms"], "window_deg": tuple(float(x) for x in window_deg)}


def _window(psi, window_deg):
    lo, hi = (float(x) for x in window_deg)
    if not -180.0 <= lo < hi <= 0.0:
        raise AnalysisError(f"window_deg={window_deg!r} must be an ascending pair within the "
                            "compression stroke, -180..0 deg from firing TDC")
    sel = (psi >= lo * DEG) & (psi <= hi * DEG)
    if sel.sum() < 8:
        raise AnalysisError(f"window_deg={window_deg!r} holds fewer than 8 grid points")
    return sel


# ------------------------------------------------------------------------------ TDC
@dataclass(frozen=True)
class TdcCheck:
    """Thermodynamic check of the TDC position.

    Attributes
    ----------
    offset : float
        δ, rad: the thermodynamic TDC lies δ after the assigned TDC (correct the crank angle
        by subtracting δ).
    standard_error : float
        Random error (1 σ) of δ from the fit, rad (NaN for the motored-peak method).
    method : str
        "compression polytropic fit".
    motored : bool
        The cycle looked motored (expansion within 15 % of the compression at 40–80° from
        TDC).
    exponent : float
        Polytropic exponent of the fit.
    note : str
        What the accuracy rests on.
    motored_peak_offset : float
        For a motored cycle, the second estimate: peak angle plus the loss angle, rad (NaN
        when fired).
    """

    offset: float
    standard_error: float
    method: str
    motored: bool
    exponent: float = float("nan")
    note: str = ""
    motored_peak_offset: float = float("nan")

    @property
    def offset_deg(self) -> float:
        """δ, deg."""
        return float(np.rad2deg(self.offset))

    @property
    def plausible(self) -> bool:
        """The fit describes a polytropic compression (1.15 ≤ n ≤ 1.5) and pins δ to better
        than 1°; otherwise the check is inconclusive (a compression that is not polytropic,
        a window holding combustion, too few or too noisy cycles)."""
        return bool(1.15 <= self.exponent <= 1.5 and np.isfinite(self.standard_error)
                    and self.standard_error < DEG)

    def to_dict(self) -> dict:
        return {"offset_deg": self.offset_deg,
                "standard_error_deg": float(np.rad2deg(self.standard_error)),
                "method": self.method, "motored": bool(self.motored),
                "exponent": float(self.exponent), "note": self.note,
                "plausible": self.plausible,
                "motored_peak_offset_deg": float(np.rad2deg(self.motored_peak_offset))}


def thermodynamic_tdc(engine, crank_angle, pressure, *, cylinder=1, window_deg=(-90.0, -25.0),
                      loss_angle_deg=0.5, search_deg=None):
    """Estimate the TDC error of a (cycle-averaged) pressure trace from its thermodynamics.

    Parameters
    ----------
    engine : predict.engine.Engine
    crank_angle : array_like
        Grid over one cycle, rad from the assigned firing TDC.
    pressure : array_like
        One cycle (the mean of many cycles), Pa; the absolute level need not be right (an
        offset is fitted).
    cylinder : int
    window_deg : (float, float)
        Compression window of the fit, deg (before combustion starts).
    loss_angle_deg : float
        Thermodynamic loss angle of the motored-peak estimate (by how much the peak leads
        TDC), deg.
    search_deg : (float, float), optional
        Range of δ to scan first, deg (default ±3°; wider when the zero is only a guess).

    Returns
    -------
    TdcCheck

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
    ...            reciprocating_mass=1.0, bore=0.1, compression_ratio=11.0)
    >>> psi = np.linspace(-2 * np.pi, 2 * np.pi, 7200, endpoint=False)
    >>> v = chamber_volume(e, psi - np.deg2rad(0.8))       # the real TDC is 0.8 deg later
    >>> p = 1e5 * (v.max() / v) ** 1.33 * (1 + 2 * np.exp(-((psi - 0.2) / 0.15) ** 2))
    >>> chk = thermodynamic_tdc(e, psi, p)
    >>> chk.method, round(chk.offset_deg, 4)
    ('compression polytropic fit', 0.8)
    """
    cycle = engine.cycle
    psi, _ = _grid(crank_angle, cycle)
    p = _rows(pressure, psi.size).mean(axis=0)
    sel = _window(psi, window_deg)
    # motored or fired: a fired cycle's expansion stands well above its compression at the same
    # distance from TDC (informational: the compression fit serves both)
    h = psi[1] - psi[0]
    side = np.arange(int(round(40 * DEG / h)), int(round(80 * DEG / h)) + 1)
    mid = int(np.argmin(np.abs(psi)))
    ratio = float(p[mid + side].mean() / p[mid - side].mean())
    motored = bool(ratio < 1.15)
    peak_offset = np.nan
    if motored:
        near = np.abs(psi) <= 60 * DEG
        loss = check_range(loss_angle_deg, "loss_angle_deg", 0.0, 5.0, error=AnalysisError)
        peak_offset = float(cycle_peaks(psi[near], p[near])["angle"][0] + loss * DEG)
    lo, hi = (-3.0, 3.0) if search_deg is None else (float(x) for x in search_deg)

    def vol(d):
        return _volume_and_slope(engine, psi[sel] - d, cylinder)[0]

    # coarse scan of δ at 0.5° (the fit is not convex far from the answer), then Gauss–Newton
    # within ±1° of the best point, moved on while it ends on that bound
    scan = np.arange(lo, hi + 0.25, 0.5) * DEG
    rms = [_fit_compression(vol(d), p[sel])["rms"] for d in scan]
    d0 = float(scan[int(np.argmin(rms))])
    for _ in range(4):
        fit = _fit_compression(lambda d: vol(d0 + d), p[sel], delta_bound=DEG)
        d0 += fit["delta"]
        if abs(fit["delta"]) < 0.999 * DEG:
            break
    note = ("random error from the fit residual; a polytropic compression has no heat "
            "transfer, so on real data add a bias of the order of the loss angle (a few tenths "
            "of a degree)")
    if motored:
        note += (f"; motored (expansion/compression {ratio:.2f}): the peak plus a "
                 f"{loss_angle_deg:g} deg loss angle gives {np.rad2deg(peak_offset):+.2f} deg")
    return TdcCheck(offset=d0, standard_error=fit["delta_se"],
                    method="compression polytropic fit", motored=motored, exponent=fit["n"],
                    note=note, motored_peak_offset=peak_offset)


# ------------------------------------------------------------------------------ heat release
@dataclass(frozen=True)
class HeatRelease:
    """Single-zone apparent heat release of one (mean) cycle.

    Attributes
    ----------
    crank_angle : ndarray
        rad from firing TDC (the analysis window).
    rate : ndarray
        dQ/dψ, J/rad.
    cumulative : ndarray
        Q, J, from the start of the window.
    total : float
        Released heat (maximum after the peak minus minimum before it), J.
    gamma : float
        Ratio of specific heats used.
    mfb_deg : dict
        Crank angle (deg) of 10, 50 and 90 % mass fraction burnt.
    """

    crank_angle: np.ndarray
    rate: np.ndarray
    cumulative: np.ndarray
    total: float
    gamma: float
    mfb_deg: dict = field(default_factory=dict)

    @property
    def mfb50_deg(self) -> float:
        """Crank angle of 50 % mass fraction burnt, deg from firing TDC."""
        return self.mfb_deg[50]


def heat_release(engine, crank_angle, pressure, *, cylinder=1, gamma=1.32,
                 window_deg=(-90.0, 110.0)):
    """Apparent heat release of a single-zone model with constant γ.

    Parameters
    ----------
    engine : predict.engine.Engine
    crank_angle : array_like
        Grid over one cycle, rad from firing TDC.
    pressure : array_like
        Absolute pressure of one cycle (or rows averaged), Pa.
    cylinder : int
    gamma : float
        Ratio of specific heats (1 < γ < 1.67); 1.32 is a usual value for the whole cycle.
    window_deg : (float, float)
        Closed part of the cycle analysed, deg (after intake closing, before exhaust opening).

    Returns
    -------
    HeatRelease

    References
    ----------
    Heywood 1988, §10.2.2 eq. (10.4).

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
    ...            reciprocating_mass=1.0, bore=0.1, compression_ratio=11.0)
    >>> psi = np.linspace(-2 * np.pi, 2 * np.pi, 7200, endpoint=False)
    >>> v = chamber_volume(e, psi)
    >>> p = 1e5 * (v.max() / v) ** 1.32                     # no combustion: Q = 0
    >>> hr = heat_release(e, psi, p)
    >>> bool(abs(hr.total) < 1e-7 * 1e5 * v.max())      # J
    True
    """
    psi, h = _grid(crank_angle, engine.cycle)
    p = _rows(pressure, psi.size).mean(axis=0)
    g = check_range(gamma, "gamma", 1.0, 1.67, inclusive=(False, True), error=AnalysisError)
    lo, hi = (float(x) for x in window_deg)
    if not (-180.0 <= lo < 0.0 < hi <= 180.0):
        raise AnalysisError(f"window_deg={window_deg!r} must span TDC within -180..180 deg")
    v, dv = _volume_and_slope(engine, psi, cylinder)
    # 4th-order central difference on the periodic cycle (error O(h⁴ p⁽⁵⁾))
    dp = (8 * (np.roll(p, -1) - np.roll(p, 1)) - (np.roll(p, -2) - np.roll(p, 2))) / (12 * h)
    rate = g / (g - 1.0) * p * dv + v * dp / (g - 1.0)
    sel = (psi >= lo * DEG) & (psi <= hi * DEG)
    a, r = psi[sel], rate[sel]
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (r[1:] + r[:-1]) * h)])
    k = int(np.argmax(cum))
    j = int(np.argmin(cum[: k + 1]))
    total = float(cum[k] - cum[j])
    mfb = {}
    if total > 0:
        frac = (cum[j:k + 1] - cum[j]) / total
        mono = np.maximum.accumulate(frac)
        for level in (10, 50, 90):
            mfb[level] = float(np.rad2deg(np.interp(level / 100.0, mono + np.arange(
                mono.size) * 1e-15, a[j:k + 1])))
    else:
        mfb = {10: np.nan, 50: np.nan, 90: np.nan}
    return HeatRelease(crank_angle=a, rate=r, cumulative=cum, total=total, gamma=g, mfb_deg=mfb)
