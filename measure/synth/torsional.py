"""Time-domain torsional response of a shaft line through resonances (complex modal integration).

The shaft line ``J x'' + C x' + K x = f(t)`` (referred to crankshaft speed, from
:mod:`predict.torsion`) is written in mass-normalised state form ``s' = A s + B f`` and
diagonalised once, ``A = V diag(lambda) V^-1`` (complex modes, so non-proportional damping -
the viscous damper, the rubber coupling, the propeller - is kept exactly). Each order ``q`` of
the cylinder torque excites every complex mode ``j`` through

``z_j' = lambda_j z_j + c_j(t) e^{i q psi(t)}``,

``psi`` the crank angle of cylinder 1 from firing TDC and ``c_j`` its slowly varying modal force
(gas part scaled with the load, plus ``Omega**2`` times the inertia part). Over one step ``h``
the forcing is taken as ``c e^{i(q psi_k + omega_k s)}`` (exponential hold: ``omega_k`` from the
exact phase increment, ``c`` at the step's middle), which the recurrence

``z_{k+1} = e^{lambda h} z_k + c e^{i q psi_k} h e^{lambda h} phi_1((i omega_k - lambda) h)``,
``phi_1(x) = (e^x - 1)/x``,

integrates *exactly* for constant speed and force, whatever the ratio of the order frequency or
the natural frequency to the sample rate. During a sweep the remaining error is the change of
``c`` and ``omega`` within one step (relative ``h |d ln c/dt|`` and ``q alpha h**2 / 2`` rad of
phase), negligible at the sample rates used. The recurrence is a first-order IIR filter per
mode (``scipy.signal.lfilter``), started at the steady state of the initial speed, so there is
no start-up transient; what remains is the genuine transient of passing through a resonance
at a finite sweep rate.

Because each order is integrated separately, the response per order (its complex envelope) is
available along the run: this is the ground truth of the order amplitudes, including the
transient effects of a fast sweep.

Hysteretic damping (loss factors of shafts and couplings) has no exact time-domain form; each
spring's ``eta k`` is turned into the viscous ``eta k / omega_e`` at the natural frequency of the
undamped mode that strains it most (exact at that resonance). :func:`equivalent_viscous_system`
returns that viscous model so a frequency-domain solution of the same model can check the
integration.

References
----------
Jiaotong University, *IC-engine dynamics* (内燃机动力学), 1958, part 2 ch. 4 §3 (resonance
curves: amplitude through a critical speed).
Liang Shoupan, *Engine dynamics* (發動機動力學), 1948, ch. 7 (vibration of the crankshaft).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

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


@dataclass(frozen=True)
class ModalModel:
    """Complex modes of a (damped) torsional system, ready for time integration.

    Attributes
    ----------
    eigenvalues : numpy.ndarray (m,), complex
        State-space eigenvalues, 1/s (``-zeta omega_n +- i omega_d``; zero for the rigid-body
        angle of a free shaft line).
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
    """

    eigenvalues: np.ndarray
    modal_input: np.ndarray
    angle_output: np.ndarray
    velocity_output: np.ndarray
    node_names: tuple
    node_ratio: np.ndarray
    condition: float
    regularised: bool = False

    @classmethod
    @renamed(speed="omega")
    def from_system(cls, system, *, omega=None):
        """Diagonalise the equivalent viscous model of ``system``.

        Parameters
        ----------
        system : predict.torsion.TorsionalSystem
        omega : float, optional
            Crankshaft speed (rad/s) for speed-dependent springs (centrifugal pendulums); their
            stiffness is frozen at this speed.

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
        """
        visc = equivalent_viscous_system(system)
        j = np.asarray(visc.inertias, float)
        k = visc.stiffness_matrix(omega)
        c = visc.damping_matrix()
        regularised = False
        if np.all(visc.node_damping == 0) and visc.is_free:
            w = np.sqrt(np.maximum(np.linalg.eigvalsh(k / np.sqrt(np.outer(j, j))), 0.0))
            w1 = w[w > 1e-9 * max(w.max(), 1.0)]
            eps = 1e-6 * (w1.min() if w1.size else 1.0)
            c = c + np.diag(eps * j)
            regularised = True
        s = 1.0 / np.sqrt(j)
        kt = k * np.outer(s, s)
        ct = c * np.outer(s, s)
        n = j.size
        a = np.zeros((2 * n, 2 * n))
        a[:n, n:] = np.eye(n)
        a[n:, :n] = -kt
        a[n:, n:] = -ct
        lam, vec = np.linalg.eig(a)
        cond = float(np.linalg.cond(vec))
        if not np.isfinite(cond) or cond > 1e10:
            raise ModelError(f"torsional state matrix is (nearly) defective (eigenvector "
                             f"condition {cond:.3g}); cannot integrate modally")
        inv = np.linalg.inv(vec)
        modal_input = inv[:, n:] * s[None, :]          # force on node -> d(state)/dt
        angle_out = vec[:n, :] * s[:, None]
        vel_out = vec[n:, :] * s[:, None]
        return cls(eigenvalues=lam, modal_input=modal_input, angle_output=angle_out,
                   velocity_output=vel_out, node_names=tuple(system.node_names),
                   node_ratio=np.asarray(system.node_ratio, float), condition=cond,
                   regularised=regularised)

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

    @renamed(speed="omega")
    def respond(self, time, psi, order, gas, inertia, omega, *, load=None, nodes,
                method="split", margin=6.0, grid_points=1000):
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
            ``"full"`` integrates every mode in time (except zero eigenvalues, rigid-body
            rotation and free damper-ring offsets, which cannot resonate and are always taken
            quasi-statically so that no constant angle offset from the start is kept in the
            orders). ``"split"`` (default) integrates the modes
            whose damped natural frequency lies at or below the highest order frequency
            ``q Omega`` of the run, widened by ``margin`` half-power bandwidths (at least 5 %),
            including the rigid-body and real modes; the stiff modes above the swept band and
            the negative-frequency halves of the complex pairs respond quasi-statically, at the
            instantaneous speed (steady-state response interpolated from a ``grid_points``
            speed grid). The split's error is the transient of those modes, of relative order
            ``alpha q / (omega_n - q Omega)**2`` (``alpha`` the angular acceleration), and the
            grid interpolation error.
        margin : float
        grid_points : int

        Returns
        -------
        angle, velocity : numpy.ndarray (len(nodes), T), complex
            Referred angle (rad) and angular velocity (rad/s); the real signals are their real
            parts, the order's amplitude their moduli.
        """
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
        quasi = active & ~resonant
        nodes = list(nodes)
        out_x = np.zeros((len(nodes), time.size), complex)
        out_v = np.zeros((len(nodes), time.size), complex)
        if quasi.any():
            lamq = lam_all[quasi]
            single = np.ptp(omega) == 0
            g = np.linspace(omega.min(), omega.max(), 1 if single else grid_points)
            inv = 1.0 / (1j * order * g[None, :] - lamq[:, None])        # (mq, G)
            force = b_gas[quasi, None] * load_fn(g)[None, :] + b_in[quasi, None] * g**2
            resp = force * inv
            cols = np.flatnonzero(quasi)
            for out, mat in ((out_x, self.angle_output), (out_v, self.velocity_output)):
                table = mat[np.ix_(nodes, cols)] @ resp                      # (nodes, G)
                for r in range(len(nodes)):
                    if single:
                        out[r] += carrier * table[r, 0]
                    else:
                        out[r] += carrier * (np.interp(omega, g, table[r].real)
                                             + 1j * np.interp(omega, g, table[r].imag))
        idx = np.flatnonzero(resonant)
        if idx.size:
            step = _cis(w_step * h)                      # e^{i omega h}, shared by all modes
            iw = 1j * w_step
            mid = 0.5 * (omega[1:] + omega[:-1])
            c_gas = carrier[:-1] * load_fn(mid)
            c_in = carrier[:-1] * (0.5 * (omega[1:] ** 2 + omega[:-1] ** 2))
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
                # steady state of the initial speed: no start-up transient
                z0 = (b_gas[jm] * load_fn(omega[:1])[0] + b_in[jm] * omega[0] ** 2) \
                    * carrier[0] / (1j * order * omega[0] - lam)
                z = np.empty(time.size, complex)
                z[0] = z0
                z[1:] = lfilter([1.0], [1.0, -e], drive, zi=[e * z0])[0]
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
