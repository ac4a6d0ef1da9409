"""Human column headers with units and the number format of each quantity, for report tables.

A table column named in code (``speed_rpm_predicted``) is printed under a header a person reads
("predicted speed (rpm)"), in its display unit, with the digits its quantity deserves: speeds to
0.1 rpm, frequencies to 0.01 Hz, deviations as signed percentages to 0.01, ratios to 0.01,
damping ratios to 3 significant digits, amplitudes to 3 significant digits. Round-off is not
data: a value below 1e-9 of its column's largest magnitude is printed as 0, and a phase whose
amplitude is round-off has no phase (—).

Examples
--------
>>> import pandas as pd
>>> f = pd.DataFrame({"speed_rpm": [721.04], "amplitude": [2.03e-14], "deviation_pct": [0.391]})
>>> f.loc[1] = [540.0, 3.1e-3, -1.0]
>>> headers, rows = format_table(f, amplitude_units="rad")
>>> headers
['speed (rpm)', 'amplitude (mdeg)', 'deviation (%)']
>>> rows
[['721.0', '0', '+0.39'], ['540.0', '178', '-1.00']]
"""

from __future__ import annotations

import numpy as np

__all__ = ["COLUMNS", "format_table", "format_value"]

# name: (header, unit, kind); unit "{amp}" takes the amplitude unit of the table
COLUMNS = {
    "mode": ("mode", "", "int"),
    "order": ("order", "", "order"),
    "speed_rpm": ("speed", "rpm", "speed"),
    "speed_rpm_predicted": ("predicted speed", "rpm", "speed"),
    "speed_rpm_measured": ("measured speed", "rpm", "speed"),
    "speed_rpm_undamped": ("undamped critical speed", "rpm", "speed"),
    "deviation_rpm": ("deviation", "rpm", "signed_speed"),
    "deviation_pct": ("deviation", "%", "pct"),
    "frequency_hz": ("frequency", "Hz", "freq"),
    "frequency_hz_predicted": ("predicted frequency", "Hz", "freq"),
    "frequency_hz_measured": ("measured frequency", "Hz", "freq"),
    "frequency_hz_undamped": ("undamped frequency", "Hz", "freq"),
    "spread_hz": ("spread over orders", "Hz", "freq"),
    "n_orders": ("orders matched", "", "int"),
    "orders": ("orders", "", "text"),
    "amplitude": ("amplitude", "{amp}", "amp"),
    "amplitude_corrected": ("amplitude, sweep-corrected", "{amp}", "amp"),
    "amplitude_predicted": ("predicted amplitude", "{amp}", "amp"),
    "amplitude_measured": ("measured amplitude", "{amp}", "amp"),
    "amplitude_ratio": ("amplitude ratio meas./pred.", "", "ratio"),
    "damping_ratio": ("damping ratio", "", "sig3"),
    "confidence": ("confidence", "", "ratio"),
    "speed_ok": ("speed within tolerance", "", "bool"),
    "amplitude_ok": ("amplitude within tolerance", "", "bool"),
    "significant": ("significant", "", "bool"),
    "identified": ("identified by fit", "", "bool"),
    "major": ("major order", "", "bool"),
    "vector_sum": ("relative vector sum", "", "sig3"),
    "sweep_rate_rpm_per_s": ("sweep rate", "rpm/s", "sig3"),
    "sweep_peak_loss": ("sweep peak loss", "%", "loss_pct"),
    "direction": ("sweep", "", "text"),
    "method": ("method", "", "text"),
    "median_ratio": ("median ratio meas./pred.", "", "ratio"),
    "min_ratio": ("min. ratio", "", "ratio"),
    "max_ratio": ("max. ratio", "", "ratio"),
    "rms_log_deviation_db": ("rms deviation", "dB", "db"),
    "n_points": ("speeds compared", "", "int"),
    "passed": ("passed", "", "bool"),
    "predicted_max": ("predicted max.", "{amp}", "amp"),
    "measured_max": ("measured max.", "{amp}", "amp"),
    "balanced_by_design": ("balanced by design", "", "bool"),
    "phase_deg": ("phase", "deg", "phase"),
    "amplitude_uncertainty": ("± amplitude (1σ)", "{amp}", "amp"),
    "phase_uncertainty_deg": ("± phase (1σ)", "deg", "sig3"),
    "segment": ("steady segment", "", "int"),
    "revolutions": ("revolutions", "", "int"),
    "status": ("status", "", "text"),
}

#: display unit and scale of SI amplitude units
_AMPLITUDE_DISPLAY = {"rad": ("mdeg", np.rad2deg(1.0) * 1e3), "rad/s": ("rad/s", 1.0),
                      "m/s^2": ("m/s²", 1.0), "m/s²": ("m/s²", 1.0), "m/s": ("mm/s", 1e3),
                      "m": ("µm", 1e6), "Pa": ("MPa", 1e-6)}

ROUNDOFF = 1e-9


def amplitude_display(units: str):
    """(display unit, scale) for an SI amplitude unit (rad → mdeg, m/s → mm/s, Pa → MPa).

    Examples
    --------
    >>> amplitude_display("rad")[0], round(float(amplitude_display("rad")[1]), 3)
    ('mdeg', 57295.78)
    """
    return _AMPLITUDE_DISPLAY.get(str(units), (str(units), 1.0))


def format_value(value, kind: str, *, scale: float = 1.0, column_max: float | None = None) -> str:
    """One cell: NaN/None → —, round-off (below 1e-9 of ``column_max``) → 0, else the digits
    of its kind.

    Examples
    --------
    >>> format_value(42.0e6, "sig3", scale=1e-6), format_value(2e-14, "amp", column_max=3e-3)
    ('42.0', '0')
    """
    if value is None:
        return "—"
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if kind in ("text",) or isinstance(value, str):
        return str(value)
    try:
        v = float(value)
    except (TypeError, ValueError):
        return str(value)
    if not np.isfinite(v):
        return "—"
    v *= scale
    if kind == "bool":
        return "yes" if v else "no"
    if kind == "int":
        return f"{int(round(v))}"
    top = np.inf if column_max is None or not np.isfinite(column_max) else abs(column_max)
    if (np.isfinite(top) and abs(v) <= ROUNDOFF * top * abs(scale)) or abs(v) < 1e-300:
        return "0"
    if kind == "order":
        return f"{v:g}"
    if kind == "speed":
        return f"{v:.1f}"
    if kind == "signed_speed":
        return f"{v:+.1f}"
    if kind == "freq":
        return f"{v:.2f}"
    if kind == "pct":
        return f"{v:+.2f}"
    if kind == "loss_pct":
        return f"{100 * v:.1f}"
    if kind == "ratio":
        return f"{v:.2f}"
    if kind == "db":
        return f"{v:.1f}"
    if kind == "phase":
        return f"{v:.0f}"
    # amplitudes and other magnitudes: 3 significant digits, no exponent for ordinary sizes
    if 1e-3 <= abs(v) < 1e6:
        digits = max(0, 2 - int(np.floor(np.log10(abs(v)))))
        return f"{v:.{digits}f}"
    return f"{v:.3g}"


def format_table(frame, *, amplitude_units: str = "", columns: dict | None = None):
    """Headers and formatted rows of a DataFrame (see the module docstring).

    Parameters
    ----------
    frame : pandas.DataFrame
    amplitude_units : str
        SI units of the amplitude columns (converted for display: rad → mdeg ...).
    columns : dict, optional
        Overrides of :data:`COLUMNS`: ``{name: (header, unit, kind)}``.

    Returns
    -------
    (list of str, list of list of str)
    """
    spec = dict(COLUMNS)
    spec.update(columns or {})
    amp_unit, amp_scale = amplitude_display(amplitude_units)
    headers, kinds, scales, maxima = [], [], [], []
    for c in frame.columns:
        header, unit, kind = spec.get(str(c), (str(c).replace("_", " "), "", "auto"))
        scale = 1.0
        if unit == "{amp}":
            unit, scale = amp_unit, amp_scale
        headers.append(f"{header} ({unit})" if unit else header)
        kinds.append(kind)
        scales.append(scale)
        col = frame[c]
        try:
            values = np.abs(np.asarray(col, float))
            maxima.append(float(np.nanmax(values)) if np.isfinite(values).any() else None)
        except (TypeError, ValueError):
            maxima.append(None)
    amp_col = next((i for i, c in enumerate(frame.columns)
                    if spec.get(str(c), ("", "", ""))[1] == "{amp}"), None)
    rows = []
    for row in frame.itertuples(index=False):
        cells = []
        for v, kind, scale, top in zip(row, kinds, scales, maxima):
            if kind == "auto":
                kind = "text" if isinstance(v, str) else ("bool" if isinstance(
                    v, (bool, np.bool_)) else "sig3")
            cells.append(format_value(v, kind, scale=scale, column_max=top))
        if amp_col is not None and cells[amp_col] == "0":
            # no phase on a round-off residual
            cells = ["—" if k == "phase" else c for c, k in zip(cells, kinds)]
        rows.append(cells)
    return headers, rows
