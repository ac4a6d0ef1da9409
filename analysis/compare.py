"""Measurement against prediction: critical speeds, natural frequencies and balance residuals.

:func:`match_criticals` assigns measured resonances to predicted (mode, order) critical
speeds. It is an *assignment* (Hungarian algorithm, ``scipy.optimize.linear_sum_assignment``)
on the relative speed deviation, restricted to equal orders and gated, so two measured peaks
can never claim the same critical and a peak is never forced onto a critical far away. From
the matches it reports deviations in rpm and %, the amplitude ratio measured/predicted, what
stayed unmatched on either side, and the natural frequency of each mode collected across every
order that excited it (the Campbell-diagram crossings).

:func:`compare_balance` sets measured order-1/2 vibration at the mounts against the predicted
response to the balance residuals (computed by the caller through the mount model).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from crankbench.predict._validate import check_positive, check_range
from crankbench.predict.errors import AnalysisError

__all__ = ["CriticalComparison", "match_criticals", "not_judged_reason", "BalanceComparison",
           "compare_balance"]

log = logging.getLogger("crankbench")

_FORBIDDEN = 1e6


def _measured_frame(measured):
    import pandas as pd

    if hasattr(measured, "to_frame") and not isinstance(measured, pd.DataFrame):
        frame = measured.to_frame()
    elif isinstance(measured, pd.DataFrame):
        frame = measured.copy()
    else:
        raise AnalysisError(f"measured must be a ResonanceTable or DataFrame, got "
                            f"{type(measured).__name__}")
    for col in ("order", "speed_rpm"):
        if col not in frame:
            raise AnalysisError(f"measured resonances need a column {col!r}; columns: "
                                f"{list(frame.columns)}")
    # an empty table (no resonance found) has object columns: make the numbers numbers
    for col in ("order", "speed_rpm", "frequency_hz", "amplitude", "amplitude_corrected",
                "confidence", "damping_ratio"):
        if col in frame:
            frame[col] = pd.to_numeric(frame[col], errors="coerce").astype(float)
    if "amplitude_corrected" in frame:
        amp = frame["amplitude_corrected"].where(np.isfinite(frame["amplitude_corrected"]),
                                                 frame.get("amplitude"))
        frame["amplitude_used"] = amp
    elif "amplitude" in frame:
        frame["amplitude_used"] = frame["amplitude"]
    else:
        frame["amplitude_used"] = np.nan
    if "confidence" not in frame:
        frame["confidence"] = 1.0
    if "damping_ratio" not in frame:
        frame["damping_ratio"] = np.nan
    return frame.reset_index(drop=True)


def _combine_sweeps(frame, gate):
    """Merge resonances of one order found in several sweeps (run-up and run-down) when they
    lie within ``gate`` of each other: confidence-weighted means."""
    import pandas as pd

    if frame.empty:
        return frame
    rows = []
    for order, grp in frame.groupby("order", sort=True):
        grp = grp.sort_values("speed_rpm")
        cluster = [grp.iloc[0]]
        for _, r in list(grp.iterrows())[1:]:
            if abs(r.speed_rpm - cluster[-1].speed_rpm) <= gate * cluster[-1].speed_rpm and \
                    r.get("sweep", 0) != cluster[-1].get("sweep", 0):
                cluster.append(r)
            else:
                rows.append(_merge(cluster))
                cluster = [r]
        rows.append(_merge(cluster))
    return pd.DataFrame(rows).reset_index(drop=True)


def _merge(cluster):
    import pandas as pd

    if len(cluster) == 1:
        out = cluster[0].copy()
        out["n_sweeps"] = 1
        return out
    df = pd.DataFrame(cluster)
    w = np.clip(df["confidence"].to_numpy(float), 1e-6, None)
    out = df.iloc[int(np.argmax(w))].copy()
    for col in ("speed_rpm", "frequency_hz", "amplitude_used", "damping_ratio"):
        if col in df:
            v = df[col].to_numpy(float)
            ok = np.isfinite(v)
            if ok.any():
                out[col] = float(np.sum(w[ok] * v[ok]) / np.sum(w[ok]))
    out["n_sweeps"] = len(cluster)
    return out


@dataclass(frozen=True)
class CriticalComparison:
    """Measured resonances matched to predicted critical speeds.

    Attributes
    ----------
    matched : pandas.DataFrame
        One row per match: ``mode``, ``order``, ``speed_rpm_predicted``,
        ``speed_rpm_measured``, ``deviation_rpm``, ``deviation_pct`` (measured − predicted,
        % of predicted), ``frequency_hz_predicted``, ``frequency_hz_measured``,
        ``amplitude_predicted``, ``amplitude_measured``, ``amplitude_ratio``
        (measured/predicted), ``damping_ratio``, ``confidence``, ``speed_ok``,
        ``amplitude_ok``.
    unmatched_measured : pandas.DataFrame
        Resonances no critical explains (within the gate).
    unmatched_predicted : pandas.DataFrame
        Criticals inside the measured speed range with no measured resonance; column
        ``significant`` marks those that should have been visible, ``status`` says 'not
        found' or why the record could not show them (see ``unresolved``).
    natural_frequencies : pandas.DataFrame
        Per mode: ``frequency_hz_measured`` (confidence-weighted over the matched orders),
        ``frequency_hz_predicted`` (the same weighting over the same orders; the mode's first
        critical when nothing matched), ``spread_hz`` (weighted standard deviation over
        orders), ``n_orders``, ``orders``, ``deviation_pct``.
    gate, tolerance, amplitude_tolerance : float
        Settings: assignment gate (relative speed), speed tolerance for agreement, amplitude
        ratio tolerance (ratio within [1/(1+t), 1+t]).
    flags : tuple of str
        Human-readable disagreements; empty when measurement and prediction agree.
    unresolved : tuple of str
        Significant criticals not found where the record could not be shown to contradict
        them: amplitudes not judged (the expected rise is unknown), or the expected rise
        (predicted amplitude less the measured level) below ``(1 + amplitude_tolerance)`` times the
        finder's detection limit there (column ``detection_limit`` of the predicted table,
        :func:`analysis.resonance.detect.detection_limits`). They make the verdict
        inconclusive, not failed. Without a ``detection_limit`` column every significant
        critical not found is a flag.
    """

    matched: object
    unmatched_measured: object
    unmatched_predicted: object
    natural_frequencies: object
    gate: float
    tolerance: float
    amplitude_tolerance: float
    flags: tuple = ()
    settings: dict = field(default_factory=dict)
    unresolved: tuple = ()

    @property
    def agrees(self) -> bool:
        """True when nothing was flagged."""
        return not self.flags

    def verdict(self, *, steady=False, basis=""):
        """The comparison as a three-state :class:`analysis.verdict.Verdict`.

        Fail when a significant critical disagrees (speed, amplitude, missing though the
        record could have shown it, unexplained peak); inconclusive when nothing was compared —
        a steady run (no critical speed is crossed at constant speed) or no significant
        predicted critical and no matched resonance in the measured range — or when a
        significant critical was not found where the record's noise hides it
        (``unresolved``); pass otherwise.

        Parameters
        ----------
        steady : bool
            The record is a steady-speed run.
        basis : str
            The data compared (record, channel, speed range).

        Examples
        --------
        >>> import pandas as pd
        >>> pred = pd.DataFrame({"mode": [1], "order": [6.0], "speed_rpm": [400.0]})
        >>> meas = pd.DataFrame({"order": [6.0], "speed_rpm": [402.0]})
        >>> print(match_criticals(meas, pred, speed_range_rpm=(300, 500)).verdict().status)
        pass
        >>> empty = pd.DataFrame({"order": [], "speed_rpm": []})
        >>> v = match_criticals(empty, pred, speed_range_rpm=(600, 700)).verdict()
        >>> print(v.status, "|", v.reason)
        inconclusive | no predicted critical speed in the measured range and no resonance matched: nothing was compared
        """
        from .verdict import Verdict

        name = "critical speeds against the model"
        unjudged = self.settings.get("amplitudes_not_judged")
        amplitude_rule = (f"amplitude ratio within [{1 / (1 + self.amplitude_tolerance):.2f}, "
                          f"{1 + self.amplitude_tolerance:.2f}]" if unjudged is None else
                          f"amplitudes not judged ({unjudged})")
        rule = (f"measured critical within ±{100 * self.tolerance:g} % of the predicted, "
                f"{amplitude_rule}, every significant critical found "
                f"(gate ±{100 * self.gate:g} %)")
        m = self.matched
        n_sig = int(m["significant"].sum()) if len(m) else 0
        up = self.unmatched_predicted
        n_sig += int(up["significant"].sum()) if len(up) else 0
        basis = basis or f"{len(m)} matched resonance(s), {n_sig} significant critical(s)"
        if steady:
            return Verdict.inconclusive(
                name, rule=rule, basis=basis,
                reason="steady-speed run: no critical speed is crossed, so none can be "
                       "compared (a steady-state order comparison is needed)")
        if self.flags:
            return Verdict.failed(name, rule=rule, basis=basis,
                                  reason="; ".join(self.flags[:3])
                                  + (f" (+{len(self.flags) - 3} more)" if len(self.flags) > 3
                                     else ""))
        if self.unresolved:
            return Verdict.inconclusive(
                name, rule=rule, basis=basis,
                reason=f"{len(m)} critical(s) matched; "
                       + "; ".join(self.unresolved[:2])
                       + (f" (+{len(self.unresolved) - 2} more)" if len(self.unresolved) > 2
                          else ""))
        if n_sig == 0 and len(m) == 0:
            return Verdict.inconclusive(
                name, rule=rule, basis=basis,
                reason="no predicted critical speed in the measured range and no resonance "
                       "matched: nothing was compared")
        if unjudged is not None:
            return Verdict.passed(name, rule=rule, basis=basis,
                                  reason=f"{len(m)} critical(s) matched within the speed "
                                         f"tolerance; amplitudes not judged: {unjudged}")
        return Verdict.passed(name, rule=rule, basis=basis,
                              reason=f"{len(m)} critical(s) matched within the tolerances")

    def to_frame(self):
        """The matched table (copy)."""
        return self.matched.copy()

    def summary(self) -> dict:
        """Counts and worst deviations, for summaries and JSON output."""
        m = self.matched
        return {
            "matched": int(len(m)),
            "unmatched_measured": int(len(self.unmatched_measured)),
            "unmatched_predicted": int(len(self.unmatched_predicted)),
            "unmatched_predicted_significant": int(self.unmatched_predicted["significant"].sum())
            if len(self.unmatched_predicted) else 0,
            "max_abs_deviation_pct": float(m["deviation_pct"].abs().max()) if len(m) else
            float("nan"),
            "agrees": self.agrees,
            "flags": list(self.flags),
            "unresolved": list(self.unresolved),
        }

    def plot(self, ax=None):
        """Measured against predicted critical speed per match, with the tolerance band."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots(figsize=(5.5, 5))
        else:
            fig = ax.figure
        m = self.matched
        if len(m):
            lo = float(min(m.speed_rpm_predicted.min(), m.speed_rpm_measured.min())) * 0.9
            hi = float(max(m.speed_rpm_predicted.max(), m.speed_rpm_measured.max())) * 1.1
            x = np.array([lo, hi])
            ax.plot(x, x, "k-", lw=0.8)
            ax.fill_between(x, x * (1 - self.tolerance), x * (1 + self.tolerance),
                            color="g", alpha=0.15, label=f"±{self.tolerance:.0%}")
            for mode, grp in m.groupby("mode"):
                ax.plot(grp.speed_rpm_predicted, grp.speed_rpm_measured, "o",
                        label=f"mode {mode}")
                for _, r in grp.iterrows():
                    ax.annotate(f"{r.order:g}", (r.speed_rpm_predicted, r.speed_rpm_measured),
                                textcoords="offset points", xytext=(4, -8), fontsize=7)
            ax.legend(fontsize=8)
        ax.set_xlabel("predicted critical speed (rpm)")
        ax.set_ylabel("measured critical speed (rpm)")
        ax.grid(alpha=0.3)
        return fig


def match_criticals(measured, predicted, *, gate=0.15, tolerance=0.03,
                    amplitude_tolerance=0.5, speed_range_rpm=None, combine_sweeps=True,
                    amplitudes_not_judged=None,
                    order_tolerance=1e-6, significant_fraction=0.05):
    """Assign measured resonances to predicted (mode, order) critical speeds.

    Parameters
    ----------
    measured : ResonanceTable or pandas.DataFrame
        From :func:`analysis.find_resonances` (or a frame with ``order``, ``speed_rpm`` and
        optionally ``amplitude``/``amplitude_corrected``, ``confidence``, ``frequency_hz``).
    predicted : pandas.DataFrame
        Critical speeds as from ``TorsionalSystem.critical_speeds``: ``mode``, ``order``,
        ``speed_rpm``, optionally ``frequency_hz``, ``amplitude`` (predicted resonance
        amplitude in the measured units and convention), ``major``/``vector_sum``.
    gate : float
        Largest relative speed deviation a match may have (0.15 = 15 %); beyond it the two
        stay unmatched.
    tolerance : float
        Relative speed deviation above which a match is flagged as disagreement.
    amplitude_tolerance : float
        A match is flagged when measured/predicted amplitude lies outside [1/(1+t), 1+t].
    speed_range_rpm : (float, float), optional
        Speed range the measurement covered; predicted criticals outside it are ignored.
        Default: the range of the measured track if the table carries its curves, else all.
    combine_sweeps : bool
        Merge one order's resonances from different sweeps (run-up, run-down) first.
    amplitudes_not_judged : str, optional
        Why the amplitude ratios cannot be judged (e.g. the run's load is not stated, so the
        predicted amplitudes rest on an assumed load): they are still tabulated, but raise no
        disagreement, and the verdict's rule says so. None (default): judged.
    order_tolerance : float
        Orders equal within this are the same order.
    significant_fraction : float
        A predicted critical is *significant* when its predicted amplitude is at least this
        fraction of the largest predicted amplitude (without amplitudes: when it is a major
        order, or always without that column either); a boolean ``significant`` column in
        ``predicted`` overrides this. Only significant criticals are judged: their deviations
        and their absence are flagged, while weak ones (whose peaks sit on a large background
        and cannot be identified reliably) are matched and listed only. Likewise a measured
        resonance without a critical is flagged when its amplitude is at least this fraction
        of the largest measured one.

    Returns
    -------
    CriticalComparison

    Notes
    -----
    Cost matrix ``c_ij = |n_i − n_j| / n_j`` for equal orders, a forbidden cost otherwise
    or beyond the gate; the optimal assignment minimises the summed deviation (Kuhn–Munkres,
    O(n³)). A nearest-neighbour rule per item can give one critical two peaks; the assignment
    cannot.

    References
    ----------
    Kuhn, H. W., "The Hungarian method for the assignment problem", Naval Res. Logist. Q. 2
    (1955) 83–97; Crouse, D. F., "On implementing 2D rectangular assignment algorithms", IEEE
    Trans. Aerosp. Electron. Syst. 52 (2016) 1679–1696 (scipy's algorithm).

    Examples
    --------
    >>> import pandas as pd
    >>> pred = pd.DataFrame({"mode": [1, 1, 2], "order": [6.0, 4.5, 6.0],
    ...                      "speed_rpm": [400.0, 533.3, 1500.0]})
    >>> meas = pd.DataFrame({"order": [6.0, 4.5], "speed_rpm": [404.0, 530.0]})
    >>> c = match_criticals(meas, pred, speed_range_rpm=(300, 900))
    >>> print(c.matched[["mode", "order", "deviation_pct"]].round(2).to_string(index=False))
     mode  order  deviation_pct
        1    4.5          -0.62
        1    6.0           1.00
    """
    import pandas as pd
    from scipy.optimize import linear_sum_assignment

    gate = check_range(gate, "gate", 0.0, 1.0, inclusive=(False, True), error=AnalysisError)
    tolerance = check_positive(tolerance, "tolerance", error=AnalysisError)
    amplitude_tolerance = check_positive(amplitude_tolerance, "amplitude_tolerance",
                                         error=AnalysisError)
    meas = _measured_frame(measured)
    if not isinstance(predicted, pd.DataFrame):
        raise AnalysisError(f"predicted must be a pandas DataFrame of critical speeds, got "
                            f"{type(predicted).__name__}")
    for col in ("mode", "order", "speed_rpm"):
        if col not in predicted:
            raise AnalysisError(f"predicted criticals need a column {col!r}; columns: "
                                f"{list(predicted.columns)}")
    pred = predicted.copy().reset_index(drop=True)
    if "frequency_hz" not in pred:
        pred["frequency_hz"] = pred["speed_rpm"] * pred["order"] / 60.0
    if "amplitude" not in pred:
        pred["amplitude"] = np.nan
    if speed_range_rpm is None and hasattr(measured, "curves") and measured.curves:
        speed_range_rpm = (min(float(c.speed_rpm.min()) for c in measured.curves),
                           max(float(c.speed_rpm.max()) for c in measured.curves))
    if speed_range_rpm is not None:
        lo, hi = map(float, speed_range_rpm)
        if not lo < hi:
            raise AnalysisError(f"speed_range_rpm={speed_range_rpm!r} must be (low, high) "
                                "with low < high")
        pred = pred[(pred.speed_rpm >= lo) & (pred.speed_rpm <= hi)].reset_index(drop=True)
    if "frequency_hz" not in meas:
        meas["frequency_hz"] = meas["speed_rpm"] * meas["order"] / 60.0
    if combine_sweeps:
        meas = _combine_sweeps(meas, gate)

    n_m, n_p = len(meas), len(pred)
    pairs = []
    if n_m and n_p:
        mo = meas["order"].to_numpy(float)[:, None]
        po = pred["order"].to_numpy(float)[None, :]
        ms = meas["speed_rpm"].to_numpy(float)[:, None]
        ps = pred["speed_rpm"].to_numpy(float)[None, :]
        cost = np.abs(ms - ps) / ps
        allowed = (np.abs(mo - po) <= order_tolerance) & (cost <= gate)
        cost = np.where(allowed, cost, _FORBIDDEN)
        rows, cols = linear_sum_assignment(cost)
        pairs = [(int(i), int(j)) for i, j in zip(rows, cols) if allowed[i, j]]

    amp_lo, amp_hi = 1.0 / (1.0 + amplitude_tolerance), 1.0 + amplitude_tolerance
    amps = pred["amplitude"].to_numpy(float)
    if "significant" in pred:
        significant = pred["significant"].to_numpy(bool)
    elif np.isfinite(amps).any() and np.nanmax(amps) > 0:
        significant = np.nan_to_num(amps) >= significant_fraction * np.nanmax(amps)
    elif "major" in pred:
        significant = pred["major"].to_numpy(bool)
    else:
        significant = np.ones(n_p, bool)
    records = []
    for i, j in pairs:
        m, p = meas.iloc[i], pred.iloc[j]
        dev = float(m.speed_rpm - p.speed_rpm)
        ratio = float(m.amplitude_used / p.amplitude) if np.isfinite(p.amplitude) and \
            p.amplitude > 0 and np.isfinite(m.amplitude_used) else float("nan")
        records.append(dict(
            mode=int(p["mode"]), order=float(p.order),
            speed_rpm_predicted=float(p.speed_rpm), speed_rpm_measured=float(m.speed_rpm),
            deviation_rpm=dev, deviation_pct=100.0 * dev / float(p.speed_rpm),
            frequency_hz_predicted=float(p.frequency_hz),
            frequency_hz_measured=float(m.frequency_hz),
            amplitude_predicted=float(p.amplitude), amplitude_measured=float(m.amplitude_used),
            amplitude_ratio=ratio, damping_ratio=float(m.damping_ratio),
            confidence=float(m.confidence),
            speed_ok=bool(abs(dev) <= tolerance * float(p.speed_rpm)),
            amplitude_ok=bool(not np.isfinite(ratio) or amp_lo <= ratio <= amp_hi),
            significant=bool(significant[j])))
    columns = ["mode", "order", "speed_rpm_predicted", "speed_rpm_measured", "deviation_rpm",
               "deviation_pct", "frequency_hz_predicted", "frequency_hz_measured",
               "amplitude_predicted", "amplitude_measured", "amplitude_ratio", "damping_ratio",
               "confidence", "speed_ok", "amplitude_ok", "significant"]
    matched = pd.DataFrame(records, columns=columns).sort_values(
        ["mode", "order"], ignore_index=True)
    used_m = {i for i, _ in pairs}
    used_p = {j for _, j in pairs}
    keep_m = [c for c in ("order", "speed_rpm", "frequency_hz", "amplitude_used",
                          "damping_ratio", "confidence") if c in meas]
    unmatched_measured = meas.loc[[i for i in range(n_m) if i not in used_m], keep_m] \
        .rename(columns={"amplitude_used": "amplitude"}).reset_index(drop=True)
    unmatched_predicted = pred.loc[[j for j in range(n_p) if j not in used_p]] \
        .reset_index(drop=True)
    unmatched_predicted["significant"] = [bool(significant[j]) for j in range(n_p)
                                          if j not in used_p]

    nat = _natural_frequencies(matched, pred)
    flags = []
    for _, r in matched.iterrows():
        if not r.significant:
            continue  # weak criticals are listed, not judged: their peaks sit on a background
        if not r.speed_ok:
            flags.append(f"mode {r['mode']} order {r.order:g}: measured critical speed "
                         f"{r.speed_rpm_measured:.1f} rpm deviates {r.deviation_pct:+.1f} % "
                         f"from the predicted {r.speed_rpm_predicted:.1f} rpm "
                         f"(tolerance ±{100 * tolerance:g} %)")
        if not r.amplitude_ok and amplitudes_not_judged is None:
            flags.append(f"mode {r['mode']} order {r.order:g}: amplitude ratio measured/"
                         f"predicted {r.amplitude_ratio:.2f} outside "
                         f"[{amp_lo:.2f}, {amp_hi:.2f}]")
    unresolved = []
    scale = _amplitude_scale(amplitudes_not_judged)
    status = ["" if not sig else "not found" for sig in unmatched_predicted["significant"]]
    for row, (_, r) in enumerate(unmatched_predicted.iterrows()):
        if not r.significant:
            continue
        missing = (f"mode {r['mode']} order {r.order:g}: predicted critical at "
                   f"{r.speed_rpm:.1f} rpm not found in the measurement (gate ±{100 * gate:g} %)")
        limit = float(r.get("detection_limit", np.nan))
        if not np.isfinite(limit):           # what the record could show is not known
            flags.append(missing)
            continue
        rise = float(r.amplitude) * scale - float(r.get("measured_level", 0.0))
        if np.isfinite(rise) and rise >= (1.0 + amplitude_tolerance) * limit:
            flags.append(f"{missing}: its expected rise {rise:.3g} is above the detection "
                         f"limit {limit:.3g}")
        else:
            if not np.isfinite(rise):
                why = "expected rise unknown (amplitudes not judged)"
            elif rise <= 0:
                why = (f"its predicted amplitude {float(r.amplitude):.3g} does not rise above "
                       f"the measured level {float(r.get('measured_level', 0.0)):.3g}")
            else:
                why = f"expected rise {rise:.3g}"
            unresolved.append(f"mode {r['mode']} order {r.order:g} at {r.speed_rpm:.1f} rpm "
                              f"not found and not resolvable: {why} against a detection limit "
                              f"{limit:.3g} (the track's noise there × the finder's SNR)")
            status[row] = f"not found, not resolvable: {why} (detection limit {limit:.3g})"
    unmatched_predicted["status"] = status
    meas_amp = unmatched_measured["amplitude"].to_numpy(float) if "amplitude" in \
        unmatched_measured else np.full(len(unmatched_measured), np.nan)
    top = np.nanmax(meas["amplitude_used"].to_numpy(float)) if n_m and \
        np.isfinite(meas["amplitude_used"].to_numpy(float)).any() else np.nan
    for k, (_, r) in enumerate(unmatched_measured.iterrows()):
        if np.isfinite(top) and np.isfinite(meas_amp[k]) and \
                meas_amp[k] < significant_fraction * top:
            continue
        flags.append(f"order {r.order:g}: measured resonance at {r.speed_rpm:.1f} rpm matches "
                     f"no predicted critical (gate ±{100 * gate:g} %)")
    settings = dict(gate=gate, tolerance=tolerance, amplitude_tolerance=amplitude_tolerance,
                    speed_range_rpm=None if speed_range_rpm is None else
                    [float(v) for v in speed_range_rpm], combine_sweeps=bool(combine_sweeps),
                    amplitudes_not_judged=amplitudes_not_judged)
    return CriticalComparison(matched, unmatched_measured, unmatched_predicted, nat, gate,
                              tolerance, amplitude_tolerance, tuple(flags), settings,
                              tuple(unresolved))


def _amplitude_scale(amplitudes_not_judged) -> float:
    """Factor on a predicted amplitude for the rise expected in the record: 1 when amplitudes
    are judged, NaN (unknown) when they rest on an assumed load — the other criticals' ratios
    do not scale it (under a propeller law the load, and so the ratio, changes with speed:
    0.13 at the 6L32's 247 rpm critical against 0.32 at 543 rpm)."""
    return 1.0 if amplitudes_not_judged is None else float("nan")


def not_judged_reason(predicted, mode, order) -> str:
    """Why a predicted critical in the range is listed but not judged: the reason the sweep
    analysis recorded (``predicted['not_judged']``, e.g. not covered with both flanks), else
    'weak (below the significance threshold)'.

    Examples
    --------
    >>> import pandas as pd
    >>> p = pd.DataFrame({"mode": [1, 2], "order": [0.5, 6.0],
    ...                   "not_judged": ["not covered by the run", ""]})
    >>> not_judged_reason(p, 1, 0.5), not_judged_reason(p, 2, 6.0)
    ('not covered by the run', 'weak (below the significance threshold)')
    """
    if predicted is not None and "not_judged" in getattr(predicted, "columns", ()):
        hit = predicted[(predicted["mode"] == mode) & (predicted["order"] == order)]
        if len(hit) and isinstance(hit["not_judged"].iloc[0], str) and hit["not_judged"].iloc[0]:
            return hit["not_judged"].iloc[0]
    return "weak (below the significance threshold)"


def _natural_frequencies(matched, pred):
    """Per mode: the measured natural frequency collected over every matched order."""
    import pandas as pd

    rows = []
    for mode, grp in pred.groupby("mode"):
        f_pred = float(grp["frequency_hz"].iloc[0])
        m = matched[matched["mode"] == mode]
        if len(m):
            w = np.clip(m["confidence"].to_numpy(float), 1e-6, None)
            f = m["frequency_hz_measured"].to_numpy(float)
            f_meas = float(np.sum(w * f) / np.sum(w))
            # like with like: the prediction over the same orders, same weights
            f_pred = float(np.sum(w * m["frequency_hz_predicted"].to_numpy(float)) / np.sum(w))
            spread = float(np.sqrt(np.sum(w * (f - f_meas) ** 2) / np.sum(w))) if len(m) > 1 \
                else float("nan")
        else:
            f_meas = spread = float("nan")
        rows.append(dict(mode=int(mode), frequency_hz_predicted=f_pred,
                         frequency_hz_measured=f_meas, spread_hz=spread, n_orders=int(len(m)),
                         orders=", ".join(f"{o:g}" for o in sorted(m["order"])),
                         deviation_pct=100.0 * (f_meas - f_pred) / f_pred
                         if np.isfinite(f_meas) else float("nan")))
    return pd.DataFrame(rows, columns=["mode", "frequency_hz_predicted", "frequency_hz_measured",
                                       "spread_hz", "n_orders", "orders", "deviation_pct"])


# ---------------------------------------------------------------------------------------------
# balance
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class BalanceComparison:
    """Measured order vibration at a mount against the predicted response to the residuals.

    Attributes
    ----------
    table : pandas.DataFrame
        Per order: ``order``, ``median_ratio`` (measured/predicted), ``min_ratio``,
        ``max_ratio``, ``rms_log_deviation_db`` (rms of 20 log10 ratio), ``n_points``,
        ``passed``.
    curves : dict
        ``{order: (speed_rpm, measured, predicted)}`` arrays for plotting.
    units : str
    factor : float
        Agreement band: median ratio within [1/factor, factor].
    channel : str
    """

    table: object
    curves: dict
    units: str
    factor: float
    channel: str = ""

    @property
    def passed(self) -> bool:
        return bool(len(self.table)) and bool(self.table["passed"].all())

    def to_frame(self):
        return self.table.copy()

    def plot(self, ax=None):
        """Measured (solid) and predicted (dashed) order amplitude against speed."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots(figsize=(7, 4))
        else:
            fig = ax.figure
        for order, (rpm, meas, pred) in self.curves.items():
            line, = ax.plot(rpm, meas, lw=1.0, label=f"order {order:g} measured")
            ax.plot(rpm, pred, "--", color=line.get_color(), lw=1.2,
                    label=f"order {order:g} predicted")
        ax.set_xlabel("speed (rpm)")
        ax.set_ylabel(f"amplitude ({self.units})")
        ax.set_title(f"balance residuals at {self.channel}" if self.channel else
                     "balance residuals")
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
        return fig


def compare_balance(measured, predicted, *, orders=(1.0, 2.0), factor=2.0, channel="",
                    min_fraction=0.01):
    """Compare measured order amplitudes at a mount with the predicted balance response.

    Parameters
    ----------
    measured : xarray.Dataset
        Order track at the mount (``amplitude`` over ``order`` × ``time`` with an ``rpm``
        coordinate, or over ``order`` × ``rpm``).
    predicted : xarray.DataArray
        Predicted amplitude over (``order``, ``rpm``), same units and amplitude convention
        as the measurement (for example the mount model's response to the residual forces
        and moments of :func:`predict.balance.unbalance`).
    orders : sequence of float
        Orders to compare (the balance orders, 1 and 2 by default).
    factor : float
        Agreement band for the median ratio (2 = within a factor of two). Balance residuals
        depend on manufacturing tolerances, so the band is wide by nature.
    channel : str
        Channel name, for the report.
    min_fraction : float
        Speeds where the prediction is below this fraction of its maximum are skipped
        (ratios of near-zero predictions say nothing).

    Returns
    -------
    BalanceComparison

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> rpm = np.linspace(600, 1800, 50)
    >>> pred = xr.DataArray(np.vstack([1e-4 * (rpm / 1000) ** 2, 2e-5 * (rpm / 1000) ** 2]),
    ...                     dims=("order", "rpm"), coords={"order": [1.0, 2.0], "rpm": rpm})
    >>> meas = xr.Dataset({"amplitude": (("order", "time"), 1.2 * pred.values)},
    ...                   coords={"order": [1.0, 2.0], "rpm": ("time", rpm)})
    >>> print(compare_balance(meas, pred).table[["order", "median_ratio"]].round(3).to_string(index=False))
     order  median_ratio
       1.0           1.2
       2.0           1.2
    """
    import pandas as pd
    import xarray as xr

    factor = check_range(factor, "factor", 1.0, None, inclusive=(False, True),
                         error=AnalysisError)
    if not isinstance(measured, xr.Dataset) or "amplitude" not in measured:
        raise AnalysisError("measured must be an order-track Dataset with an 'amplitude' "
                            "variable")
    if not isinstance(predicted, xr.DataArray) or set(predicted.dims) != {"order", "rpm"}:
        raise AnalysisError("predicted must be an xarray.DataArray over ('order', 'rpm'), got "
                            f"{type(predicted).__name__} "
                            f"{getattr(predicted, 'dims', '')}")
    units = str(measured["amplitude"].attrs.get("units", predicted.attrs.get("units", "")))
    rows, curves = [], {}
    for order in orders:
        order = float(order)
        if not np.any(np.isclose(measured["order"].values, order)):
            raise AnalysisError(f"order {order:g} is not in the measured track; available: "
                                f"{', '.join(f'{o:g}' for o in measured['order'].values)}")
        if not np.any(np.isclose(predicted["order"].values, order)):
            raise AnalysisError(f"order {order:g} is not in the prediction")
        sub = measured.sel(order=order, method="nearest")
        rpm = np.asarray(sub["rpm"].values, float)
        amp = np.asarray(sub["amplitude"].values, float)
        p = predicted.sel(order=order, method="nearest")
        prpm = np.asarray(p["rpm"].values, float)
        pval = np.asarray(p.values, float)
        k = np.argsort(prpm)
        inside = (rpm >= prpm.min()) & (rpm <= prpm.max()) & np.isfinite(amp)
        rpm, amp = rpm[inside], amp[inside]
        pred_at = np.interp(rpm, prpm[k], pval[k])
        ok = pred_at > min_fraction * np.max(np.abs(pval)) if pval.size else pred_at > 0
        if ok.sum() < 3:
            raise AnalysisError(f"order {order:g}: fewer than 3 speeds where measurement and "
                                "prediction overlap")
        ratio = amp[ok] / pred_at[ok]
        db = 20 * np.log10(np.clip(ratio, 1e-12, None))
        med = float(np.median(ratio))
        rows.append(dict(order=order, median_ratio=med, min_ratio=float(ratio.min()),
                         max_ratio=float(ratio.max()),
                         rms_log_deviation_db=float(np.sqrt(np.mean(db**2))),
                         n_points=int(ok.sum()), passed=bool(1 / factor <= med <= factor)))
        s = np.argsort(rpm)
        curves[order] = (rpm[s], amp[s], pred_at[s])
    return BalanceComparison(pd.DataFrame(rows), curves, units, factor, channel)
