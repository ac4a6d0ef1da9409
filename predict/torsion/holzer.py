"""The classical Holzer table of a torsional chain at a trial frequency.

References
----------
H. Holzer, *Die Berechnung der Drehschwingungen*, Springer, 1921; 内燃机动力学 (1958),
第二篇 第二章 §2 多质量振动系统.
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError

__all__ = ["holzer_table"]

TWO_PI = 2.0 * np.pi


def holzer_table(system, frequency_hz: float):
    """Classical Holzer table at a trial frequency (chains only).

    Starting with unit amplitude at the first mass (the free end of a grounded chain),
    each row gives the inertia torque J ω² θ, the cumulative torque in the following shaft
    and the twist ΣT/k. The residual torque (last row's ``torque_sum``) is zero at a
    natural frequency.

    Parameters
    ----------
    system : TorsionalSystem
        A chain (free or grounded).
    frequency_hz : float
        Trial frequency, Hz.

    Returns
    -------
    pandas.DataFrame
        Columns ``node``, ``inertia``, ``amplitude`` (rad), ``inertia_torque`` (N·m/rad of
        reference amplitude), ``torque_sum`` (N·m), ``stiffness`` (N·m/rad), ``twist`` (rad);
        ``attrs['residual']`` is the residual: the torque past the last mass (free chain,
        ``attrs['residual_torque']``, N·m per rad at the first mass) or the angle at the
        ground (grounded chain, marched from the free end, ``attrs['residual_amplitude']``).

    References
    ----------
    H. Holzer, *Die Berechnung der Drehschwingungen*, Springer, 1921; 内燃机动力学 (1958),
    第二篇 第二章 §2 多质量振动系统.

    Examples
    --------
    >>> from crankbench.predict.torsion import chain
    >>> from crankbench.predict.torsion.holzer import holzer_table
    >>> s = chain([1.0, 1.0], [1e4])
    >>> t = holzer_table(s, s.natural_frequencies()[1])
    >>> print(abs(t.attrs["residual_torque"]) < 1e-9)
    True
    """
    import pandas as pd

    from .._validate import check_nonnegative

    fr = check_nonnegative(frequency_hz, "frequency_hz", error=ModelError)
    kind, info = system._layout()
    if kind != "chain":
        raise ModelError("holzer_table: the system is branched; the Holzer table applies "
                         "to chains (use natural_frequencies() for trees)")
    order = info["nodes"][info["order"]]
    ks = np.asarray(info["chain_k"], float)
    grounded = info["grounded"]
    if grounded:
        # march from the free end towards the ground; the residual is the ground's angle
        order = order[::-1]
        ks = ks[::-1]
    w2 = (TWO_PI * fr) ** 2
    rows = []
    theta, tsum = 1.0, 0.0
    for idx, node in enumerate(order):
        jt = system._j[node] * w2 * theta
        tsum += jt
        k = ks[idx] if idx < len(ks) else np.nan
        twist = tsum / k if np.isfinite(k) else np.nan
        rows.append((system.node_names[node], system._j[node], theta, jt, tsum, k, twist))
        if np.isfinite(k):
            theta -= twist
    if grounded:
        rows.append(("ground", np.inf, theta, np.nan, np.nan, np.nan, np.nan))
    frame = pd.DataFrame(rows, columns=["node", "inertia", "amplitude", "inertia_torque",
                                        "torque_sum", "stiffness", "twist"])
    frame.attrs["frequency_hz"] = fr
    if grounded:
        frame.attrs["residual_amplitude"] = float(theta)
        frame.attrs["residual"] = float(theta)
    else:
        frame.attrs["residual_torque"] = float(tsum)
        frame.attrs["residual"] = float(tsum)
    return frame

