"""Time-domain torsional response of a shaft line through resonances, with the damping model of
the prediction.

The prediction (:func:`predict.torsion.forced_response`) solves ``(K(1 + i eta) - w**2 J +
i w C) x = f`` in the frequency domain: hysteretic loss factors ``eta`` of shafts and couplings
beside viscous dampers. Hysteretic damping has no exact causal time-domain form, so a record
cannot be integrated with it directly. The synthesis therefore splits each order's response
into

``x(t) = X_ss(Omega(t)) e^{i q psi(t)} + sum_j v_j (z_j(t) - z_j,ss(t))``:

* **the steady-state part** ``X_ss``: the exact harmonic solve of the prediction
  (:func:`predict.torsion.forced.harmonic_solve`, the very damping model, speed-dependent
  springs included) tabulated on a geometric speed grid fine enough for the sharpest resonance
  and interpolated by cubic splines (the interpolation error is measured at the grid midpoints
  and reported). At constant speed the record *is* the prediction.
* **the sweep transient** of every mode the orders sweep through: complex modal coordinates
  ``z_j' = lambda_j z_j + b_j c(t) e^{i q psi(t)}`` minus their quasi-static value
  ``z_j,ss = b_j c e^{i q psi} / (i q Omega - lambda_j)``; the difference is zero at constant
  speed and carries the lag, loss and ringing of a finite sweep. Each mode's pole, input and
  shape come from the shaft line with its hysteretic damping turned into the viscous
  ``eta k / w`` at *that mode's own* natural frequency (``TorsionalSystem.damping_matrix(w)``,
  iterated to the fixed point ``w = |lambda_j|``), so every mode decays with the damping the
  prediction gives it at its resonance. (A single viscous matrix tuned at one mode - the
  former scheme, :func:`equivalent_viscous_system` - over-damps the modes above that one:
  mode 4 of the I4 scene had zeta 0.096 against 0.050.)

Over one step ``h`` the forcing is taken as ``c e^{i(q psi_k + omega_k s)}`` (exponential hold:
``omega_k`` from the exact phase increment, ``c`` at the step's middle), which the recurrence

``z_{k+1} = e^{lambda h} z_k + c e^{i q psi_k} h e^{lambda h} phi_1((i omega_k - lambda) h)``,
``phi_1(x) = (e^x - 1)/x``,

integrates *exactly* for constant speed and force, whatever the ratio of the order frequency or
the natural frequency to the sample rate; during a sweep the remaining error is the change of
``c`` and ``omega`` within one step (relative ``h |d ln c/dt|`` and ``q alpha h**2 / 2`` rad
of phase). The recurrence is a first-order IIR filter per mode (``scipy.signal.lfilter``)
started at the steady state of the initial speed, so there is no start-up transient. For a
purely viscous shaft line the split is an identity: the sum over all modes of the
quasi-static modal parts is the exact harmonic solve, and the response equals the plain modal
integration (checked against ``solve_ivp``).

Because each order is integrated separately, the response per order (its complex envelope) is
available along the run: the ground truth of the order amplitudes, including the transient
effects of a fast sweep.

References
----------
Jiaotong University, *IC-engine dynamics* (内燃机动力学), 1958, part 2 ch. 4 §3 (resonance
curves: amplitude through a critical speed).
Liang Shoupan, *Engine dynamics* (發動機動力學), 1948, ch. 7 (vibration of the crankshaft).
Crandall, S. H., "The role of damping in vibration theory", J. Sound Vib. 11 (1970) 3-18
(hysteretic damping is non-causal; equivalent viscous damping at one frequency).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from crankbench.predict.errors import ConfigError, ModelError
from crankbench.predict._deprecate import renamed

__all__ = ["ModalModel", "equivalent_viscous_system", "order_forcing"]

log = logging.getLogger("crankbench")

TWO_PI = 2.0 * np.pi


def _hysteretic_frequencies(system):
    """Natural frequency (rad/s) of the undamped mode straining each edge the most."""
    from scipy.linalg import eigh

    k = system.stiffness_matrix()
    m = system.inertia_matrix()
    w2, phi = eigh(k, m)
    w = np.sqrt(np.maximum(w2, 0.0))
    e = system.edges
    a = np.where((e[:, 0] >= 0)[:, None], phi[np.maximum(e[:, 0], 0), :], 0.0)
    twist = phi[e[:, 1], :] - a                               # (edges, modes)
    energy = system.stiffnesses[:, None] * twist**2
    modal = np.maximum(np.einsum("im,ij,jm->m", phi, k, phi), 1e-300)
    share = energy / modal[None, :]
    elastic = w > 1e-6 * max(w.max(), 1.0)
    share[:, ~elastic] = -1.0
    best = np.argmax(share, axis=1)
    out = w[best]
    out[~elastic.any() | (out <= 0)] = np.nan
    return out


def equivalent_viscous_system(system):
    """The shaft line with each hysteretic loss factor replaced by its equivalent viscous damping.

    ``c_e = eta_e k_e / omega_e`` with ``omega_e`` the natural frequency of the undamped mode in
    which spring ``e`` holds the largest share of the strain energy.

    Parameters
    ----------
    system : predict.torsion.TorsionalSystem

    Returns
    -------
    predict.torsion.TorsionalSystem
        Same system, ``edge_loss_factor`` zero and ``edge_damping`` increased.

    Examples
    --------
    >>> from crankbench.predict.torsion import chain
    >>> s = chain([1.0, 1.0], [1e4]).replace(edge_loss_factor=[0.1])
    >>> v = equivalent_viscous_system(s)
    >>> round(float(v.edge_damping[0]), 4)           # 0.1 * 1e4 / sqrt(2e4)
    7.0711
    """
    eta = np.asarray(system.edge_loss_factor, float)
    if not np.any(eta):
        return system
    w = _hysteretic_frequencies(system)
    extra = np.where(eta > 0, eta * system.stiffnesses / np.where(np.isfinite(w), w, 1.0), 0.0)
    if np.any((eta > 0) & ~np.isfinite(w)):
        raise ModelError("a spring with a loss factor takes part in no elastic mode; cannot "
                         "convert its hysteretic damping")
    return system.replace(edge_damping=np.asarray(system.edge_damping) + extra,
                          edge_loss_factor=np.zeros_like(eta))


def order_forcing(system, excitation, orders, *, misfire=None):
    """Nodal forcing vectors per order: gas part and inertia part per unit speed squared.

    Returns
    -------
    gas, inertia : numpy.ndarray, shape (n_orders, n_nodes), complex
        Torque at each node (referred, N·m) for ``T = Re[(gas + Omega**2 inertia) e^{i q psi}]``,
        cylinder ``c`` delayed by its firing angle.

    Examples
    --------
    >>> from pathlib import Path
    >>> from crankbench.predict.torsion import from_toml
    >>> from crankbench.predict.torsion.excitation import engine_excitation
    >>> root = Path(__file__).resolve().parents[2]
    >>> s = from_toml(root / "sample_data/shaftlines/marine_6l.toml")
    >>> gas, inertia = order_forcing(s, engine_excitation(s, imep=2e6, orders=[3.0]), [3.0])
    >>> gas.shape, bool(np.allclose(np.abs(gas[0, 2:8]), np.abs(gas[0, 2])))
    ((1, 13), True)
    """
    from crankbench.predict.torsion.forced import cylinder_forcing

    orders = np.asarray(orders, float)
    g = excitation.harmonics(np.array([0.0]), orders, misfire=misfire)[0]      # (n_o, z)
    i1 = excitation.harmonics(np.array([1.0]), orders, misfire=misfire)[0] - g
    gas = cylinder_forcing(system, g[None], orders, 1)[0]
    inertia = cylinder_forcing(system, i1[None], orders, 1)[0]
    return gas, inertia


def _state_matrix(j, k, c):
    """Mass-normalised first-order form ``s' = A s`` of ``J x'' + C x' + K x = 0``."""
    s = 1.0 / np.sqrt(j)
    n = j.size
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -k * np.outer(s, s)
    a[n:, n:] = -c * np.outer(s, s)
    return a, s


def _mac(a, b):
    """Modal assurance criterion of complex vectors (columns of ``a`` against vector ``b``)."""
    num = np.abs(b.conj() @ a) ** 2
    den = np.real(np.sum(a.conj() * a, axis=0)) * np.real(b.conj() @ b)
    return num / np.maximum(den, 1e-300)


def _refine_mode(system, k, j, extra, target, w0, *, iterations=12):
    """Pole, right eigenvector and left row of the mode like ``target`` with the hysteretic
    damping converted at its own natural frequency: fixed point ``w = |lambda(w)|``.

    Returns (lambda, vec column, inverse row, converged frequency rad/s, iterations used).
    """
    n = j.size
    w = float(w0)
    for it in range(1, iterations + 1):
        c = system.damping_matrix(w) + extra
        a, _ = _state_matrix(j, k, c)
        lam, vec = np.linalg.eig(a)
        upper = np.flatnonzero(lam.imag > 0)
        if upper.size == 0:
            return None
        pick = int(upper[np.argmax(_mac(vec[:n, upper], target))])
        w_new = float(abs(lam[pick]))
        if abs(w_new - w) <= 1e-12 * w:
            break
        w = w_new
    inv = np.linalg.inv(vec)
    return lam[pick], vec[:, pick], inv[pick, :], w_new, it


@dataclass(frozen=True)
class ModalModel:
    """Complex modes of a (damped) torsional system, ready for time integration.

    Attributes
    ----------
    eigenvalues : numpy.ndarray (m,), complex
        State-space eigenvalues, 1/s (``-zeta omega_n +- i omega_d``; zero for the rigid-body
        angle of a free shaft line). With ``damping="per-mode"`` each oscillating pair is the
        pole of its own mode with the hysteretic damping taken at that mode's frequency.
    modal_input : numpy.ndarray (m, n), complex
        Modal force per unit nodal torque.
    angle_output, velocity_output : numpy.ndarray (n, m), complex
        Nodal angle (rad) and angular velocity (rad/s) per unit modal coordinate (referred).
    node_names : tuple of str
    node_ratio : numpy.ndarray
        Speed ratio of each node to the crankshaft (real angle = ratio x referred angle).
    condition : float
        Condition number of the eigenvector matrix (accuracy indicator).
    regularised : bool
        True if a tiny absolute damping was added to a free line without any (see
        :meth:`from_system`).
    damping : str
        'per-mode' (each mode with the hysteretic damping at its own frequency) or
        'single viscous' (one viscous matrix, :func:`equivalent_viscous_system`).
    system : predict.torsion.TorsionalSystem or None
        The shaft line; when given, :meth:`respond` takes the steady-state part from its
        exact harmonic solve (the prediction's damping model).
    omega : float or None
        Crankshaft speed (rad/s) at which speed-dependent springs were frozen for the modes.
    """

    eigenvalues: np.ndarray
    modal_input: np.ndarray
    angle_output: np.ndarray
    velocity_output: np.ndarray
    node_names: tuple
    node_ratio: np.ndarray
    condition: float
    regularised: bool = False
    damping: str = "single viscous"
    system: object = field(default=None, repr=False, compare=False)
    omega: float | None = None

    @classmethod
    @renamed(speed="omega")
    def from_system(cls, system, *, omega=None, damping="per-mode", max_frequency_hz=None):
        """Complex modes of ``system`` for the time integration.

        Parameters
        ----------
        system : predict.torsion.TorsionalSystem
        omega : float, optional
            Crankshaft speed (rad/s) for speed-dependent springs (centrifugal pendulums); their
            stiffness is frozen at this speed for the modes (the steady-state part of
            :meth:`respond` keeps them exact at every speed).
        damping : {"per-mode", "single viscous"}
            ``"per-mode"`` (default): each oscillating mode's pole, input and shape come from
            the system with its hysteretic damping turned into the viscous ``eta k / w`` at
            that mode's own natural frequency ``w = |lambda|`` (fixed-point iteration, a few
            eigen-solves per mode), so each mode has the damping the frequency-domain
            prediction gives it at resonance. ``"single viscous"``: one matrix,
            :func:`equivalent_viscous_system` (each spring converted at the mode straining it
            most).
        max_frequency_hz : float, optional
            Modes above this natural frequency keep the single-matrix pole (with
            ``respond(method="split")`` they respond quasi-statically anyway); default: all
            refined.

        Notes
        -----
        A free shaft line without any absolute damping has a defective (non-diagonalisable)
        rigid-body block; a damping ``1e-6 omega_1 J_i`` to ground is then added at every node
        (changes responses by about ``1e-6 omega_1 / omega``) and ``regularised`` is set.

        Examples
        --------
        >>> from crankbench.predict.torsion import TorsionalSystem
        >>> s = TorsionalSystem([2.0], [(-1, 0)], [2.0 * (2 * np.pi * 20) ** 2],
        ...                     node_damping=[2 * 0.02 * 2.0 * 2 * np.pi * 20])
        >>> fn, zeta = ModalModel.from_system(s).natural_frequencies()
        >>> round(float(fn[0]), 9), round(float(zeta[0]), 9)
        (20.0, 0.02)

        Two modes of springs with one loss factor ``eta`` each get ``zeta = eta / 2`` at their
        own frequency, as the frequency-domain model gives them (one viscous matrix, each
        spring tuned at the mode it strains most, cannot give both):

        >>> s = TorsionalSystem([1.0, 1.0], [(-1, 0), (0, 1)], [1e4, 1e4],
        ...                     edge_loss_factor=[0.04, 0.04])
        >>> [round(float(z), 4) for z in ModalModel.from_system(s).natural_frequencies()[1]]
        [0.02, 0.02]
        >>> [round(float(z), 4) for z in ModalModel.from_system(
        ...     s, damping="single viscous").natural_frequencies()[1]]
        [0.0166, 0.0289]
        """
        from crankbench.predict._validate import check_option

        check_option(damping, "damping", ("per-mode", "single viscous"), error=ConfigError)
        visc = equivalent_viscous_system(system)
        j = np.asarray(visc.inertias, float)
        k = visc.stiffness_matrix(omega)
        c = visc.damping_matrix()
        n = j.size
        extra = np.zeros((n, n))
        regularised = False
        if np.all(visc.node_damping == 0) and visc.is_free:
            w = np.sqrt(np.maximum(np.linalg.eigvalsh(k / np.sqrt(np.outer(j, j))), 0.0))
            w1 = w[w > 1e-9 * max(w.max(), 1.0)]
            eps = 1e-6 * (w1.min() if w1.size else 1.0)
            extra = np.diag(eps * j)
            c = c + extra
            regularised = True
        a, s = _state_matrix(j, k, c)
        lam, vec = np.linalg.eig(a)
        cond = float(np.linalg.cond(vec))
        if not np.isfinite(cond) or cond > 1e10:
            raise ModelError(f"torsional state matrix is (nearly) defective (eigenvector "
                             f"condition {cond:.3g}); cannot integrate modally")
        inv = np.linalg.inv(vec)
        if damping == "per-mode" and np.any(np.asarray(system.edge_loss_factor) > 0):
            top = np.inf if max_frequency_hz is None else TWO_PI * float(max_frequency_hz)
            lam = lam.copy()
            vec = vec.copy()
            inv = inv.copy()
            scale = max(float(np.abs(lam).max()), 1.0)
            for idx in np.flatnonzero(lam.imag > 1e-9 * scale):
                if abs(lam[idx]) > top:
                    continue
                got = _refine_mode(system, k, j, extra, vec[:n, idx], abs(lam[idx]))
                if got is None:
                    continue
                lam_j, v_j, u_j, _, _ = got
                partner = int(np.argmin(np.abs(lam - np.conj(lam[idx]))))
                lam[idx], vec[:, idx], inv[idx] = lam_j, v_j, u_j
                if partner != idx:
                    lam[partner] = np.conj(lam_j)
                    vec[:, partner] = np.conj(v_j)
                    inv[partner] = np.conj(u_j)
        modal_input = inv[:, n:] * s[None, :]          # force on node -> d(state)/dt
        angle_out = vec[:n, :] * s[:, None]
        vel_out = vec[n:, :] * s[:, None]
        return cls(eigenvalues=lam, modal_input=modal_input, angle_output=angle_out,
                   velocity_output=vel_out, node_names=tuple(system.node_names),
                   node_ratio=np.asarray(system.node_ratio, float), condition=cond,
                   regularised=regularised, damping=damping, system=system,
                   omega=None if omega is None else float(omega))

    def natural_frequencies(self):
        """Natural frequencies ``|lambda| / 2 pi`` (Hz) and damping ratios ``-Re lambda /
        |lambda|`` of the oscillating modes, ascending. The amplitude peak of a mode's
        resonance lies at ``f_n sqrt(1 - 2 zeta**2)`` (displacement)."""
        lam = self.eigenvalues[self.eigenvalues.imag > 1e-9]
        order = np.argsort(np.abs(lam))
        lam = lam[order]
        wn = np.abs(lam)
        return wn / TWO_PI, -lam.real / wn

    def critical_speeds(self, orders, speed_range_rpm, major=None):
        """Critical speeds of the damped model: every (oscillating mode, order) crossing.

        ``speed_rpm = 60 f_n sqrt(1 - 2 zeta**2) / q``, the speed of the displacement peak of
        the mode's resonance curve.

        Returns
        -------
        pandas.DataFrame
            ``mode`` (1 = lowest oscillating mode), ``order``, ``speed_rpm``,
            ``frequency_hz``, ``damping_ratio``, ``major`` (from ``major``, a boolean per
            order, or False), sorted by speed.
        """
        import pandas as pd

        fn, zeta = self.natural_frequencies()
        orders = np.asarray(orders, float)
        major = np.zeros(orders.size, bool) if major is None else np.asarray(major, bool)
        lo, hi = speed_range_rpm
        rows = []
        for m, (f, z) in enumerate(zip(fn, zeta), start=1):
            peak = f * np.sqrt(max(1.0 - 2.0 * z * z, 0.0))
            for k, q in enumerate(orders):
                rpm = 60.0 * peak / q
                if lo <= rpm <= hi:
                    rows.append((m, float(q), rpm, f, z, bool(major[k])))
        frame = pd.DataFrame(rows, columns=["mode", "order", "speed_rpm", "frequency_hz",
                                            "damping_ratio", "major"])
        return frame.sort_values(["speed_rpm", "mode"], ignore_index=True)

    def node_index(self, name):
        """Index of a node by name (error lists the names)."""
        if name not in self.node_names:
            from crankbench.predict._validate import suggest

            raise ConfigError(f"shaft-line node {name!r} does not exist"
                              f"{suggest(name, self.node_names)}; nodes: "
                              f"{', '.join(self.node_names)}")
        return self.node_names.index(name)

    def _steady_grid(self, order, omega, grid_points):
        """Speeds (rad/s) of the steady-state table: geometric, ``zeta_min / 16`` apart
        relative to speed for the sharpest mode the order sweeps through."""
        lo, hi = float(omega.min()), float(omega.max())
        if hi <= lo:
            return np.array([lo])
        if grid_points is not None:
            return np.geomspace(max(lo, 1e-9 * hi), hi, int(grid_points))
        lam = self.eigenvalues
        osc = lam.imag > 1e-9 * max(float(np.abs(lam).max()), 1.0)
        wn = np.abs(lam[osc])
        zeta = -lam[osc].real / wn
        inside = (wn >= 0.8 * order * lo) & (wn <= 1.25 * order * hi)
        z_min = float(zeta[inside].min()) if inside.any() else 0.03
        step = float(np.clip(z_min / 16.0, 2e-5, 2e-3))
        lo = max(lo, 1e-9 * hi)
        count = int(np.clip(np.ceil(np.log(hi / lo) / step) + 1, 64, 50_000))
        return np.geomspace(lo, hi, count)

    def _steady_table(self, order, gas, inertia, grid, nodes):
        """Exact steady-state response of ``nodes`` per unit load (gas) and per unit speed²
        (inertia) on ``grid``: (n_grid, nodes) each, from the system's harmonic solve."""
        from crankbench.predict.torsion.forced import harmonic_solve

        n = self.system.n_nodes
        forcing = np.empty((grid.size, 1, n), complex)
        forcing[:] = gas
        xg = harmonic_solve(self.system, grid, [order], forcing)[:, 0, :][:, nodes]
        forcing[:] = inertia
        xi = harmonic_solve(self.system, grid, [order], forcing)[:, 0, :][:, nodes]
        return xg, xi

    def _steady_modal(self, order, gas, inertia, grid, nodes, keep):
        """Steady-state response from the modal sum over modes ``keep`` (no system given)."""
        lam = self.eigenvalues[keep]
        inv = 1.0 / (1j * order * grid[None, :] - lam[:, None])             # (m, G)
        out = self.angle_output[np.ix_(nodes, np.flatnonzero(keep))]
        xg = (out @ ((self.modal_input[keep] @ gas)[:, None] * inv)).T
        xi = (out @ ((self.modal_input[keep] @ inertia)[:, None] * inv)).T
        return xg, xi

    @renamed(speed="omega")
    def respond(self, time, psi, order, gas, inertia, omega, *, load=None, nodes,
                method="split", margin=6.0, grid_points=None, diagnostics=None):
        """Complex response of ``nodes`` to one order of excitation along a run.

        Parameters
        ----------
        time : numpy.ndarray (T,)
            Uniform time grid, s.
        psi : numpy.ndarray (T,)
            Crank angle of cylinder 1 from firing TDC at those times, rad (mean motion).
        order : float
        gas, inertia : numpy.ndarray (n_nodes,), complex
            Nodal forcing of this order (:func:`order_forcing`).
        omega : numpy.ndarray (T,)
            Crankshaft speed, rad/s.
        load : callable, optional
            Gas-torque scale factor as a function of speed (rad/s), vectorised; default 1.
        nodes : sequence of int
        method : {"split", "full"}
            Which modes carry a sweep transient. ``"full"``: every mode except zero
            eigenvalues (rigid-body rotation, free damper-ring offsets: they cannot resonate
            and respond quasi-statically, so no constant angle offset from the start is kept
            in the orders). ``"split"`` (default): the modes whose damped natural frequency
            lies at or below the highest order frequency ``q Omega`` of the run, widened by
            ``margin`` half-power bandwidths (at least 5 %), including the real modes; the
            stiff modes above the swept band and the negative-frequency halves of the pairs
            only respond quasi-statically. The split leaves out their transient, of relative
            order ``alpha q / (omega_n - q Omega)**2`` (``alpha`` the angular acceleration).
        margin : float
        grid_points : int, optional
            Speeds of the steady-state table (default: geometric spacing ``zeta_min / 16``
            for the sharpest mode in the swept band, 64 to 50 000 points).
        diagnostics : dict, optional
            Filled with ``steady_interpolation_rel_error`` (largest error of the spline
            interpolation of the steady-state table at the grid midpoints, relative to the
            largest steady amplitude, exact solve as reference), ``steady_points`` and
            ``transient_modes``.

        Returns
        -------
        angle, velocity : numpy.ndarray (len(nodes), T), complex
            Referred angle (rad) and angular velocity (rad/s); the real signals are their real
            parts, the order's amplitude their moduli.
        """
        from scipy.interpolate import CubicSpline
        from scipy.signal import lfilter

        h = float(time[1] - time[0])
        qpsi = order * psi
        w_step = np.diff(qpsi) / h                       # exact phase increment per step
        carrier = _cis(qpsi)
        load_fn = (lambda w: np.ones_like(w)) if load is None else load
        b_gas = self.modal_input @ gas                  # (m,)
        b_in = self.modal_input @ inertia
        lam_all = self.eigenvalues
        active = (b_gas != 0) | (b_in != 0)
        # zero eigenvalues (rigid rotation of a free line, a damper ring's free offset) cannot
        # resonate; integrated, they would keep a constant offset from the start-up (an angle
        # that belongs to the mean motion), so they always respond quasi-statically
        zero = np.abs(lam_all) <= 1e-9 * max(np.abs(lam_all).max(), 1.0)
        if method == "full":
            resonant = active & ~zero
        else:
            hi = order * omega.max()
            width = np.maximum(margin * np.abs(lam_all.real), 0.05 * np.abs(lam_all))
            # modes at or below the swept band (free vibration they pick up lingers), not the
            # stiff modes above it, nor the negative-frequency halves of the pairs
            resonant = active & ~zero & (lam_all.imag >= 0) & (lam_all.imag - width <= hi)
        nodes = list(nodes)
        # ---- steady-state part: exact harmonic solve (or the modal sum), splined over speed
        grid = self._steady_grid(order, omega, grid_points)
        if self.system is not None:
            table = self._steady_table(order, gas, inertia, grid, nodes)
        else:
            table = self._steady_modal(order, gas, inertia, grid, nodes, active)
        load_w = load_fn(omega)
        if grid.size == 1:
            steady = load_w[None, :] * table[0][0][:, None] + \
                (omega**2)[None, :] * table[1][0][:, None]
        else:
            x_log = np.log(grid)
            splines = [CubicSpline(x_log, t, axis=0) for t in table]
            u = np.log(np.clip(omega, grid[0], grid[-1]))
            steady = (load_w[:, None] * splines[0](u) + (omega**2)[:, None] * splines[1](u)).T
            if diagnostics is not None:
                mid = np.sqrt(grid[1:] * grid[:-1])
                exact = self._steady_table(order, gas, inertia, mid, nodes) \
                    if self.system is not None else \
                    self._steady_modal(order, gas, inertia, mid, nodes, active)
                err = 0.0
                for t_ex, sp in zip(exact, splines):
                    ref = max(float(np.abs(t_ex).max()), 1e-300)
                    err = max(err, float(np.abs(sp(np.log(mid)) - t_ex).max()) / ref)
                diagnostics["steady_interpolation_rel_error"] = max(
                    err, diagnostics.get("steady_interpolation_rel_error", 0.0))
        if diagnostics is not None:
            diagnostics["steady_points"] = max(int(grid.size),
                                               diagnostics.get("steady_points", 0))
            diagnostics["transient_modes"] = max(int(resonant.sum()),
                                                 diagnostics.get("transient_modes", 0))
        out_x = steady * carrier[None, :]
        out_v = out_x * (1j * order * omega)[None, :]
        # ---- sweep transient of each resonant mode: z_j - z_j,ss
        idx = np.flatnonzero(resonant)
        if idx.size:
            step = _cis(w_step * h)                      # e^{i omega h}, shared by all modes
            iw = 1j * w_step
            mid = 0.5 * (omega[1:] + omega[:-1])
            c_gas = carrier[:-1] * load_fn(mid)
            c_in = carrier[:-1] * (0.5 * (omega[1:] ** 2 + omega[:-1] ** 2))
            f_gas = carrier * load_w
            f_in = carrier * omega**2
            ax = self.angle_output[nodes, :]
            av = self.velocity_output[nodes, :]
            for jm in idx:
                lam = lam_all[jm]
                e = np.exp(lam * h)
                den = iw - lam
                # h e^{lambda h} phi_1((i omega - lambda) h) = (e^{i omega h} - e^{lambda h})
                # / den; |den| >= zeta omega_n keeps the cancellation harmless; series if tiny
                if np.min(np.abs(den)) * h < 1e-6:
                    small = np.abs(den) * h < 1e-6
                    gain = np.where(small, h * e * (1 + 0.5 * den * h),
                                    (step - e) / np.where(small, 1.0, den))
                else:
                    gain = (step - e) / den
                drive = (b_gas[jm] * c_gas + b_in[jm] * c_in) * gain
                # quasi-static modal coordinate at every sample; the integration starts there
                z_ss = (b_gas[jm] * f_gas + b_in[jm] * f_in) / (1j * order * omega - lam)
                z = np.empty(time.size, complex)
                z[0] = z_ss[0]
                z[1:] = lfilter([1.0], [1.0, -e], drive, zi=[e * z_ss[0]])[0]
                z -= z_ss
                for r in range(len(nodes)):
                    out_x[r] += ax[r, jm] * z
                    out_v[r] += av[r, jm] * z
        return out_x, out_v


def _cis(x):
    """exp(1j x) for real x (cos + i sin: faster than the complex exponential)."""
    out = np.empty(np.shape(x), complex)
    out.real = np.cos(x)
    out.imag = np.sin(x)
    return out
