"""Result object of the undamped eigen-analysis of a torsional system."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Modes"]


@dataclass(frozen=True)
class Modes:
    """Undamped natural frequencies and mode shapes of a torsional system.

    Attributes
    ----------
    frequencies_hz : ndarray (n_modes,)
        Natural frequencies, Hz, ascending; rigid-body modes are exactly 0.
    shapes : ndarray (n_nodes, n_modes)
        Mass-normalised mode shapes (``xᵀ J x = 1``), rad per modal unit, referred to crankshaft
        speed. Nodes left out of the undamped analysis (seismic rings of viscous dampers,
        pendulums) hold 0.
    mode_numbers : ndarray (n_modes,)
        0 for rigid-body modes, 1, 2, ... for elastic modes.
    node_names : tuple of str
    method : str
        Solver used: ``'bidiagonal dqds'`` (chains), ``'tree bisection'`` or ``'dense eigh'``.
    relative_error_bound : float
        Stated bound on the relative error of each frequency.
    """

    frequencies_hz: np.ndarray
    shapes: np.ndarray
    mode_numbers: np.ndarray
    node_names: tuple
    method: str
    relative_error_bound: float

    def relative(self) -> np.ndarray:
        """Shapes scaled so each column's largest |amplitude| is 1 and that entry positive."""
        idx = np.argmax(np.abs(self.shapes), axis=0)
        peak = self.shapes[idx, np.arange(self.shapes.shape[1])]
        peak = np.where(peak == 0, 1.0, peak)
        return self.shapes / peak

    def to_frame(self):
        """Relative mode shapes as a DataFrame (rows: nodes, columns: ``mode k (f Hz)``)."""
        import pandas as pd

        cols = [f"mode {m} ({f:.4g} Hz)" for m, f in zip(self.mode_numbers, self.frequencies_hz)]
        return pd.DataFrame(self.relative(), index=list(self.node_names), columns=cols)

    def plot(self, ax=None, *, modes=None):
        """Plot relative mode shapes along the nodes; returns the figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots(figsize=(7, 4))
        else:
            fig = ax.figure
        rel = self.relative()
        sel = [i for i, m in enumerate(self.mode_numbers)
               if (modes is None and 1 <= m <= 4) or (modes is not None and m in modes)]
        for i in sel:
            ax.plot(rel[:, i], marker="o",
                    label=f"mode {self.mode_numbers[i]}: {self.frequencies_hz[i]:.4g} Hz")
        ax.set_xticks(range(len(self.node_names)), self.node_names, rotation=60, fontsize=7)
        ax.axhline(0, color="0.6", lw=0.8)
        ax.set_ylabel("relative amplitude")
        ax.legend(fontsize=8)
        fig.tight_layout()
        return fig
