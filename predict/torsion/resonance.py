"""Resonance amplitudes at the critical speeds: the exact damped solve, with the classical
energy-balance estimate beside it.

The headline value (``amplitude_deg``) is the peak of the exact damped harmonic solve; the
energy balance (``energy_balance_deg``) is the textbook estimate, kept for comparison with hand
calculations and reports that quote it. With a damper the two can differ widely: on the
sample 6L32 shaft line (``sample_data/shaftlines/marine_6l.toml``, viscous damper at the free
end) the energy balance lies 28-38 % below the exact value on the damped third mode (checked
by ``tests/predict/test_resonance_headline.py``).

Energy balance (classical, one mode): at resonance the work the order-q excitation does per
cycle on mode a (mass-normalised, amplitude scale A) equals the work the dampers dissipate,

``π A |aᵀF| = π A² (ω aᵀ C a + aᵀ K_η a)``  ⇒  ``A = |aᵀF| / (ω aᵀ C a + aᵀ K_η a)``,

where F holds the cylinders' order-q torque phasors (so aᵀF is the phase-vector sum times the
harmonic torque), C the viscous and K_η = η∘K the hysteretic damping. The dynamic magnifier is
the resonant over the static modal amplitude, ``M = ω² / (ω aᵀCa + aᵀK_η a)`` (= 1/2ζ).

Nodes left out of the undamped eigen-analysis (rings of viscous and friction dampers,
centrifugal pendulums) have zero modal amplitude: a damper ring is thus taken as standing still
(the classical seismic-ring assumption, an upper bound of its damping, so the energy balance
under-estimates the amplitude) and a pendulum's tuning is ignored. The exact solve includes
them; the difference shows in ``method_error``.

The exact value is the peak of the full damped harmonic solve of that order near the critical
speed (:func:`predict.torsion.forced.harmonic_solve`; two grid passes of 61 speeds, relative
speed resolution ≈ 1e-5). The relative difference is the energy-balance method error (mode
coupling by damping, other modes' contribution, shift of the peak); it is reported per row.

References
----------
.. [1] 交通大学内燃机教研组, 内燃机动力学、构造与计算 (上册), 1958, 第二篇 第四章 §2 共振扭幅
   (能量法).
.. [2] J. P. Den Hartog, *Mechanical Vibrations*, 4th ed., McGraw-Hill, 1956, ch. 5 (energy
   method for resonant amplitudes of engine shafts; dynamic magnifier).
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError
from .forced import cylinder_forcing, harmonic_solve, stress_factor

__all__ = ["resonance_amplitudes"]

TWO_PI = 2.0 * np.pi


def resonance_amplitudes(system, *, torque=None, orders=None, speed_range_rpm=None,
                         imep=None, misfire=None, min_vector_sum=0.0):
    """Resonant amplitudes at every critical speed by energy balance and by the exact solve.

    Parameters
    ----------
    system : TorsionalSystem
    torque : Excitation or callable or array_like, optional
        An :class:`~predict.torsion.excitation.Excitation` (default: the engine's), or a
        callable ``torque(order, speed_rad_s) -> complex`` giving one cylinder's harmonic, N·m.
    orders : array_like, optional
    speed_range_rpm : (float, float), optional
    imep : float, optional
        Pa, for the default excitation.
    misfire : int, optional
        Cylinder (1-based) without gas torque.
    min_vector_sum : float
        Skip criticals whose relative vector sum is below this (minor orders of little effect).

    Returns
    -------
    pandas.DataFrame
        Columns ``mode``, ``order``, ``speed_rpm`` (undamped critical speed), ``vector_sum``,
        ``node`` (largest modal amplitude), ``amplitude_deg`` (the headline: peak vibratory
        angle of the exact damped solve at ``node``, deg, single amplitude),
        ``amplitude_speed_rpm`` (speed of that peak), ``energy_balance_deg`` (classical
        estimate), ``method_error`` ((EB − exact)/exact), ``dynamic_magnifier``,
        ``max_stress_mpa``, ``section``; ``exact_deg`` and ``exact_speed_rpm`` repeat the
        headline under their former names.

    Examples
    --------
    >>> import numpy as np
    >>> from crankbench.predict.torsion import chain
    >>> s = chain([1.0, 1.0], [1e4]).replace(
    ...     cylinder_nodes=[0], firing_angles_deg=[0.0], edge_damping=[1.0])
    >>> t = resonance_amplitudes(s, torque=lambda q, w: 10.0, orders=[2.0])
    >>> print(float(t.method_error.abs().iloc[0]) < 0.01)
    True
    """
    import logging

    import pandas as pd

    if system.friction_dampers:
        logging.getLogger("crankbench").warning(
            "resonance_amplitudes: the non-linear friction ring(s) %s are not in this linear "
            "table; their response is predict.torsion.friction_forced_response",
            ", ".join(repr(d.name) for d in system.friction_dampers))
    if torque is None:
        from .excitation import engine_excitation

        torque = engine_excitation(system, imep=imep if imep is not None
                                   else system.operating.get("imep"))
    crit = system.critical_speeds(orders, speed_range_rpm)
    omega_n, shapes, numbers, _, _ = system._eigen
    sf = stress_factor(system)
    e = system.edges
    rows = []
    for _, row in crit.iterrows():
        if np.isfinite(row.vector_sum) and row.vector_sum < min_vector_sum:
            continue
        i = int(np.flatnonzero(numbers == row["mode"])[0])
        a = shapes[:, i]
        w = omega_n[i]
        q = float(row.order)
        speed_c = w / q

        def forcing(speeds):
            if callable(torque) and not hasattr(torque, "harmonics"):
                h = np.array([[torque(q, s)] for s in speeds], complex)
            else:
                h = torque.harmonics(speeds, [q], misfire=misfire)
            return cylinder_forcing(system, h, np.array([q]), len(speeds))

        f = forcing(np.array([speed_c]))[0, 0]
        c_mat = system.damping_matrix(None)
        keta = system._laplacian(system.stiffnesses * system.edge_loss_factor)
        dissip = w * a @ c_mat @ a + a @ keta @ a
        if dissip <= 0:
            raise ModelError(f"mode {row['mode']} has no damping: the resonant amplitude is "
                             "unbounded; give absolute, relative or hysteretic damping")
        amp_scale = abs(a @ f) / dissip
        ref = int(np.argmax(np.abs(a * system.node_ratio)))
        eb = amp_scale * abs(a[ref]) * abs(system.node_ratio[ref])
        magnifier = w * w / dissip
        # exact: peak of the damped solve of this order near the critical speed
        zeta = dissip / (2 * w * w)  # modal damping ratio
        half = min(max(8 * zeta, 2e-3), 0.5)
        lo, hi = speed_c * (1 - half), speed_c * (1 + half)
        best = speed_c
        for _pass in range(3):
            grid = np.linspace(lo, hi, 61)
            x = harmonic_solve(system, grid, [q], forcing(grid))[:, 0, :]
            amp = np.abs(x[:, ref]) * abs(system.node_ratio[ref])
            k = int(np.argmax(amp))
            best = grid[k]
            step = grid[1] - grid[0]
            lo, hi = best - 2 * step, best + 2 * step
        exact = float(amp[k])
        xb = x[k, e[:, 1]]
        xa = np.where(e[:, 0] >= 0, x[k, np.maximum(e[:, 0], 0)], 0.0)
        wq = best * q
        zk = (system.stiffnesses * (1 + 1j * system.edge_loss_factor)
              + system.edge_stiffness_omega2 * best ** 2 + 1j * wq * system.edge_damping)
        stress = np.abs(zk * (xb - xa) / system.edge_ratio) * sf
        if np.all(np.isnan(stress)):
            smax, sec = np.nan, ""
        else:
            j = int(np.nanargmax(stress))
            smax, sec = stress[j] / 1e6, system.edge_names[j]
        rows.append(dict(mode=int(row["mode"]), order=q, speed_rpm=float(row.speed_rpm),
                         vector_sum=float(row.vector_sum), node=system.node_names[ref],
                         amplitude_deg=float(np.rad2deg(exact)),
                         amplitude_speed_rpm=float(best * 60 / TWO_PI),
                         energy_balance_deg=float(np.rad2deg(eb)),
                         exact_deg=float(np.rad2deg(exact)),
                         exact_speed_rpm=float(best * 60 / TWO_PI),
                         method_error=float((eb - exact) / exact) if exact > 0 else np.nan,
                         dynamic_magnifier=float(magnifier), max_stress_mpa=float(smax),
                         section=sec))
    frame = pd.DataFrame(rows, columns=["mode", "order", "speed_rpm", "vector_sum", "node",
                                        "amplitude_deg", "amplitude_speed_rpm",
                                        "energy_balance_deg", "method_error",
                                        "dynamic_magnifier", "max_stress_mpa", "section",
                                        "exact_deg", "exact_speed_rpm"])
    frame.attrs["method"] = ("amplitude_deg: exact damped harmonic solve (headline); "
                             "energy_balance_deg: classical single-mode energy balance beside "
                             "it, method_error = (EB − exact)/exact")
    return frame
