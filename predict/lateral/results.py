"""Result objects of the rotor finite-element model (:mod:`predict.lateral.fe`).

All values SI (rad/s, m, kg); frames add ``speed_rpm`` / ``frequency_hz`` / ``*_deg`` columns.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LateralModes", "CriticalSpeeds", "CampbellDiagram", "UnbalanceResponse"]

_RPM = 30.0 / np.pi
_COLORS = {"forward": "tab:blue", "backward": "tab:red", "mixed": "tab:gray"}


def _figure(ax, nrows=1):
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(nrows, 1, sharex=True, squeeze=False)
        return fig, list(ax[:, 0])
    axes = list(np.atleast_1d(ax))
    return axes[0].figure, axes


@dataclass(frozen=True)
class LateralModes:
    """Damped natural frequencies and whirl of a rotor at one spin speed.

    Attributes
    ----------
    speed : float
        Spin speed Ω, rad/s.
    omega : ndarray
        Damped natural frequencies ω_d, rad/s, ascending.
    damping_ratio : ndarray
        ζ = −Re(s)/|s| of each mode (0 without damping).
    whirl : tuple of str
        "forward", "backward" or "mixed" (planar/degenerate, e.g. at Ω = 0).
    whirl_index : ndarray
        Σ 2 Im(u v̄) / Σ (|u|² + |v|²) over the nodes: +1 circular forward, −1 backward.
    error_estimate : ndarray
        Discretisation-error estimate of ω_d, rad/s (Richardson, |ω_h − ω_2h|/15), NaN if
        not computed.
    positions : ndarray
        Node positions along the shaft, m.
    shapes : ndarray
        Complex mode shapes, shape (n_modes, n_nodes, 2) for the (x, y) displacements,
        scaled to unit maximum magnitude.
    theory : str
        "euler-bernoulli" or "timoshenko".
    n_elements : int
        Number of shaft elements (the fidelity used).
    """

    speed: float
    omega: np.ndarray
    damping_ratio: np.ndarray
    whirl: tuple
    whirl_index: np.ndarray
    error_estimate: np.ndarray
    positions: np.ndarray
    shapes: np.ndarray
    theory: str
    n_elements: int

    @property
    def frequency_hz(self) -> np.ndarray:
        """Damped natural frequencies, Hz."""
        return self.omega / (2 * np.pi)

    def to_frame(self):
        """Table: mode, frequency_hz, frequency_rpm, damping_ratio, whirl, error_estimate_hz."""
        import pandas as pd

        return pd.DataFrame({
            "mode": np.arange(1, self.omega.size + 1), "frequency_hz": self.frequency_hz,
            "frequency_rpm": self.omega * _RPM, "damping_ratio": self.damping_ratio,
            "whirl": list(self.whirl), "error_estimate_hz": self.error_estimate / (2 * np.pi),
            "speed_rpm": self.speed * _RPM, "theory": self.theory,
            "n_elements": self.n_elements})

    def plot(self, ax=None):
        """Plot the x-displacement of each mode along the shaft; returns the figure."""
        fig, (ax,) = _figure(ax)
        for i in range(self.omega.size):
            shape = self.shapes[i, :, 0]
            k = np.argmax(np.abs(shape))
            ax.plot(self.positions, np.real(shape * np.exp(-1j * np.angle(shape[k]))), "o-",
                    ms=3, label=f"{self.frequency_hz[i]:.4g} Hz {self.whirl[i]}")
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_xlabel("position (m)")
        ax.set_ylabel("x displacement (normalised)")
        ax.set_title(f"mode shapes at {self.speed * _RPM:.5g} rpm")
        ax.legend(fontsize="small")
        return fig


@dataclass(frozen=True)
class CriticalSpeeds:
    """Undamped critical speeds: spin speeds where a natural frequency equals order × Ω.

    Attributes
    ----------
    omega : ndarray
        Critical spin speeds, rad/s.
    order : ndarray
        Excitation order of each critical speed (1 = unbalance).
    whirl : tuple of str
        Whirl direction of the mode at its critical speed.
    mode : ndarray
        Mode number (1-based, ascending critical speed within each order and whirl).
    method : str
        How they were found ("hermitian eigen-solve" is exact for the discretised model).
    n_elements : int
    theory : str
    """

    omega: np.ndarray
    order: np.ndarray
    whirl: tuple
    mode: np.ndarray
    method: str
    n_elements: int
    theory: str

    @property
    def speed_rpm(self) -> np.ndarray:
        """Critical speeds, rpm."""
        return self.omega * _RPM

    def to_frame(self):
        """Table: mode, order, whirl, speed_rpm, omega, frequency_hz."""
        import pandas as pd

        return pd.DataFrame({"mode": self.mode, "order": self.order, "whirl": list(self.whirl),
                             "speed_rpm": self.speed_rpm, "omega": self.omega,
                             "frequency_hz": self.order * self.omega / (2 * np.pi)})

    def plot(self, ax=None):
        """Stem plot of the critical speeds (rpm) coloured by whirl; returns the figure."""
        fig, (ax,) = _figure(ax)
        for w, s, o in zip(self.whirl, self.speed_rpm, self.order):
            ax.vlines(s, 0, o, color=_COLORS.get(w, "k"))
            ax.plot(s, o, "o", color=_COLORS.get(w, "k"))
        ax.set_xlabel("critical speed (rpm)")
        ax.set_ylabel("order")
        ax.set_title("critical speeds (blue forward, red backward)")
        return fig


@dataclass(frozen=True)
class CampbellDiagram:
    """Natural frequencies against spin speed with whirl direction.

    Attributes
    ----------
    speeds : ndarray
        Spin speeds, rad/s.
    omega : ndarray
        Damped natural frequencies, rad/s, shape (n_speeds, n_modes), ascending per speed.
    whirl : ndarray
        Whirl labels, same shape.
    orders : tuple of float
        Excitation orders drawn as lines.
    criticals : CriticalSpeeds
        Exact critical speeds for those orders.
    """

    speeds: np.ndarray
    omega: np.ndarray
    whirl: np.ndarray
    orders: tuple
    criticals: CriticalSpeeds

    def to_frame(self):
        """Long table: speed_rpm, mode, frequency_hz, whirl."""
        import pandas as pd

        n_s, n_m = self.omega.shape
        return pd.DataFrame({
            "speed_rpm": np.repeat(self.speeds * _RPM, n_m),
            "mode": np.tile(np.arange(1, n_m + 1), n_s),
            "frequency_hz": self.omega.ravel() / (2 * np.pi),
            "whirl": self.whirl.ravel()})

    def plot(self, ax=None):
        """Campbell diagram (Hz against rpm) with order lines and critical speeds."""
        fig, (ax,) = _figure(ax)
        rpm = self.speeds * _RPM
        for w, color in _COLORS.items():
            mask = self.whirl == w
            if mask.any():
                ax.plot(np.broadcast_to(rpm[:, None], mask.shape)[mask],
                        self.omega[mask] / (2 * np.pi), ".", color=color, label=w)
        top = np.nanmax(self.omega) / (2 * np.pi) if self.omega.size else 1.0
        for k in self.orders:
            ax.plot(rpm, k * self.speeds / (2 * np.pi), "k--", lw=0.8)
            ax.annotate(f"{k:g}×", (rpm[-1], min(k * self.speeds[-1] / (2 * np.pi), top)))
        c = self.criticals
        ax.plot(c.speed_rpm, c.order * c.omega / (2 * np.pi), "kx", ms=8, label="critical")
        ax.set_ylim(0, top * 1.05)
        ax.set_xlabel("speed (rpm)")
        ax.set_ylabel("natural frequency (Hz)")
        ax.set_title("Campbell diagram")
        ax.legend(fontsize="small")
        return fig


@dataclass(frozen=True)
class UnbalanceResponse:
    """Steady-state synchronous response to unbalance at probe positions.

    Attributes
    ----------
    speeds : ndarray
        Spin speeds, rad/s.
    positions : ndarray
        Probe positions along the shaft, m.
    response : ndarray
        Complex displacement amplitudes, m, shape (n_speeds, n_probes, 2) for x and y:
        x(t) = Re(X e^{iΩt}), y(t) = Re(Y e^{iΩt}).
    """

    speeds: np.ndarray
    positions: np.ndarray
    response: np.ndarray

    @property
    def major_axis(self) -> np.ndarray:
        """Semi-major axis of the orbit, m, shape (n_speeds, n_probes)."""
        x, y = self.response[..., 0], self.response[..., 1]
        # x + iy = (X + iY)/2 e^{iΩt} + conj(X − iY)/2 e^{−iΩt}: forward + backward circles
        return (np.abs(x + 1j * y) + np.abs(x - 1j * y)) / 2

    def to_frame(self):
        """Long table: speed_rpm, position, amplitude_x, phase_x_deg, amplitude_y,
        phase_y_deg, major_axis (amplitudes in m, peak)."""
        import pandas as pd

        n_s, n_p = self.response.shape[:2]
        x, y = self.response[..., 0], self.response[..., 1]
        return pd.DataFrame({
            "speed_rpm": np.repeat(self.speeds * _RPM, n_p),
            "position": np.tile(self.positions, n_s),
            "amplitude_x": np.abs(x).ravel(), "phase_x_deg": np.degrees(np.angle(x)).ravel(),
            "amplitude_y": np.abs(y).ravel(), "phase_y_deg": np.degrees(np.angle(y)).ravel(),
            "major_axis": self.major_axis.ravel()})

    def plot(self, ax=None):
        """Bode plot (x amplitude and phase against rpm) per probe; returns the figure."""
        fig, axes = _figure(ax, nrows=2)
        rpm = self.speeds * _RPM
        for j, z in enumerate(self.positions):
            axes[0].semilogy(rpm, np.abs(self.response[:, j, 0]), label=f"x at {z:g} m")
            if len(axes) > 1:
                axes[1].plot(rpm, np.degrees(np.angle(self.response[:, j, 0])))
        axes[0].set_ylabel("amplitude (m, peak)")
        axes[0].legend(fontsize="small")
        axes[-1].set_xlabel("speed (rpm)")
        if len(axes) > 1:
            axes[1].set_ylabel("phase (deg)")
        return fig
