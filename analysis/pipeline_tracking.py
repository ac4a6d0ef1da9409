"""Order tracking inside the end-to-end chain (:func:`analysis.pipeline.analyse`, step 2):
the tracker call for the chosen method and the settings (and why) for the report and --json.
"""

from __future__ import annotations

import numpy as np

__all__: list[str] = []     # helpers of analysis.pipeline


def _track(x, fs, rpm, orders, *, method, bandwidth_orders, revolutions):
    from .orders import order_track

    if method == "auto":
        # the tracker's own choice, but never narrower than resonance identification needs
        return order_track(x, fs=fs, speed_rpm=rpm, orders=orders, method="auto",
                           min_bandwidth_orders=bandwidth_orders)
    if method == "vkf":
        return order_track(x, fs=fs, speed_rpm=rpm, orders=orders, method="vkf",
                           bandwidth_orders=bandwidth_orders)
    return order_track(x, fs=fs, speed_rpm=rpm, orders=orders, method="cot",
                       revolutions=revolutions,
                       overlap=0.9)


def _tracking_settings(track, method, bandwidth_orders, revolutions) -> dict:
    """The order tracker's settings, and why, for the report and --json."""
    if method == "auto":
        rng = track.attrs.get("auto_bandwidth_hz_range", [float("nan")] * 2)
        err = track.attrs.get("auto_expected_error", [])
        orders = track["order"].values
        return {"VKF bandwidth (Hz, chosen from the record)": f"{rng[0]:.3g} – {rng[1]:.3g}",
                "tracking settings (auto)": track.attrs.get("auto_settings", ""),
                "expected amplitude error (max, per order)": ", ".join(
                    f"{o:g}: {100 * e:.2g} %" for o, e in zip(orders, err)),
                "window": "— (VKF)"}
    if method == "vkf":
        return {"VKF bandwidth (orders)": bandwidth_orders,
                "order resolution": f"{bandwidth_orders:g} orders (−3 dB)", "window": "— (VKF)",
                "bandwidth chosen because": "sweep rate R: 0.25 orders up to 25 rpm/s, then "
                                            "0.25·√(R/25) up to 0.5 (a resonance crossed fast "
                                            "needs a wider filter to keep its peak)",
                "expected amplitude error (max, per order)": ", ".join(
                    f"{o:g}: ±{np.nanmax(u):.3g}" for o, u in zip(
                        track["order"].values, track["amplitude_uncertainty"].values))
                if "amplitude_uncertainty" in track else "—"}
    return {"COT block (revolutions)": revolutions, "order resolution": f"{1 / revolutions:g} "
            "orders", "window": track.attrs.get("window", "hann")}
