"""The sweep-rate effect: an SDOF mode passed through at a finite rate.

The swept response envelope (exponential integrator on the resonant pole), the peak loss,
shift and apparent damping it causes, the inversion of the apparent damping, and the
swept-SDOF fit of an order track.
"""

from __future__ import annotations

import logging

import numpy as np

from crankbench.predict._validate import check_option, check_positive, check_range
from crankbench.predict.errors import AnalysisError

from .sdof import RESPONSES, _background, _modal_fit, _peak_and_half_power, half_power_damping

__all__ = ["sweep_peak_loss", "sweep_expectation", "correct_sweep_delay"]

def _swept_envelope(zeta, s, p, *, lead=None, lag=None):
    """Response envelope of an SDOF through a linear sweep, in normalised time τ = ω_n t.

    ``z'' + 2ζz' + z = exp(iφ)`` with ``φ' = ν(τ) = ν₀ + sτ``. By partial fractions
    ``z = (q₁ − q₂)/(λ₁ − λ₂)`` with ``q_j' = λ_j q_j + exp(iφ)`` and poles
    ``λ₁,₂ = −ζ ± i√(1 − ζ²)``. Writing ``q_j = u_j exp(iφ)``: ``u_j' = (λ_j − iν)u_j + 1``.
    The resonant pole's ``u₁`` is stepped exactly for ν frozen at each step's midpoint
    (exponential integrator, linear recurrence evaluated by chunked cumulative products); the
    non-resonant ``u₂`` follows quasi-statically (relative error O(sζ)).
    Returns (ν, complex response envelope).
    """
    direction = 1.0 if s > 0 else -1.0
    a = abs(s)
    lead = max(8.0 * zeta, 0.02) if lead is None else lead
    # the swept peak trails resonance by ~ a/ζ (slow sweeps) or ~ √a (fast sweeps)
    lag = max(8.0 * zeta, 0.02) + 10.0 * np.sqrt(a) if lag is None else lag
    nu0 = max(1.0 - direction * lead, 0.05)
    nu1 = max(1.0 + direction * lag, 0.05)
    tau_end = abs(nu1 - nu0) / a
    wd = np.sqrt(1.0 - zeta**2)
    lam1, lam2 = complex(-zeta, wd), complex(-zeta, -wd)
    # frozen-ν exponential steps: exact rotation and decay, error O(s h²) per step; the ν
    # resolution s·h ≤ ζ/50 resolves the peak (checked against h → h/100: < 2e-6 relative)
    h = min(np.sqrt(2e-3 / a), 0.02 * max(zeta, np.sqrt(a)) / a)
    n = int(np.clip(np.ceil(tau_end / h), 200, 400_000))
    h = tau_end / n
    tau = np.arange(n + 1) * h
    nu = nu0 + s * tau
    mu = lam1 - 1j * (nu0 + s * (tau[:-1] + 0.5 * h))
    step_a = np.exp(mu * h)
    step_b = np.expm1(mu * h) / mu
    mu0 = lam1 - 1j * nu0
    u1 = np.empty(n + 1, dtype=complex)
    u1[0] = -1.0 / mu0 - 1j * s / mu0**3  # quasi-static start with its first sweep correction
    chunk = 256
    for k0 in range(0, n, chunk):  # u_{k+1} = A_k u_k + B_k, |cumprod(A)| stays O(1) per chunk
        A = step_a[k0:k0 + chunk]
        B = step_b[k0:k0 + chunk]
        P = np.cumprod(A)
        u1[k0 + 1:k0 + 1 + A.size] = P * (u1[k0] + np.cumsum(B / P))
    u2 = 1.0 / (1j * nu - lam2)
    w = (u1 - u2) / (lam1 - lam2)
    v = (lam1 * u1 - lam2 * u2) / (lam1 - lam2)
    if p == 0:
        env = w
    elif p == 1:
        env = v
    else:  # z'' = e^{iφ} − 2ζz' − z
        env = 1.0 - 2.0 * zeta * v - w
    return nu, env


def sweep_peak_loss(*, natural_frequency, damping_ratio, sweep_rate, response="displacement"):
    """Peak loss, peak shift and apparent damping of an SDOF mode swept at a constant rate.

    The SDOF response to ``exp(iφ(t))`` is integrated through the resonance from a
    quasi-static start with an exponential integrator on the resonant pole (exact for a
    frozen frequency within each step); the envelope is read
    against the instantaneous excitation frequency, as an order track reads amplitude
    against rpm. Cost: a few thousand vectorised steps, about 1 ms.

    Parameters
    ----------
    natural_frequency : float
        f_n, Hz.
    damping_ratio : float
        ζ of the mode (true, not apparent).
    sweep_rate : float
        Rate of change of the excitation frequency α, Hz/s; negative for a run-down. For order
        ``k`` of a run-up at ``R`` rpm/s, ``α = k R / 60``.
    response : {'displacement', 'velocity', 'acceleration'}

    Returns
    -------
    dict
        ``loss`` (fraction of the steady-state peak lost, ≥ 0 for slow sweeps), ``shift``
        (f_peak,swept − f_peak,steady in Hz, same sign as the sweep), ``apparent_damping``
        (half-power damping ratio read off the swept envelope), ``eta`` (α/(ζ f_n)²).

    Notes
    -----
    The loss depends only on ζ and η; below η = 0.02 it is under 1e-4 and the integration is
    skipped (returns zeros). Integration error < 1e-5 relative (checked against halved steps
    and an adaptive Runge–Kutta solution in the tests).

    References
    ----------
    Lewis, F. M., "Vibration during acceleration through a critical speed", Trans. ASME 54
    (1932) 253–261; Reed & Kabe, "Peak response of single-degree-of-freedom systems to
    swept-frequency excitation", The Mathematica Journal 21 (2019).

    Examples
    --------
    >>> r = sweep_peak_loss(natural_frequency=10.0, damping_ratio=0.02, sweep_rate=0.2)
    >>> print(f"eta={r['eta']:.2f} loss={r['loss']:.3f}")
    eta=5.00 loss=0.082
    """
    check_option(response, "response", RESPONSES)
    fn = check_positive(natural_frequency, "natural_frequency", error=AnalysisError)
    zeta = check_range(damping_ratio, "damping_ratio", 0.0, 0.5, inclusive=(False, True),
                       error=AnalysisError)
    alpha = check_range(sweep_rate, "sweep_rate", error=AnalysisError)
    eta = abs(alpha) / (zeta * fn) ** 2
    if eta < 0.02:
        return {"loss": 0.0, "shift": 0.0, "apparent_damping": zeta, "fit_damping": zeta,
                "fit_shift": 0.0, "eta": eta}
    return _sweep_effect(zeta, alpha / (2.0 * np.pi * fn**2), RESPONSES[response], fn,
                         complex_data=True) | {"eta": float(eta)}


def _sweep_effect(zeta, s, p, fn, *, complex_data):
    """Loss, peak shift, half-power and modal-fit damping/shift read off a swept envelope."""
    nu, env = _swept_envelope(zeta, s, p)
    order = np.argsort(nu)
    nu, env = nu[order], env[order]
    mag = np.abs(env)
    nu_pk, env_pk, nu1, nu2 = _peak_and_half_power(nu, mag)
    # steady-state peak of the same response, on a fine grid around ν = 1
    grid = np.linspace(max(1.0 - 6 * zeta, 0.01), 1.0 + 6 * zeta, 4001)
    steady = np.abs((1j * grid) ** p / (1.0 - grid**2 + 2j * zeta * grid))
    g_pk, s_pk, _, _ = _peak_and_half_power(grid, steady)
    apparent = fit_zeta = fit_shift = np.nan
    if np.isfinite(nu1) and np.isfinite(nu2) and nu2 > nu1 > 0:
        apparent, nu_hp = half_power_damping(nu1, nu2, response=list(RESPONSES)[p])
        half = 0.5 * (nu2 - nu1)
        win = (nu >= nu_pk - 3 * half) & (nu <= nu_pk + 3 * half)
        sel = np.flatnonzero(win)
        if sel.size > 400:  # the fit needs shape, not every integration step
            sel = sel[np.linspace(0, sel.size - 1, 400).astype(int)]
        if sel.size >= 7:
            data = env[sel] if complex_data else mag[sel]
            fit = _modal_fit(nu[sel], data, nu_hp, apparent, p, complex_data)
            if fit is not None:
                fit_zeta, fit_shift = fit[1], (fit[0] - 1.0) * fn
    return {"loss": float(1.0 - env_pk / s_pk), "shift": float((nu_pk - g_pk) * fn),
            "apparent_damping": float(apparent), "fit_damping": float(fit_zeta),
            "fit_shift": float(fit_shift)}


def _ascending(x, y):
    order = np.argsort(x)
    return x[order], y[order]


def _deinflate(zeta_app, fn, alpha, p, key, complex_data):
    """True ζ whose swept estimate ``key`` ('fit_damping' or 'apparent_damping') equals the
    apparent ``zeta_app``; returns (ζ, sweep effect dict) or None when no ζ explains it."""
    from scipy.optimize import brentq

    s = alpha / (2.0 * np.pi * fn**2)
    cache = {}

    def effect(z):
        if z not in cache:
            cache[z] = _sweep_effect(z, s, p, fn, complex_data=complex_data)
        return cache[z]

    def gap(z):
        value = effect(z)[key]
        return (value if np.isfinite(value) else np.inf) - zeta_app

    # the half-power damping is inflated by a sweep; the modal-fit damping barely moves and
    # may fall slightly below the true value: bracket on both sides
    lo, hi = max(0.2 * zeta_app, 1e-3), min(3.0 * zeta_app, 0.5)
    if hi <= lo:
        return None
    g_lo, g_hi = gap(lo), gap(hi)
    if not (np.isfinite(g_lo) and g_lo < 0 < g_hi):
        return None
    z = float(brentq(gap, lo, hi, xtol=1e-5 * zeta_app, rtol=1e-6))
    return z, effect(z)



def _swept_fit(x, c, order, rate, fn0, zeta0, p, complex_data, terms="cl",
               peak_range=None):
    """SDOF fit that models the sweep: c ≈ R E(x; fn, ζ, sweep) + B·b(x).

    ``E`` is the swept envelope of :func:`_swept_envelope` read at the data's instantaneous
    speeds, ``b(x)`` the out-of-band residual terms of :func:`_background` (treated as
    quasi-static: they vary slowly); ``x`` and ``fn`` in rpm of this order, ``rate`` in rpm/s.
    Variable projection as in :func:`_modal_fit`. Returns (fn, ζ, r2, steady-state peak
    amplitude — the largest over ``peak_range``, default the window) or None.
    """
    from scipy.optimize import least_squares

    xm = float(np.mean(x))
    bg = _background(x, xm, terms)
    up = rate > 0

    def envelope(theta):
        fn = np.exp(theta[0])
        zeta = np.exp(theta[1])
        fn_hz = fn * order / 60.0
        s = (order * rate / 60.0) / (2.0 * np.pi * fn_hz**2)
        below = max(1.0 - x.min() / fn, 0.0) + 2.0 * zeta
        above = max(x.max() / fn - 1.0, 0.0) + 2.0 * zeta
        lead, lag = (below, above) if up else (above, below)
        lead = max(lead, 8.0 * zeta, 0.02)
        lag = max(lag, 8.0 * zeta, 0.02)
        nu, env = _swept_envelope(zeta, s, p, lead=lead, lag=lag)
        k = np.argsort(nu)
        nu, env = nu[k], env[k]
        xi = x / fn
        e = np.interp(xi, nu, env.real) + 1j * np.interp(xi, nu, env.imag)
        return e if complex_data else np.abs(e)

    def solve(theta):
        a = np.column_stack([envelope(theta), bg])
        coef, *_ = np.linalg.lstsq(a, c, rcond=None)
        return coef, c - a @ coef

    def fun(theta):
        _, res = solve(theta)
        return np.concatenate([res.real, res.imag]) if complex_data else res

    theta0 = np.array([np.log(fn0), np.log(min(max(zeta0, 2e-3), 0.4))])
    lower = [np.log(x.min()), np.log(1e-3)]
    upper = [np.log(x.max()), np.log(0.45)]
    theta0 = np.clip(theta0, np.add(lower, 1e-9), np.subtract(upper, 1e-9))
    try:
        # the simulation's step count changes with ζ: difference over a resolvable step
        sol = least_squares(fun, theta0, method="trf", bounds=(lower, upper), diff_step=1e-4,
                            xtol=1e-9, ftol=1e-10, max_nfev=60)
    except (ValueError, np.linalg.LinAlgError, FloatingPointError):
        return None
    if not np.all(np.isfinite(sol.x)):
        return None
    coef, res = solve(sol.x)
    total = np.sum(np.abs(c - np.mean(c)) ** 2)
    r2 = 1.0 - np.sum(np.abs(res) ** 2) / total if total > 0 else 0.0
    fn, zeta = float(np.exp(sol.x[0])), float(np.exp(sol.x[1]))
    # the steady-state order amplitude the fitted model predicts (same R and residual terms,
    # the steady SDOF response in place of the swept envelope) at its resonance: the local
    # maximum of the steady curve within one half-power width of the SDOF's peak, or - a
    # shoulder on a rising background has none - its value at that peak. (The largest value
    # over the whole window would read the background's slope, not the resonance: +15 % on
    # the 6L32 order-2.5 shoulder.)
    x_lo, x_hi = (x.min(), x.max()) if peak_range is None else peak_range
    xg = np.linspace(max(x.min(), x_lo), min(x.max(), x_hi), 4001)
    nu = xg / fn
    h = (1j * nu) ** p / (1.0 - nu**2 + 2j * zeta * nu)
    steady = np.abs(coef[0] * (h if complex_data else np.abs(h))
                    + _background(xg, xm, terms) @ coef[1:])
    x_res = fn * np.sqrt(max(1.0 - 2.0 * zeta**2, 1e-12)) ** (1 - p)
    near = np.abs(xg - x_res) <= zeta * fn
    k = np.flatnonzero(near)
    if k.size >= 3:
        inner = k[1:-1][(steady[k[1:-1]] >= steady[k[:-2]]) & (steady[k[1:-1]] >= steady[k[2:]])]
        if inner.size:
            peak = float(steady[inner[np.argmin(np.abs(xg[inner] - x_res))]])
            return fn, zeta, float(r2), peak
    return fn, zeta, float(r2), float(np.interp(x_res, xg, steady))




def _crossing_rate(time, speed_rpm, target_rpm, half_window_rpm):
    """Local sweep rate (rpm/s) where the run first crosses ``target_rpm``: slope of a straight
    line through the samples within ``half_window_rpm`` of that crossing; NaN if it never
    crosses."""
    d = speed_rpm - target_rpm
    cross = np.flatnonzero(np.signbit(d[:-1]) != np.signbit(d[1:]))
    if cross.size == 0:
        return float("nan")
    i = int(cross[0])
    lo = hi = i
    n = speed_rpm.size
    while lo > 0 and abs(speed_rpm[lo - 1] - target_rpm) <= half_window_rpm:
        lo -= 1
    while hi < n - 1 and abs(speed_rpm[hi + 1] - target_rpm) <= half_window_rpm:
        hi += 1
    lo, hi = max(0, min(lo, i - 2)), min(n - 1, max(hi, i + 3))
    t, r = time[lo:hi + 1], speed_rpm[lo:hi + 1]
    if np.ptp(t) <= 0:
        return float("nan")
    return float(np.polyfit(t - t.mean(), r, 1)[0])


def sweep_expectation(criticals, *, time, speed_rpm, response="displacement", flanks=1.0):
    """Where, how high and whether at all each predicted resonance shows in a swept record.

    A mode crossed at a finite rate peaks later, lower and wider than its steady-state
    resonance curve (:func:`sweep_peak_loss`). Given the record's speed trace, each predicted
    critical gets the local sweep rate where the run crosses it, the delay and loss of its
    peak at that rate (from its predicted natural frequency and damping), and whether the run
    covers it: the flank the sweep comes from (``flanks`` half-power half-widths ``ζ n``
    before the critical) and the delayed peak lie inside the speed range. A resonance the
    run enters on its flank cannot be identified (the response has not built up, the fit has
    one side), so it is not expected in the measurement.

    Parameters
    ----------
    criticals : pandas.DataFrame
        Predicted critical speeds with ``order``, ``speed_rpm``, ``frequency_hz`` and
        optionally ``damping_ratio`` (NaN or absent: no sweep effect, coverage of the speed
        itself) and ``amplitude``.
    time : array_like
        Times of the speed samples, s.
    speed_rpm : array_like
        Speed of the run at those times, rpm (for example the ``rpm`` coordinate of an order
        track).
    response : {'displacement', 'velocity', 'acceleration'}
        Measured quantity (sets which peak the delay refers to).
    flanks : float
        Half-power half-widths required on the side the sweep comes from.

    Returns
    -------
    pandas.DataFrame
        A copy with ``sweep_rate_rpm_per_s`` (local rate at the crossing, NaN if never
        crossed), ``sweep_eta`` (α/(ζ f_n)²), ``sweep_shift_rpm`` (delay of the swept peak,
        same sign as the sweep), ``sweep_fit_shift_rpm`` (the same read by an SDOF modal fit
        of the swept curve), ``sweep_peak_loss`` (fraction of the steady peak lost),
        ``speed_rpm_swept``, ``amplitude_swept`` and ``covered``.

    Examples
    --------
    >>> import pandas as pd
    >>> crit = pd.DataFrame({"order": [0.5, 6.0], "speed_rpm": [1062.0, 2574.0],
    ...                      "frequency_hz": [8.85, 257.4], "damping_ratio": [0.069, 0.068],
    ...                      "amplitude": [6.7e-4, 7.1e-4]})
    >>> t = np.linspace(0.0, 20.0, 401)
    >>> out = sweep_expectation(crit, time=t, speed_rpm=1000.0 + 250.0 * t)
    >>> out[["sweep_rate_rpm_per_s", "covered"]].round(1).values.tolist()
    [[250.0, False], [250.0, True]]
    >>> round(float(out["sweep_shift_rpm"].iloc[1]), 1)
    4.5
    """
    import pandas as pd

    check_option(response, "response", RESPONSES)
    t = np.asarray(time, float)
    rpm = np.asarray(speed_rpm, float)
    if t.shape != rpm.shape or t.ndim != 1 or t.size < 4:
        raise AnalysisError(f"time and speed_rpm must be 1-D of equal length >= 4, got shapes "
                            f"{t.shape} and {rpm.shape}")
    ok = np.isfinite(t) & np.isfinite(rpm)
    t, rpm = t[ok], rpm[ok]
    if not isinstance(criticals, pd.DataFrame):
        raise AnalysisError(f"criticals must be a pandas DataFrame, got "
                            f"{type(criticals).__name__}")
    for col in ("order", "speed_rpm"):
        if col not in criticals:
            raise AnalysisError(f"criticals need a column {col!r}; columns: "
                                f"{list(criticals.columns)}")
    out = criticals.copy()
    lo, hi = float(rpm.min()), float(rpm.max())
    cols = {k: [] for k in ("sweep_rate_rpm_per_s", "sweep_eta", "sweep_shift_rpm",
                            "sweep_fit_shift_rpm", "sweep_peak_loss", "covered")}
    for _, c in out.iterrows():
        q, n = float(c["order"]), float(c["speed_rpm"])
        f = float(c["frequency_hz"]) if "frequency_hz" in c and np.isfinite(
            c["frequency_hz"]) else n * q / 60.0
        zeta = float(c["damping_ratio"]) if "damping_ratio" in c else float("nan")
        z_ok = np.isfinite(zeta) and 0.0 < zeta <= 0.5
        rate = _crossing_rate(t, rpm, n, max((zeta if z_ok else 0.02) * n, 1e-9))
        shift = fit_shift = loss = 0.0
        eta = float("nan")
        if z_ok and np.isfinite(rate) and rate != 0.0:
            eff = sweep_peak_loss(natural_frequency=f, damping_ratio=zeta,
                                  sweep_rate=q * rate / 60.0, response=response)
            eta, loss = eff["eta"], eff["loss"]
            shift = eff["shift"] * 60.0 / q
            fit_shift = eff["fit_shift"] * 60.0 / q if np.isfinite(eff["fit_shift"]) else shift
        half = (zeta if z_ok else 0.0) * n           # half-power half-width, rpm
        if not np.isfinite(rate):
            covered = False
        elif rate >= 0:    # approached from below: lower flank, then the (delayed) peak
            covered = bool(lo <= n - flanks * half and n + shift <= hi)
        else:
            covered = bool(n + flanks * half <= hi and lo <= n + shift)
        for key, value in (("sweep_rate_rpm_per_s", rate), ("sweep_eta", eta),
                           ("sweep_shift_rpm", shift), ("sweep_fit_shift_rpm", fit_shift),
                           ("sweep_peak_loss", loss), ("covered", covered)):
            cols[key].append(value)
    for key, values in cols.items():
        out[key] = np.asarray(values, bool if key == "covered" else float)
    out["speed_rpm_swept"] = out["speed_rpm"] + out["sweep_shift_rpm"]
    if "amplitude" in out:
        out["amplitude_swept"] = out["amplitude"] * (1.0 - out["sweep_peak_loss"])
    return out


def correct_sweep_delay(measured, expected, *, gate=0.15):
    """Take the predicted sweep delay out of measured resonances the finder left uncorrected.

    :func:`analysis.find_resonances` corrects a peak for the sweep when its swept modal fit
    converges; otherwise (a one-sided window, a fit that left its window, a half-power
    estimate only) the reported critical speed still carries the delay — at 250 rpm/s a
    first driveline mode appears tens of per cent late. This step removes, from each such
    measured resonance, the delay the *model* expects at the measured local sweep rate for
    the nearest predicted critical of the same order (within ``gate`` of its swept position;
    only criticals the run covers, when ``expected`` has the ``covered`` column), so that
    measurement and prediction are compared like with like. Corrected rows get
    ``sweep_corrected`` True and ``" + model sweep delay"`` appended to ``method``.

    Parameters
    ----------
    measured : pandas.DataFrame
        Resonances (``ResonanceTable.to_frame()``): ``order``, ``speed_rpm``,
        ``sweep_corrected``, ``method``, optionally ``amplitude``, ``resonant_amplitude``.
    expected : pandas.DataFrame
        From :func:`sweep_expectation`.
    gate : float
        Largest relative distance between the measured speed and the predicted swept one.

    Returns
    -------
    pandas.DataFrame
        A corrected copy of ``measured`` (same columns).

    Examples
    --------
    >>> import pandas as pd
    >>> meas = pd.DataFrame({"order": [0.5], "speed_rpm": [1120.0], "frequency_hz": [9.33],
    ...                      "amplitude": [1e-3], "amplitude_corrected": [1e-3],
    ...                      "resonant_amplitude": [5e-4], "sweep_corrected": [False],
    ...                      "method": ["modal fit"]})
    >>> exp = pd.DataFrame({"order": [0.5], "speed_rpm": [1062.0],
    ...                     "sweep_shift_rpm": [62.0], "sweep_fit_shift_rpm": [60.0],
    ...                     "sweep_peak_loss": [0.2], "speed_rpm_swept": [1124.0]})
    >>> out = correct_sweep_delay(meas, exp)
    >>> float(out.speed_rpm[0]), round(float(out.amplitude_corrected[0]), 6), out.method[0]
    (1060.0, 0.001125, 'modal fit + model sweep delay')
    """
    import pandas as pd

    if not isinstance(measured, pd.DataFrame) or not isinstance(expected, pd.DataFrame):
        raise AnalysisError("measured and expected must be pandas DataFrames")
    out = measured.copy()
    if out.empty or expected.empty or "sweep_corrected" not in out:
        return out
    if "method" in out:
        out["method"] = out["method"].astype(object)
    for i, r in out.iterrows():
        if bool(r["sweep_corrected"]):
            continue
        same = expected[np.isclose(expected["order"].to_numpy(float), float(r["order"]))]
        if "covered" in same:
            same = same[same["covered"].to_numpy(bool)]
        if same.empty:
            continue
        swept = same["speed_rpm_swept"].to_numpy(float)
        dist = np.abs(float(r["speed_rpm"]) - swept) / same["speed_rpm"].to_numpy(float)
        k = int(np.argmin(dist))
        if not dist[k] <= gate:
            continue
        c = same.iloc[k]
        fit = "fit" in str(r.get("method", ""))
        shift = float(c["sweep_fit_shift_rpm"] if fit else c["sweep_shift_rpm"])
        loss = float(c["sweep_peak_loss"])
        if not np.isfinite(shift) or (shift == 0.0 and loss == 0.0):
            continue
        out.at[i, "speed_rpm"] = float(r["speed_rpm"]) - shift
        if "frequency_hz" in out:
            out.at[i, "frequency_hz"] = (float(r["speed_rpm"]) - shift) * float(r["order"]) / 60
        if "amplitude_corrected" in out and "resonant_amplitude" in out and 0 <= loss < 1:
            res = float(r["resonant_amplitude"])
            if np.isfinite(res):
                out.at[i, "amplitude_corrected"] = float(r["amplitude"]) + res * (
                    1.0 / (1.0 - loss) - 1.0)
        if "sweep_shift_rpm" in out:
            out.at[i, "sweep_shift_rpm"] = shift
        if "sweep_peak_loss" in out:
            out.at[i, "sweep_peak_loss"] = loss
        out.at[i, "sweep_corrected"] = True
        if "method" in out:
            out.at[i, "method"] = f"{r['method']} + model sweep delay"
    return out
