"""Residual shaking forces and moments estimated back from block and mount vibration.

Per engine order ``n`` every vibrograph block ``b`` of sensor ``s`` measures the complex order
amplitude ``a_sb``, the response of the mounted block to the order's loads at the reference
point on the crankshaft axis::

    a_sb = H_s(n Ω_b) · (Ω_b² u + L(Ω_b) g e_x)

with ``H_s`` the sensor's exact receptance row (quantity and direction, per unit force and
moment, :meth:`predict.mounts.MountedEngine.receptance`), ``u`` = (F_y, F_z, M_x, M_y, M_z)
per unit speed squared (inertia loads: the free forces and moments and the inertia part of
the torque reaction; the axial force of a crank train is zero) and ``g`` the gas-torque
reaction per unit load ``L`` (kept apart when the run's speeds and load law separate it from
``Ω² u_x``; otherwise one roll term). All blocks of all sensors enter one weighted least-squares
problem (weights: each block's 1-σ noise from the order track's broadband floor), solved in
real form with column scaling; its condition number says how well the sensors determine the
loads. The standard uncertainty is the covariance of the estimate scaled by the reduced χ²
of the fit when that exceeds 1 (model error and drifting phase count, never less than the
noise), propagated linearly to every reported magnitude.

At the report speed the loads become the balance model's rotating components
(:mod:`predict.balance`): forward ``P = (F_v + i F_h)/2`` and backward
``Q = conj(F_v − i F_h)/2`` of the force (vertical = z, horizontal = y), the same of the moment
(pitch = −M_y, yaw = M_z), each order's largest force ``|P| + |Q|``. With a tacho carrying a
TDC reference the phases refer to throw 1 (θ) and the deviation from the nominal residual is
the vector difference; an order-1 deviation is also given as the equivalent single unbalance
(kg·m, angle ahead of throw 1, axial position). Without one, magnitudes are compared.

Verdicts (:class:`analysis.verdict.Verdict`), per order for the force and for the moment:
the largest deviation over a revolution from the nominal residual of the balance model (with
the model's ``[[balance.mass]]``), ``|ΔP| + |ΔQ|``, against the largest deviation the
tolerances of :func:`predict.balance_tolerance.allowed_residuals` allow, ``T_P + T_Q``: pass
when deviation + 2σ is within it, fail when deviation − 2σ exceeds it, inconclusive between
(not required when the tolerance itself lies within the uncertainty, or when the order is
nominally balanced and the model states no tolerance).

References
----------
Liang Shoupan, *Engine Dynamics* (1948) ch. 4 (unbalanced forces on the foundation);
Zhao (ed.), *Engine Design* ch. 3 §2 (forward/backward rotating vectors); Bendat & Piersol,
*Random Data* (4th ed., 2010) §9.2 (uncertainty of least-squares estimates).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from crankbench.predict._threads import single_threaded_blas

__all__ = ["ResidualEstimate", "estimate_residuals"]

log = logging.getLogger("crankbench")

#: unknown load components (indices into (F_x, F_y, F_z, M_x, M_y, M_z)); F_x is zero
_COMPONENTS = (1, 2, 3, 4, 5)
_MAX_CONDITION = 1e8


@dataclass(frozen=True)
class ResidualEstimate:
    """Shaking forces and moments per order estimated from vibrograph records.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per order at ``speed_rpm``: estimated ``force_forward_n``,
        ``force_backward_n``, ``force_n`` (largest over a revolution, ``|P| + |Q|``),
        ``moment_forward_nm``, ``moment_backward_nm``, ``moment_nm``, ``roll_nm`` (torque
        reaction amplitude), each with its 1-σ ``*_unc``; the balance model's ``predicted_*``
        and the allowed ``tolerance_*`` (N, N·m); ``deviation_*`` (vector difference with a
        TDC reference, else difference of magnitudes), ``deviation_force_n`` and
        ``deviation_moment_nm`` (``|ΔP| + |ΔQ|``) against ``tolerance_force_n`` and
        ``tolerance_moment_nm``; ``condition`` (scaled least-squares
        problem), ``n_equations``, ``chi2_reduced``; for order 1 with a TDC reference the
        equivalent single unbalance ``unbalance_kgm``, ``unbalance_angle_deg`` (ahead of
        throw 1), ``unbalance_position_m`` with uncertainties; ``verdict_force``,
        ``verdict_moment``.
    verdicts : tuple of Verdict
    speed_rpm : float
        Speed of the reported forces and moments.
    phase_reference : str
    phasors : dict
        ``{order: {"force_forward": P, "force_backward": Q, "moment_forward": ...,
        "moment_backward": ..., "roll": ...}}`` complex, N and N·m at ``speed_rpm``.
    settings : dict
    """

    table: object
    verdicts: tuple
    speed_rpm: float
    phase_reference: str
    phasors: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)

    def to_frame(self):
        """The per-order table (copy)."""
        return self.table.copy()

    def summary(self) -> dict:
        """Report speed, phase reference, orders and the combined verdict."""
        from .verdict import combine

        return {"speed_rpm": self.speed_rpm, "phase_reference": self.phase_reference,
                "orders": [int(o) for o in self.table["order"]],
                "verdict": combine(self.verdicts, name="residuals").status}

    def plot(self, ax=None):
        """Estimated (with ±2σ bars) and predicted force and moment per order; returns the
        figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, axes = plt.subplots(1, 2, figsize=(9, 3.5))
        else:
            fig = ax.figure
            axes = [ax, ax.twinx()]
        t = self.table
        x = np.arange(len(t))
        for a, key, unit in ((axes[0], "force", "N"), (axes[1], "moment", "N m")):
            for k, part in enumerate(("forward", "backward")):
                est = t[f"{key}_{part}_{'n' if key == 'force' else 'nm'}"].to_numpy(float)
                unc = t[f"{key}_{part}_unc_{'n' if key == 'force' else 'nm'}"].to_numpy(float)
                pred = t[f"predicted_{key}_{part}_{'n' if key == 'force' else 'nm'}"]
                off = -0.2 + 0.4 * k
                a.errorbar(x + off, est, yerr=2 * unc, fmt="o", ms=4, capsize=3,
                           label=f"{part} measured ±2σ")
                a.plot(x + off, pred, "_", ms=14, mew=2, label=f"{part} predicted")
            a.set_xticks(x, [f"{o:g}" for o in t["order"]])
            a.set_xlabel("order")
            a.set_ylabel(f"{key} ({unit}) at {self.speed_rpm:.0f} rpm")
            a.legend(fontsize=7)
        return fig


def _real_form(a):
    """Complex (N, p) -> real (2N, 2p) acting on [Re x, Im x]."""
    return np.block([[a.real, -a.imag], [a.imag, a.real]])


def _combo(l_row, x, cov):
    """Value, 2x2 covariance of a complex linear combination ``l_row @ x``."""
    lr = np.block([[l_row.real, -l_row.imag], [l_row.imag, l_row.real]])
    y = complex(l_row @ x)
    return y, lr @ cov @ lr.T


def _mag_unc(y, c):
    """1-σ of |y| from the 2x2 covariance of (Re y, Im y)."""
    m = abs(y)
    if m <= 1e-12 * np.sqrt(max(np.trace(c), 1e-300)):
        return float(np.sqrt(np.trace(c) / 2.0))
    g = np.array([y.real, y.imag]) / m
    return float(np.sqrt(max(g @ c @ g, 0.0)))


def _judge(name, dev, unc, tol, *, basis, required):
    from .verdict import Verdict

    rule = ("largest deviation over a revolution (|ΔP| + |ΔQ|) from the balance model's "
            "residual within the largest the tolerances allow (±2σ decides)")
    if not np.isfinite(dev):
        return Verdict.inconclusive(name, rule=rule, basis=basis, reason="not determined by "
                                    "the sensors", required=False)
    if tol <= 0:
        return Verdict.inconclusive(name, rule=rule, basis=basis, required=False,
                                    reason="nominal residual zero and the model states no "
                                           "manufacturing tolerance ([balance])")
    if dev + 2 * unc <= tol:
        return Verdict.passed(name, rule=rule, basis=basis,
                              reason=f"deviation {dev:.3g} ± {2 * unc:.2g} <= {tol:.3g}",
                              required=required)
    if dev - 2 * unc > tol:
        return Verdict.failed(name, rule=rule, basis=basis, required=required,
                              reason=f"deviation {dev:.3g} ± {2 * unc:.2g} > {tol:.3g}")
    if tol <= 4 * unc:
        # a tolerance inside the measurement's uncertainty cannot be decided either way
        return Verdict.inconclusive(name, rule=rule, basis=basis, required=False,
                                    reason=f"tolerance {tol:.3g} is within the estimate's "
                                           f"uncertainty (2σ = {2 * unc:.2g}): more sensors, "
                                           "less noise or a higher speed would decide it")
    return Verdict.inconclusive(name, rule=rule, basis=basis, required=required,
                                reason=f"deviation {dev:.3g} ± {2 * unc:.2g} straddles the "
                                       f"tolerance {tol:.3g}")


def _solve(rows, data, sigma):
    """Weighted real least squares: ((x complex, covariance (2p, 2p) of [Re, Im], condition,
    chi2_reduced), condition), the first None when the sensors do not determine x."""
    a = _real_form(rows / sigma[:, None])
    y = np.concatenate([(data / sigma).real, (data / sigma).imag])
    p = rows.shape[1]
    if a.shape[0] <= a.shape[1]:
        return None, float("inf")
    scale = np.linalg.norm(a, axis=0)
    if np.any(scale <= 0):
        return None, float("inf")
    sv = np.linalg.svd(a / scale, compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    if not cond < _MAX_CONDITION:
        return None, cond
    z, *_ = np.linalg.lstsq(a / scale, y, rcond=None)
    resid = y - (a / scale) @ z
    dof = a.shape[0] - a.shape[1]
    chi2 = float(resid @ resid / dof)
    pinv = np.linalg.pinv((a / scale).T @ (a / scale))
    cov = max(chi2, 1.0) * pinv / np.outer(scale, scale)
    xr = z / scale
    return (xr[:p] + 1j * xr[p:], cov, cond, chi2), cond


@single_threaded_blas  # small least-squares solves: BLAS threads only cost (issue 21)
def estimate_residuals(blocks, channels, orders, loads, engine, spec, *, phase,
                       residual_orders, speed_rpm=None, excitation_has_gas=True):
    """Estimate per-order shaking forces and moments from vibrograph order tracks.

    Parameters
    ----------
    blocks : dict
        Per channel: ``rpm`` (n_b), ``measured`` (n_o, n_b) complex order amplitudes,
        ``noise`` (n_b) 1-σ per real component, ``h`` (n_o, n_b, 6) measured quantity per
        unit load (F_x..M_z at ``loads.point``), ``load`` (n_b) gas-load factor — as built by
        :func:`analysis.vibrograph.compare_vibrograph`.
    channels : sequence of str
    orders : ndarray
        Orders of the tracks.
    loads : predict.mounts.BlockExcitation
        The model's loads (for the predicted torque reaction).
    engine : predict.engine.Engine
    spec : predict.balance_tolerance.BalanceSpec
    phase : dict
        Per channel ``(e^{i delta_b} or None, description)``: the TDC reference per block.
    residual_orders : sequence of int
    speed_rpm : float, optional
        Report speed (default: the highest block speed).
    excitation_has_gas : bool

    Returns
    -------
    ResidualEstimate

    Examples
    --------
    A 5 g mass at 60 mm, 30° ahead of throw 1 in the plane x = 0.1 m, added to a balanced
    in-line four: noise-free order-1 amplitudes at six sensors, 20 blocks 2000-3000 rpm:

    >>> from crankbench.predict.balance import Counterweight
    >>> from crankbench.predict.balance_tolerance import BalanceSpec
    >>> from crankbench.predict.engine import Engine
    >>> from crankbench.predict.mounts import MountedEngine, block_excitation, direction_vector
    >>> e = Engine.from_toml("sample_data/engines/i4.toml")
    >>> m = MountedEngine.from_toml("sample_data/engines/i4.toml")
    >>> true = block_excitation(e, [1.0], counterweights=[Counterweight(3e-4, 30.0, 0.1)])
    >>> w = np.linspace(2000, 3000, 20) * np.pi / 30
    >>> blocks = {}
    >>> for i, (p, d) in enumerate([([-.1, .25, .15], "z"), ([-.1, .25, .15], "y"),
    ...                             ([.55, -.2, .15], "z"), ([.55, -.2, .15], "y"),
    ...                             ([.2, 0, -.25], "y"), ([.3, 0, .3], "x")]):
    ...     h = m.receptance(w / (2 * np.pi), at=[p], directions=[direction_vector(d)],
    ...                      point=true.point)[:, 0, :][None] * -(w**2)[None, :, None]
    ...     blocks[f"s{i}"] = dict(rpm=w * 30 / np.pi, h=h, noise=np.full(20, 1e-3),
    ...                            measured=np.einsum("bj,bj->b", h[0], true.at(w)[:, 0])[None],
    ...                            load=np.ones(20))
    >>> est = estimate_residuals(blocks, list(blocks), np.array([1.0]),
    ...                          block_excitation(e, [1.0]), e, BalanceSpec(),
    ...                          phase={c: (np.ones(20), "exact") for c in blocks},
    ...                          residual_orders=[1], excitation_has_gas=False)
    >>> r = est.table.iloc[0]
    >>> [round(float(r[k]), 4) for k in ("unbalance_kgm", "unbalance_angle_deg",
    ...                                  "unbalance_position_m", "force_forward_n")]
    [0.0003, 30.0, 0.1, 29.6088]
    """
    import pandas as pd

    from crankbench.predict.balance_tolerance import allowed_residuals

    absolute = all(phase[c][0] is not None for c in channels)
    reference = phase[channels[0]][1] if absolute else next(
        (phase[c][1] for c in channels if phase[c][0] is None), "relative")
    all_rpm = np.concatenate([blocks[c]["rpm"] for c in channels])
    ref_rpm = float(speed_rpm) if speed_rpm is not None else float(all_rpm.max())
    w_ref = ref_rpm * np.pi / 30.0
    ref_load = float(np.interp(ref_rpm, *_sorted(blocks, channels)))
    nominal = allowed_residuals(engine, spec, omega=w_ref, orders=residual_orders)
    tolerance = nominal["tolerance"]
    ds = nominal["nominal"]
    round_off = nominal["round_off"]
    theta_f = float(engine.firing_tdc_shaft_angle)
    rows_out, verdicts, phasors = [], [], {}
    basis = (f"{len(channels)} vibrograph channels ({', '.join(channels)}); loads per unit "
             f"speed² estimated over all blocks; phases: {reference}")
    for i, n in enumerate(residual_orders):
        hit = np.flatnonzero(np.isclose(orders, n))
        row = {"order": int(n), "speed_rpm": ref_rpm}
        if hit.size == 0:
            continue
        k = int(hit[0])
        mats, data, sig, w2, lf = [], [], [], [], []
        for c in channels:
            b = blocks[c]
            meas = b["measured"][k]
            ref = phase[c][0]
            if absolute:
                meas = meas * np.conj(ref / np.abs(ref)) ** n
            mats.append(b["h"][k])
            data.append(meas)
            sig.append(b["noise"])
            w2.append((b["rpm"] * np.pi / 30.0) ** 2)
            lf.append(b["load"])
        h = np.concatenate(mats)
        data = np.concatenate(data)
        sig = np.concatenate(sig)
        w2 = np.concatenate(w2)
        lf = np.concatenate(lf)
        sig = np.maximum(sig, 1e-3 * np.median(sig))
        cols = [h[:, j] * w2 for j in _COMPONENTS]
        gas_apart = False
        if excitation_has_gas and np.ptp(w2) > 0:
            cosang = abs(w2 @ lf) / (np.linalg.norm(w2) * np.linalg.norm(lf))
            gas_apart = cosang < 0.999
        if gas_apart:
            cols.append(h[:, 3] * lf)
        out, cond = _solve(np.column_stack(cols), data, sig)
        row.update(condition=cond, n_equations=int(data.size))
        if out is None:
            log.info("order %d: residual loads not determined by the sensors (condition %.3g)",
                     n, cond)
            for name in ("force", "moment"):
                verdicts.append(_judge(f"residual {name} order {n}", float("nan"), 0.0, 0.0,
                                       basis=basis, required=False))
                row[f"verdict_{name}"] = "inconclusive"
            rows_out.append(row)
            continue
        x, cov, cond, chi2 = out
        row.update(chi2_reduced=chi2)
        p = x.size
        # linear maps from the unknowns to the phasors at the report speed (theta reference)
        rot = np.exp(-1j * n * theta_f) if absolute else 1.0

        def lin(coef):
            row_l = np.zeros(p, complex)
            for j, v in coef.items():
                row_l[j] = v
            return row_l

        fy, fz, mx, my, mz = range(5)
        s2 = w_ref**2
        maps = {
            "force_forward": lin({fz: 0.5 * s2 * rot, fy: 0.5j * s2 * rot}),
            "force_backward_conj": lin({fz: 0.5 * s2 * rot, fy: -0.5j * s2 * rot}),
            "moment_forward": lin({my: -0.5 * s2 * rot, mz: 0.5j * s2 * rot}),
            "moment_backward_conj": lin({my: -0.5 * s2 * rot, mz: -0.5j * s2 * rot}),
            "roll": lin({mx: s2, **({5: ref_load} if gas_apart else {})}),
        }
        # the phasor Q is the conjugate of the map (same magnitude; its covariance mirrored)
        values, covs = {}, {}
        for key, l_row in maps.items():
            y, c = _combo(l_row, x, cov)
            if key.endswith("_conj"):
                key = key[:-5]
                y = np.conj(y)
                c = c * np.array([[1.0, -1.0], [-1.0, 1.0]])
            values[key], covs[key] = y, c
        phasors[int(n)] = dict(values)
        nom = {}
        for key in ("force_forward", "force_backward", "moment_forward", "moment_backward"):
            value = complex(ds[f"{key}_phasor"].values[i])
            level = round_off["force" if key.startswith("force") else "moment"]
            nom[key] = value if abs(value) > level else 0j      # round-off of the sums: zero
        pred_roll = abs(loads.inertia[k, 3] * w_ref**2 + loads.gas[k, 3] * ref_load)
        roll_scale = np.abs(loads.inertia[:, 3] * w_ref**2 + loads.gas[:, 3] * ref_load).max()
        pred_roll = pred_roll if pred_roll > 1e-9 * roll_scale else 0.0
        for key in ("force_forward", "force_backward", "moment_forward", "moment_backward"):
            unit = "n" if key.startswith("force") else "nm"
            y, c = values[key], covs[key]
            row[f"{key}_{unit}"] = abs(y)
            row[f"{key}_unc_{unit}"] = _mag_unc(y, c)
            row[f"predicted_{key}_{unit}"] = abs(nom[key])
            row[f"tolerance_{key}_{unit}"] = float(tolerance[key][i])
            if absolute:
                d = y - nom[key]
                row[f"deviation_{key}_{unit}"] = abs(d)
                row[f"deviation_{key}_unc_{unit}"] = _mag_unc(d, c)
            else:
                row[f"deviation_{key}_{unit}"] = abs(abs(y) - abs(nom[key]))
                row[f"deviation_{key}_unc_{unit}"] = row[f"{key}_unc_{unit}"]
        row["force_n"] = row["force_forward_n"] + row["force_backward_n"]
        row["moment_nm"] = row["moment_forward_nm"] + row["moment_backward_nm"]
        row["roll_nm"] = abs(values["roll"])
        row["roll_unc_nm"] = _mag_unc(values["roll"], covs["roll"])
        row["predicted_roll_nm"] = pred_roll
        if n == 1 and absolute:
            row.update(_equivalent_unbalance(maps, x, cov, nom, w_ref,
                                             float(engine.reference_position)))
        for name in ("force", "moment"):
            # the largest deviation over a revolution, |ΔP| + |ΔQ|, against the largest
            # allowed, T_P + T_Q (both worst cases)
            unit = "n" if name == "force" else "nm"
            dev = sum(row[f"deviation_{name}_{part}_{unit}"] for part in ("forward", "backward"))
            unc = float(np.hypot(*(row[f"deviation_{name}_{part}_unc_{unit}"]
                                   for part in ("forward", "backward"))))
            tol = sum(row[f"tolerance_{name}_{part}_{unit}"] for part in ("forward", "backward"))
            row[f"deviation_{name}_{unit}"] = dev
            row[f"deviation_{name}_unc_{unit}"] = unc
            row[f"tolerance_{name}_{unit}"] = tol
            v = _judge(f"residual {name} order {n}", dev, unc, tol, basis=basis,
                       required=tol > 0)
            verdicts.append(v)
            row[f"verdict_{name}"] = v.status
        rows_out.append(row)
    table = pd.DataFrame(rows_out)
    settings = {"components": "F_y, F_z, M_x, M_y, M_z per unit speed squared (F_x = 0); gas "
                              "roll apart when separable",
                "report speed (rpm)": ref_rpm, "phase reference": reference,
                "uncertainty": "1-σ, covariance × max(1, reduced χ²)",
                "tolerance": "balance model nominal ± manufacturing tolerances "
                             "(predict.balance_tolerance)"}
    return ResidualEstimate(table=table, verdicts=tuple(verdicts), speed_rpm=ref_rpm,
                            phase_reference=reference, phasors=phasors, settings=settings)


def _sorted(blocks, channels):
    rpm = np.concatenate([blocks[c]["rpm"] for c in channels])
    lf = np.concatenate([blocks[c]["load"] for c in channels])
    k = np.argsort(rpm)
    return rpm[k], lf[k]


def _equivalent_unbalance(maps, x, cov, nominal, omega, z_ref):
    """Order-1 deviation as one unbalance: m·r (kg·m), angle ahead of throw 1, position."""
    pf = complex(maps["force_forward"] @ x) - nominal["force_forward"]
    pm = complex(maps["moment_forward"] @ x) - nominal["moment_forward"]
    _, c = _combo(maps["force_forward"], x, cov)
    mr = abs(pf) / omega**2
    out = {"unbalance_kgm": mr, "unbalance_unc_kgm": _mag_unc(pf, c) / omega**2,
           "unbalance_angle_deg": float(np.degrees(np.angle(pf)) % 360.0)}
    if abs(pf) > 0:
        g = np.array([-pf.imag, pf.real]) / abs(pf)
        out["unbalance_angle_unc_deg"] = float(np.degrees(np.sqrt(max(g @ c @ g, 0.0))
                                                         / abs(pf)))
        # position z_ref + Re(P_M / P_F): linearised through the real unknowns
        p = x.size

        def pos(xr):
            xc = xr[:p] + 1j * xr[p:]
            f = complex(maps["force_forward"] @ xc) - nominal["force_forward"]
            m = complex(maps["moment_forward"] @ xc) - nominal["moment_forward"]
            return (m / f).real

        xr = np.concatenate([x.real, x.imag])
        step = 1e-6 * max(np.abs(xr).max(), 1e-300)
        grad = np.array([(pos(xr + step * e) - pos(xr - step * e)) / (2 * step)
                         for e in np.eye(xr.size)])
        out["unbalance_position_m"] = z_ref + (pm / pf).real
        out["unbalance_position_unc_m"] = float(np.sqrt(max(grad @ cov @ grad, 0.0)))
    return out
