"""Running spans of a record that stops: their results joined into one (shared by the
in-memory trackers, :mod:`analysis.orders` / :mod:`analysis.ordermap`, and the streamed ones,
:mod:`analysis.stream`)."""

from __future__ import annotations

import logging

import numpy as np

from crankbench.predict.errors import AnalysisError

log = logging.getLogger("crankbench")


def join_running_spans(parts, skipped, stops, *, label, t0, fs):
    """The results of a record's running spans as one (along ``time``), with the standing
    spans in ``attrs['stopped_spans_s']`` (s); refused when no span could be analysed."""
    import xarray as xr

    if not parts:
        raise AnalysisError(f"{label}: no running span long enough to analyse: "
                            f"{'; '.join(skipped)}")
    if skipped:
        log.info("%s: running spans not analysed: %s", label, "; ".join(skipped))
    extra = {} if isinstance(parts[0], xr.DataArray) else {"data_vars": "minimal"}
    out = xr.concat(parts, dim="time", coords="minimal", combine_attrs="override",
                    **extra) if len(parts) > 1 else parts[0]
    out.attrs["stopped_spans_s"] = [v for a, b in stops for v in (t0 + a / fs,
                                                                  t0 + (b - 1) / fs)]
    return out


def running_spans(stops, n, *, t0, fs):
    """The sample spans ``[(a, b), ...]`` where the shaft turns, between the standing ``stops``
    of an ``n``-sample record, and the standing spans as text (s, the first five) for the
    warning that names them."""
    bounds = [0] + [v for s in stops for v in s] + [n]
    runs = [(a, b) for a, b in zip(bounds[0::2], bounds[1::2]) if b > a]
    shown = ", ".join(f"{t0 + a / fs:.6g}..{t0 + (b - 1) / fs:.6g} s" for a, b in stops[:5])
    return runs, shown


def stopped_spans(x, fs, speed_rpm):
    """Sample spans where the shaft stands (speed ≤ 0.5 % of the record's highest speed),
    when the record also runs; None if it runs throughout (or not at all)."""
    if np.isscalar(speed_rpm) or np.ndim(getattr(speed_rpm, "values", speed_rpm)) != 1:
        return None
    speed = np.asarray(getattr(speed_rpm, "values", speed_rpm), dtype=float)
    if speed.shape[0] == 0:
        return None
    lo, hi = float(speed.min()), float(speed.max())     # NaN/inf show in one or the other
    if not (np.isfinite(lo) and np.isfinite(hi)) or hi <= 0:
        return None
    if lo < 0:
        return None                       # reverse rotation: _as_rpm names it
    if lo > 5e-3 * hi:                    # running throughout (two passes, no masks)
        return None
    stopped = speed <= 5e-3 * hi
    edges = np.flatnonzero(np.diff(np.concatenate([[0], stopped.astype(np.int8), [0]])))
    return list(zip(edges[0::2], edges[1::2]))
