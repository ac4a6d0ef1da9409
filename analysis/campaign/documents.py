"""One record's results as a store document (table -> rows) for :class:`Store.put`.

:func:`document_from_result` flattens a :class:`~crankbench.analysis.pipeline.PipelineResult`
into the tidy tables of :mod:`analysis.campaign.store`; :func:`document_from_error` records a
record that failed, so a campaign lists it with its error instead of losing it;
:func:`document_from_tracks` keeps an order analysis without a model (``analyse --store``):
its order amplitudes and steady-state table, with the verdict 'inconclusive' (nothing was
compared).
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
from pathlib import Path

import numpy as np

__all__ = ["settings_key", "document_from_result", "document_from_error",
           "document_from_tracks", "record_identity", "store_result", "store_tracks",
           "steady_order_rows", "reference_speeds"]

_IDENTITY_ATTRS = ("start_time", "test_id", "engine_id", "build")


def settings_key(settings: dict, model_sha256: str) -> str:
    """Hash of the analysis settings and the model file: part of a run's identity.

    Examples
    --------
    >>> settings_key({"max_order": 12}, "00" * 32) == settings_key({"max_order": 12}, "00" * 32)
    True
    >>> settings_key({"max_order": 12}, "00" * 32) == settings_key({"max_order": 9}, "00" * 32)
    False
    """
    from crankbench.analysis._output import to_jsonable

    text = json.dumps(to_jsonable(settings), sort_keys=True) + model_sha256
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def record_identity(record_path, attrs: dict | None = None) -> dict:
    """The identity columns of the ``runs`` row from a record file and its attrs.

    ``start_time``, ``test_id``, ``engine_id`` and ``build`` come from the record's attrs
    when present; every attr is kept as JSON in ``attrs`` (trends may use any of them).
    """
    from crankbench.analysis._output import to_jsonable

    attrs = dict(attrs or {})
    out = {"record_path": str(Path(record_path).resolve()),
           "record_name": Path(record_path).name,
           "attrs": to_jsonable({k: v for k, v in attrs.items()
                                 if k not in ("channel_map", "source_stat")}),
           "channel_map": attrs.get("channel_map")}
    for key in _IDENTITY_ATTRS:
        value = attrs.get(key)
        out[key] = None if value is None else str(value)
    return out


def reference_speeds(speed_range_rpm, count: int = 5, *, step_rpm: float = 10.0) -> np.ndarray:
    """Default reference speeds for the order-amplitude table: ``count`` speeds evenly inside
    the measured range, rounded to ``step_rpm``.

    Examples
    --------
    >>> reference_speeds((500.0, 750.0))
    array([530., 580., 630., 680., 730.])
    """
    lo, hi = (float(v) for v in speed_range_rpm)
    inner = lo + (hi - lo) * (np.arange(count) + 0.5) / count
    return np.floor(inner / step_rpm + 0.5) * step_rpm


def _order_amplitudes(track, speeds_rpm, run_id, units) -> list[dict]:
    """Order amplitudes of the track at the reference speeds (linear in rpm, first sweep); a
    steady run (speed spread under 1 rpm) gives one row per order at its median speed."""
    if track is None or "amplitude" not in track or "rpm" not in track.coords:
        return []
    rpm = np.asarray(track["rpm"].values, float)
    rows = []
    for order in np.asarray(track["order"].values, float):
        amp = np.asarray(track["amplitude"].sel(order=order).values, float)
        good = np.isfinite(amp) & np.isfinite(rpm)
        if good.sum() < 2:
            continue
        r, a = rpm[good], amp[good]
        if np.ptp(r) < 1.0:        # a steady run: one row, its median amplitude at its speed
            rows.append({"run_id": run_id, "order": float(order),
                         "speed_rpm": float(np.median(r)), "amplitude": float(np.median(a)),
                         "units": units})
            continue
        k = np.argsort(r, kind="stable")
        r, a = r[k], a[k]
        for s in speeds_rpm:
            if r[0] <= s <= r[-1]:
                rows.append({"run_id": run_id, "order": float(order), "speed_rpm": float(s),
                             "amplitude": float(np.interp(s, r, a)), "units": units})
    return rows


def steady_order_rows(table, run_id: str, units=None) -> list[dict]:
    """Rows of the ``steady_orders`` table from a steady-state order table
    (:func:`analysis.steady.steady_orders`; None or empty: no rows)."""
    if table is None:
        return []
    attrs = getattr(table, "attrs", {}) or {}
    return _frame_rows(table, {c: c for c in (
        "segment", "order", "speed_rpm", "speed_spread_rpm", "revolutions", "amplitude",
        "amplitude_uncertainty", "phase_deg", "phase_uncertainty_deg")}, run_id,
        {"units": attrs.get("units", units), "phase_reference": attrs.get("phase_reference")})


def _frame_rows(frame, columns: dict, run_id: str, extra: dict | None = None) -> list[dict]:
    """Rows of ``frame`` renamed by ``columns`` (store column -> frame column)."""
    if frame is None or len(frame) == 0:
        return []
    rows = []
    for _, r in frame.iterrows():
        row = {"run_id": run_id, **(extra or {})}
        for store_col, frame_col in columns.items():
            if frame_col in r.index:
                value = r[frame_col]
                row[store_col] = None if value is None or (
                    isinstance(value, float) and not np.isfinite(value)) else value
        rows.append(row)
    return rows


def _checks(result, run_id: str) -> list[dict]:
    """Every verdict of the result, with the value, limit and units of the limit checks."""
    limits = {c.name: c for c in getattr(result, "limits", ()) or ()}
    rows = []
    for v in getattr(result, "verdicts", ()) or ():
        d = v.as_dict()
        check = limits.get(d["check"])
        rows.append({"run_id": run_id, "check": d["check"], "verdict": d["verdict"],
                     "rule": d.get("rule"), "basis": d.get("basis"), "reason": d.get("reason"),
                     "value": getattr(check, "value", None), "limit": getattr(check, "limit", None),
                     "units": getattr(check, "units", None)})
    return rows


def document_from_result(result, *, record_path, run_id: str, settings: dict,
                         model_path=None, model_sha256: str | None = None,
                         settings_key_: str | None = None, report_path=None,
                         elapsed_s: float | None = None, reference_speeds_rpm=None) -> dict:
    """The store document of one analysed record.

    Parameters
    ----------
    result : PipelineResult
    record_path : str or Path
    run_id : str
        From :func:`~analysis.campaign.store.run_id_for`.
    settings : dict
        The options the record was analysed with (JSON-able).
    model_path, model_sha256, settings_key_ : optional
        Model file and hashes (for the ``runs`` row).
    report_path : optional
        The record's own report, linked from the campaign report.
    elapsed_s : float, optional
        Analysis time, s.
    reference_speeds_rpm : array_like, optional
        Speeds (rpm) of the order-amplitude table (default :func:`reference_speeds`).
    """
    from crankbench.analysis.report.report import crankbench_version

    record = getattr(result, "record", None)
    attrs = dict(getattr(record, "attrs", {}) or {})
    units = getattr(result, "units", None)
    lo, hi = getattr(result, "speed_range_rpm", (np.nan, np.nan))
    checks = _checks(result, run_id)
    overall = result.verdict
    summary = result.summary() if hasattr(result, "summary") else {}
    runs = {"run_id": run_id, **record_identity(record_path, attrs),
            "record_sha256": getattr(result, "record_sha256", None),
            "settings_key": settings_key_, "settings": settings,
            "model_path": None if model_path is None else str(Path(model_path).resolve()),
            "model_sha256": model_sha256, "channel": getattr(result, "channel", None),
            "status": "ok", "error": None, "verdict": overall.status, "verdict_reason": overall.reason,
            "speed_min_rpm": lo, "speed_max_rpm": hi,
            "sweep_rate_rpm_per_s": getattr(result, "sweep_rate_rpm_per_s", None),
            "resonances": summary.get("resonances"), "matched": summary.get("matched"),
            "max_abs_deviation_pct": summary.get("max_abs_deviation_pct"),
            "report_path": None if report_path is None else str(Path(report_path).resolve()),
            "elapsed_s": elapsed_s, "software_version": crankbench_version(),
            "analysed_at": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")}
    comparison = getattr(result, "comparison", None)
    tol = getattr(comparison, "tolerance", None)
    criticals = _frame_rows(getattr(comparison, "matched", None), {
        "mode": "mode", "order": "order", "speed_rpm_measured": "speed_rpm_measured",
        "speed_rpm_predicted": "speed_rpm_predicted", "deviation_pct": "deviation_pct",
        "amplitude_measured": "amplitude_measured", "amplitude_predicted": "amplitude_predicted",
        "amplitude_ratio": "amplitude_ratio", "speed_ok": "speed_ok",
        "amplitude_ok": "amplitude_ok"}, run_id, {"units": units, "speed_tolerance": tol})
    resonances_obj = getattr(result, "resonances", None)
    res_frame = resonances_obj.to_frame() if hasattr(resonances_obj, "to_frame") else None
    resonances = _frame_rows(res_frame, {
        "speed_rpm": "speed_rpm", "order": "order", "frequency_hz": "frequency_hz",
        "amplitude": "amplitude", "damping_ratio": "damping_ratio",
        "confidence": "confidence"}, run_id, {"units": units})
    speeds = (reference_speeds((lo, hi)) if reference_speeds_rpm is None
              else np.asarray(reference_speeds_rpm, float)) if np.isfinite(lo) else []
    steady = getattr(result, "steady_orders", None)   # steady-state order table, if any
    steady_frame = steady.to_frame() if hasattr(steady, "to_frame") else steady
    steady_rows = steady_order_rows(steady_frame, run_id, units)
    return {"runs": [runs], "criticals": criticals, "resonances": resonances,
            "order_amplitudes": _order_amplitudes(getattr(result, "track", None), speeds,
                                                  run_id, units),
            "steady_orders": steady_rows, "checks": checks}


def document_from_error(*, record_path, run_id: str, error: str, settings: dict,
                        record_sha256: str | None = None, model_path=None,
                        model_sha256: str | None = None, settings_key_: str | None = None,
                        elapsed_s: float | None = None) -> dict:
    """The store document of a record that could not be analysed (status 'error')."""
    from crankbench.analysis.report.report import crankbench_version

    runs = {"run_id": run_id, **record_identity(record_path), "record_sha256": record_sha256,
            "settings_key": settings_key_, "settings": settings,
            "model_path": None if model_path is None else str(Path(model_path).resolve()),
            "model_sha256": model_sha256, "status": "error", "error": error,
            "verdict": "inconclusive", "verdict_reason": f"not analysed: {error}",
            "elapsed_s": elapsed_s, "software_version": crankbench_version(),
            "analysed_at": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")}
    return {"runs": [runs]}


def store_result(store_path, result, *, record_path, model_path, settings: dict,
                 report_path=None, elapsed_s: float | None = None) -> str:
    """Write one analysed record into a campaign store (created if missing); return its
    run_id. A run with the same record and settings is replaced, never duplicated."""
    from crankbench.analysis.report import file_sha256

    model_sha = file_sha256(model_path)
    return _store(store_path, record_path, {**settings, "model": Path(model_path).name},
                  model_sha, getattr(result, "record_sha256", None),
                  lambda **ids: document_from_result(
                      result, record_path=record_path, model_path=model_path,
                      model_sha256=model_sha, report_path=report_path, elapsed_s=elapsed_s,
                      **ids))


def _store(store_path, record_path, settings, model_sha256, record_sha256, make) -> str:
    """Identify a run (record hash, settings key), build its document with ``make(run_id=,
    settings=, settings_key_=)`` and put it into the store (created if missing)."""
    from crankbench.analysis._output import to_jsonable
    from crankbench.analysis.report import file_sha256

    from .store import Store, run_id_for

    settings = to_jsonable(settings)
    key = settings_key(settings, model_sha256)
    record_sha = record_sha256 or file_sha256(record_path)
    document = make(run_id=run_id_for(record_sha, key), settings=settings, settings_key_=key)
    with Store(store_path, create=True) as store:
        return store.put(document)


def document_from_tracks(tracks, *, record_path, run_id: str, settings: dict,
                         record_sha256: str | None = None, settings_key_: str | None = None,
                         steady_table=None, elapsed_s: float | None = None,
                         reference_speeds_rpm=None, attrs: dict | None = None) -> dict:
    """The store document of an order analysis without a model (``crankbench analyse``).

    Parameters
    ----------
    tracks : xarray.Dataset
        Order tracks (``amplitude`` over (order, time) with an ``rpm`` coordinate).
    record_path : str or Path
    run_id : str
    settings : dict
        The analysis options (JSON-able).
    record_sha256, settings_key_ : str, optional
    steady_table : pandas.DataFrame, optional
        Steady-state order table (:func:`analysis.steady.steady_orders`).
    elapsed_s : float, optional
        Analysis time, s.
    reference_speeds_rpm : array_like, optional
        Speeds (rpm) of the order-amplitude table (default :func:`reference_speeds` of the
        tracked speed range).
    attrs : dict, optional
        The record's attrs (identity columns).

    Returns
    -------
    dict
        Table -> rows: ``runs`` (verdict 'inconclusive': an order analysis compares nothing),
        ``order_amplitudes`` and ``steady_orders``.
    """
    from crankbench.analysis.report.report import crankbench_version

    units = tracks["amplitude"].attrs.get("units", tracks.attrs.get("units")) \
        if "amplitude" in tracks else None
    rpm = np.asarray(tracks["rpm"].values, float) if "rpm" in tracks.coords else np.array([])
    rpm = rpm[np.isfinite(rpm)]
    lo, hi = (float(rpm.min()), float(rpm.max())) if rpm.size else (np.nan, np.nan)
    runs = {"run_id": run_id, **record_identity(record_path, attrs),
            "record_sha256": record_sha256, "settings_key": settings_key_,
            "settings": settings, "channel": settings.get("channel"), "status": "ok",
            "error": None, "verdict": "inconclusive",
            "verdict_reason": "order analysis only (crankbench analyse): nothing was compared "
                              "with a prediction or a limit",
            "speed_min_rpm": lo, "speed_max_rpm": hi,
            "sweep_rate_rpm_per_s": tracks.attrs.get("sweep_rate_rpm_per_s"),
            "elapsed_s": elapsed_s, "software_version": crankbench_version(),
            "analysed_at": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")}
    speeds = (reference_speeds((lo, hi)) if reference_speeds_rpm is None
              else np.asarray(reference_speeds_rpm, float)) if np.isfinite(lo) else []
    return {"runs": [runs], "order_amplitudes": _order_amplitudes(tracks, speeds, run_id, units),
            "steady_orders": steady_order_rows(steady_table, run_id, units)}


def store_tracks(store_path, tracks, *, record_path, settings: dict, steady_table=None,
                 attrs: dict | None = None, elapsed_s: float | None = None) -> str:
    """Write one order analysis (no model) into a campaign store (created if missing); return
    its run_id. The same record analysed with the same settings replaces its rows."""
    from crankbench.analysis.report import file_sha256

    record_sha = file_sha256(record_path)
    return _store(store_path, record_path, {**settings, "command": "analyse"}, "", record_sha,
                  lambda **ids: document_from_tracks(
                      tracks, record_path=record_path, record_sha256=record_sha,
                      steady_table=steady_table, elapsed_s=elapsed_s, attrs=attrs, **ids))
