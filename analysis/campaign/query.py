"""Queries over a campaign store: the runs and their verdicts, and trends across runs.

A trend follows one quantity over the runs of a campaign — a measured critical speed or
resonance amplitude of one (mode, order), an order amplitude at a reference speed, a limit
check's value — against the run, the build, the start time or any record attribute (a damper
stiffness, a load step), beside its prediction and the tolerance band.

Examples
--------
>>> TrendSpec.parse("critical speed mode 1 order 6")
TrendSpec(quantity='critical_speed', mode=1, order=6.0, speed_rpm=None, check=None)
>>> TrendSpec.parse("order amplitude order 4.5 at 600 rpm").speed_rpm
600.0
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass

import numpy as np

from crankbench.predict.errors import StoreError

__all__ = ["TrendSpec", "Trend", "list_runs", "trend", "QUANTITIES"]

#: quantity -> (table, measured column, predicted column or None, units column or fixed unit)
QUANTITIES = {
    "critical_speed": ("criticals", "speed_rpm_measured", "speed_rpm_predicted", "rpm"),
    "resonance_amplitude": ("criticals", "amplitude_measured", "amplitude_predicted", None),
    "amplitude_ratio": ("criticals", "amplitude_ratio", None, "1"),
    "order_amplitude": ("order_amplitudes", "amplitude", None, None),
    "steady_amplitude": ("steady_orders", "amplitude", None, None),
    "check": ("checks", "value", "limit", None),
}


@dataclass(frozen=True)
class TrendSpec:
    """What to follow across runs.

    Attributes
    ----------
    quantity : str
        One of :data:`QUANTITIES`.
    mode : int, optional
        Mode number (criticals).
    order : float, optional
        Excitation order.
    speed_rpm : float, optional
        Reference speed (order amplitudes).
    check : str, optional
        Check name (``quantity='check'``), matched as a substring.
    """

    quantity: str
    mode: int | None = None
    order: float | None = None
    speed_rpm: float | None = None
    check: str | None = None

    @classmethod
    def parse(cls, text: str) -> "TrendSpec":
        """From words: ``"critical speed mode 1 order 6"``, ``"resonance amplitude mode 2
        order 4.5"``, ``"order amplitude order 6 at 600 rpm"``, ``"steady amplitude order
        3"``, ``"check torsional stress"``."""
        words = text.strip().lower()
        if not words:
            raise StoreError("empty trend: say e.g. 'critical speed mode 1 order 6'")
        if words.startswith("check"):
            name = text.strip()[5:].strip()
            if not name:
                raise StoreError("trend 'check' needs the check's name: 'check torsional stress'")
            return cls("check", check=name)
        quantity = None
        for q in sorted(QUANTITIES, key=len, reverse=True):
            if words.startswith(q.replace("_", " ")):
                quantity = q
                break
        if quantity is None:
            names = ", ".join(q.replace("_", " ") for q in QUANTITIES)
            raise StoreError(f"trend {text!r}: starts with none of: {names}")

        def number(pattern, kind):
            m = re.search(pattern, words)
            return None if m is None else kind(m.group(1))

        spec = cls(quantity, mode=number(r"\bmode\s+(\d+)\b", int),
                   order=number(r"\border\s+([0-9]*\.?[0-9]+)", float),
                   speed_rpm=number(r"\bat\s+([0-9]*\.?[0-9]+)\s*rpm\b", float))
        spec.validate()
        return spec

    def validate(self) -> None:
        """Refuse a spec that cannot select one value per run."""
        if self.quantity not in QUANTITIES:
            from crankbench.predict._validate import suggest

            raise StoreError(f"unknown trend quantity {self.quantity!r}"
                             f"{suggest(self.quantity, QUANTITIES)}")
        table = QUANTITIES[self.quantity][0]
        if table == "criticals" and (self.mode is None or self.order is None):
            raise StoreError(f"trend {self.quantity.replace('_', ' ')} needs a mode and an "
                             "order: '... mode 1 order 6'")
        if table in ("order_amplitudes", "steady_orders") and self.order is None:
            raise StoreError(f"trend {self.quantity.replace('_', ' ')} needs an order")
        if table == "order_amplitudes" and self.speed_rpm is None:
            raise StoreError("trend order amplitude needs a reference speed: '... at 600 rpm'")

    def label(self) -> str:
        """Axis label."""
        parts = [self.quantity.replace("_", " ")]
        if self.check:
            parts.append(repr(self.check))
        if self.mode is not None:
            parts.append(f"mode {self.mode}")
        if self.order is not None:
            parts.append(f"order {self.order:g}")
        if self.speed_rpm is not None:
            parts.append(f"at {self.speed_rpm:g} rpm")
        return " ".join(parts)


def list_runs(store, *, test_id=None, engine_id=None, build=None, verdict=None, status=None,
              since=None, until=None):
    """The runs of a store, filtered; newest analysis last.

    Parameters
    ----------
    store : Store
    test_id, engine_id, build : str, optional
        Exact matches on the record's ids.
    verdict : {'pass', 'fail', 'inconclusive'}, optional
    status : {'ok', 'error'}, optional
    since, until : str, optional
        ISO dates (inclusive) on the record's start time (else the analysis time).

    Returns
    -------
    pandas.DataFrame
    """
    from crankbench.analysis.verdict import STATUSES
    from crankbench.predict._validate import check_option

    where, params = [], []
    for column, value in (("test_id", test_id), ("engine_id", engine_id), ("build", build)):
        if value is not None:
            where.append(f"{column} = ?")
            params.append(str(value))
    if verdict is not None:
        check_option(verdict, "verdict", STATUSES, error=StoreError)
        where.append("verdict = ?")
        params.append(verdict)
    if status is not None:
        check_option(status, "status", ("ok", "error"), error=StoreError)
        where.append("status = ?")
        params.append(status)
    for bound, op, value in (("since", ">=", since), ("until", "<=", until)):
        if value is not None:
            day = _iso_date(value, bound)
            where.append(f"substr(coalesce(start_time, analysed_at), 1, 10) {op} ?")
            params.append(day)
    frame = store.table("runs", " AND ".join(where), params)
    return frame.sort_values(["analysed_at", "record_path"], kind="stable",
                             ignore_index=True)


def _iso_date(value, name) -> str:
    import datetime as _dt

    try:
        return _dt.date.fromisoformat(str(value)[:10]).isoformat()
    except ValueError:
        raise StoreError(f"--{name} {value!r}: expected a date YYYY-MM-DD") from None


@dataclass(frozen=True)
class Trend:
    """One quantity across the runs of a campaign.

    Attributes
    ----------
    spec : TrendSpec
    by : str
        The x axis: 'run', 'build', 'start_time' or 'attr:NAME'.
    table : pandas.DataFrame
        One row per run: ``run_id``, ``record_name``, ``x``, ``value``, ``predicted``,
        ``low``/``high`` (tolerance band, when the quantity has one), ``units``, ``verdict``.
    """

    spec: TrendSpec
    by: str
    table: object

    def to_frame(self):
        """The table (copy)."""
        return self.table.copy()

    def plot(self, ax=None):
        """Measured value against ``by``, with the prediction and its tolerance band."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots(figsize=(7.5, 4.2))
        else:
            fig = ax.figure
        t = self.table
        numeric = np.issubdtype(np.asarray(t["x"]).dtype, np.number)
        x = np.asarray(t["x"], float) if numeric else np.arange(len(t))
        units = next((u for u in t["units"] if isinstance(u, str) and u), "")
        if t["predicted"].notna().any():
            ax.plot(x, t["predicted"], "k--", lw=1, label="predicted")
            if t["low"].notna().any():
                ax.fill_between(x, t["low"], t["high"], color="g", alpha=0.15,
                                label="tolerance")
        colours = {"pass": "tab:green", "fail": "tab:red", "inconclusive": "tab:orange"}
        for status, colour in colours.items():
            sel = np.asarray(t["verdict"] == status)
            if sel.any():
                ax.plot(x[sel], np.asarray(t["value"])[sel], "o", color=colour,
                        label=f"measured ({status} run)")
        ax.plot(x, t["value"], "-", color="0.5", lw=0.8)
        if not numeric:
            ax.set_xticks(x, [str(v) for v in t["x"]], rotation=30, ha="right")
        ax.set_xlabel(self.by.removeprefix("attr:"))
        ax.set_ylabel(f"{self.spec.label()}" + (f" ({units})" if units else ""))
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        return fig


def trend(store, spec, *, by: str = "run", **filters) -> Trend:
    """Follow one quantity across the runs.

    Parameters
    ----------
    store : Store
    spec : TrendSpec or str
        What to follow (a string is parsed by :meth:`TrendSpec.parse`).
    by : str
        'run' (analysis order), 'build', 'start_time', or 'attr:NAME' for a record attribute
        (numeric attributes give a numeric axis).
    **filters
        As :func:`list_runs`.

    Returns
    -------
    Trend
    """
    spec = TrendSpec.parse(spec) if isinstance(spec, str) else spec
    spec.validate()
    runs = list_runs(store, status="ok", **filters)
    if runs.empty:
        raise StoreError(f"{store.path}: no analysed runs match the filters")
    table, measured, predicted, unit = QUANTITIES[spec.quantity]
    where, params = [], []
    if spec.mode is not None:
        where.append("mode = ?")
        params.append(spec.mode)
    if spec.order is not None:
        where.append('abs("order" - ?) < 1e-6')
        params.append(spec.order)
    if spec.speed_rpm is not None:
        where.append("abs(speed_rpm - ?) < 1e-6")
        params.append(spec.speed_rpm)
    if spec.check is not None:
        where.append("lower(\"check\") LIKE ?")
        params.append(f"%{spec.check.lower()}%")
    rows = store.table(table, " AND ".join(where), params)
    if rows.empty:
        raise StoreError(f"{store.path}: no run has {spec.label()}")
    rows = rows.drop_duplicates("run_id", keep="first").set_index("run_id")
    out = []
    for _, run in runs.iterrows():
        if run.run_id not in rows.index:
            continue
        r = rows.loc[run.run_id]
        pred = r.get(predicted) if predicted else None
        low = high = None
        if spec.quantity == "critical_speed" and pred is not None and _finite(r.get(
                "speed_tolerance")):
            low, high = pred * (1 - r["speed_tolerance"]), pred * (1 + r["speed_tolerance"])
        out.append({"run_id": run.run_id, "record_name": run.record_name,
                    "x": _x_value(run, by, len(out)), "value": r.get(measured),
                    "predicted": pred, "low": low, "high": high,
                    "units": unit or r.get("units"), "verdict": run.verdict})
    import pandas as pd

    frame = pd.DataFrame(out, columns=["run_id", "record_name", "x", "value", "predicted", "low",
                                       "high", "units", "verdict"])
    for col in ("value", "predicted", "low", "high"):
        frame[col] = pd.to_numeric(frame[col], errors="coerce")
    if by != "run":
        try:
            frame["x"] = pd.to_numeric(frame["x"])
        except (ValueError, TypeError):
            pass
        frame = frame.sort_values("x", kind="stable", ignore_index=True)
    return Trend(spec=spec, by=by, table=frame)


def _finite(value) -> bool:
    try:
        return bool(np.isfinite(float(value)))
    except (TypeError, ValueError):
        return False


def _x_value(run, by: str, index: int):
    if by == "run":
        return index + 1
    if by in ("build", "start_time", "test_id", "engine_id"):
        return run[by]
    if by.startswith("attr:"):
        name = by[5:]
        attrs = json.loads(run["attrs"]) if isinstance(run["attrs"], str) else {}
        if name not in attrs:
            raise StoreError(f"run {run['record_name']!r} has no record attribute {name!r}; "
                             f"attributes: {', '.join(sorted(attrs)) or 'none'}")
        return attrs[name]
    raise StoreError(f"--by {by!r}: expected run, build, start_time, test_id, engine_id or "
                     "attr:NAME")
