"""A rigid engine on elastic mounts (6 degrees of freedom): natural frequencies and mode shapes,
forced response at any point, forces transmitted to the foundation, transmissibility.

Frame (SI): x along the crankshaft, the same axis and origin as the engine's
``cylinder_positions``; y horizontal, the way the top of the crank moves (the engine's
"horizontal" direction of :mod:`predict.balance`); z vertically up; the origin on the crankshaft
axis. Cross products are taken with the usual formula in this (x, y, z) order.

The body coordinates are q = (u_x, u_y, u_z, r_x, r_y, r_z): the translation of the centre of
gravity and small rotations. A point at d from the CG moves by u + r × d = T(d) q with
T(d) = [I | −[d]×]. Each mount is a spring/damper per axis (stiffness kᵢ, viscous damping cᵢ,
or a hysteretic loss factor η), so K = Σ Tᵀ Kᵢ T, C = Σ Tᵀ Cᵢ T, M = diag(m, m, m, J), and the
harmonic response to F e^{iΩt} solves (K(1 + iη) − Ω² M + iΩ C) q = f exactly (a 6×6 solve per
frequency; the natural frequencies come from the symmetric generalised eigenproblem
K φ = ω² M φ).

References
----------
Liang Shoupan, *Engine Dynamics* (1948) ch. 4 (effects of unbalanced forces on the foundation:
natural frequencies, periodic forces, vibration isolation); Den Hartog, *Mechanical Vibrations*
(1956) §3.2 (transmissibility).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._toml import load_toml
from ._validate import check_finite_array, check_nonnegative, check_positive
from .errors import ModelError

__all__ = ["Mount", "MountedEngine", "MountModes", "MountResponse", "excitation_from_unbalance",
           "BlockExcitation", "block_excitation", "direction_vector", "DOF_NAMES", "LOAD_NAMES"]

DOF_NAMES = ("x", "y", "z", "rx", "ry", "rz")
#: components of a generalised load on the block: force (N) and moment (N·m) about a point
LOAD_NAMES = ("force_x", "force_y", "force_z", "moment_x", "moment_y", "moment_z")
_AXES = {"x": 0, "y": 1, "z": 2, "axial": 0, "horizontal": 1, "lateral": 1, "transverse": 1,
         "vertical": 2}


def _vec3(value, name, *, nonneg=False) -> np.ndarray:
    arr = check_finite_array(value, name, ndim=1, error=ModelError)
    if arr.size != 3:
        raise ModelError(f"{name} must have 3 values (x, y, z), got {arr.size}")
    if nonneg and (arr < 0).any():
        raise ModelError(f"{name}={arr.tolist()} must be >= 0")
    return arr


def _skew(d):
    x, y, z = d
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def _transfer(d):
    """T(d): body coordinates → displacement of a point at d from the CG."""
    return np.hstack([np.eye(3), -_skew(d)])


@dataclass(frozen=True)
class Mount:
    """One elastic mount.

    Attributes
    ----------
    position : ndarray
        (x, y, z) of the mount's elastic centre, m.
    stiffness : ndarray
        (k_x, k_y, k_z), N/m.
    damping : ndarray
        (c_x, c_y, c_z) viscous damping, N·s/m.
    loss_factor : float
        Hysteretic loss factor η (structural damping), dimensionless.
    name : str
    """

    position: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray = field(default_factory=lambda: np.zeros(3))
    loss_factor: float = 0.0
    name: str = ""

    def __post_init__(self):
        object.__setattr__(self, "position", _vec3(self.position, "position"))
        object.__setattr__(self, "stiffness", _vec3(self.stiffness, "stiffness", nonneg=True))
        object.__setattr__(self, "damping", _vec3(self.damping, "damping", nonneg=True))
        object.__setattr__(self, "loss_factor",
                           check_nonnegative(self.loss_factor, "loss_factor", error=ModelError))


@dataclass(frozen=True)
class MountModes:
    """Rigid-body modes of the engine on its mounts.

    Attributes
    ----------
    natural_frequencies : ndarray
        Undamped natural frequencies, Hz, ascending.
    mode_shapes : ndarray
        (6, 6): column j is mode j in body coordinates (m, rad), mass-normalised.
    dominant : tuple of str
        The DOF with the largest share of kinetic energy in each mode.
    energy_fraction : ndarray
        (6, 6): share of each DOF (rows) in each mode's kinetic energy (columns).
    """

    natural_frequencies: np.ndarray
    mode_shapes: np.ndarray
    dominant: tuple
    energy_fraction: np.ndarray

    def to_frame(self):
        """One row per mode: frequency and kinetic-energy shares per DOF."""
        import pandas as pd

        data = {"mode": np.arange(1, 7), "frequency_hz": self.natural_frequencies,
                "dominant": list(self.dominant)}
        for k, name in enumerate(DOF_NAMES):
            data[f"energy_{name}"] = self.energy_fraction[k]
        return pd.DataFrame(data)

    def plot(self, ax=None):
        """Kinetic-energy distribution of each mode (stacked bars); returns the figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots()
        else:
            fig = ax.figure
        bottom = np.zeros(6)
        x = np.arange(6)
        for k, name in enumerate(DOF_NAMES):
            ax.bar(x, self.energy_fraction[k], bottom=bottom, label=name)
            bottom += self.energy_fraction[k]
        ax.set_xticks(x, [f"{f:.2f} Hz" for f in self.natural_frequencies])
        ax.set_ylabel("kinetic energy share")
        ax.legend(ncol=3)
        return fig


@dataclass(frozen=True)
class MountResponse:
    """Harmonic response of the mounted engine.

    Complex amplitudes (peak) of e^{iΩt}: real signal = Re(amplitude · e^{iΩt}).

    Attributes
    ----------
    freq_hz : ndarray
        (nf,) excitation frequencies, Hz.
    body : ndarray
        (nf, 6) CG translation (m) and rotation (rad).
    points : ndarray
        (np, 3) points where the motion was evaluated, m.
    displacement, velocity, acceleration : ndarray
        (nf, np, 3) at the points, m, m/s, m/s².
    mount_forces : ndarray
        (nf, n_mounts, 3) force transmitted to the foundation through each mount, N.
    transmitted : ndarray
        (nf, 3) total force on the foundation, N.
    mount_names : tuple of str
    """

    freq_hz: np.ndarray
    body: np.ndarray
    points: np.ndarray
    displacement: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    mount_forces: np.ndarray
    transmitted: np.ndarray
    mount_names: tuple

    def to_frame(self):
        """Rows per frequency × mount: magnitudes of the transmitted force components (N)."""
        import pandas as pd

        rows = []
        for k, f in enumerate(self.freq_hz):
            for j, name in enumerate(self.mount_names):
                fx, fy, fz = np.abs(self.mount_forces[k, j])
                rows.append({"freq_hz": f, "mount": name, "force_x_n": fx, "force_y_n": fy,
                             "force_z_n": fz})
        return pd.DataFrame(rows)

    def plot(self, ax=None):
        """|total transmitted force| per axis against frequency; returns the figure."""
        import matplotlib.pyplot as plt

        if ax is None:
            fig, ax = plt.subplots()
        else:
            fig = ax.figure
        for k, name in enumerate("xyz"):
            ax.semilogy(self.freq_hz, np.abs(self.transmitted[:, k]) + 1e-300, label=name)
        ax.set_xlabel("frequency (Hz)")
        ax.set_ylabel("force on foundation (N)")
        ax.legend()
        return fig


class MountedEngine:
    """A rigid engine (mass, inertia, centre of gravity) on elastic mounts.

    Parameters
    ----------
    mass : float
        Engine mass, kg.
    inertia : array_like
        Inertia tensor about the CG in the mount frame, kg·m²: 3 principal values
        (I_xx, I_yy, I_zz) or a symmetric 3×3 matrix.
    cg : array_like
        Centre of gravity (x, y, z), m.
    mounts : sequence of Mount

    References
    ----------
    Liang 1948 ch. 4 §4-2 to §4-4; Den Hartog (1956) §3.2.

    Examples
    --------
    >>> m = [Mount(position=[x, y, -0.3], stiffness=[2e6, 2e6, 4e6])
    ...      for x in (0.0, 1.0) for y in (-0.4, 0.4)]
    >>> eng = MountedEngine(mass=800.0, inertia=[40.0, 90.0, 90.0], cg=[0.5, 0.0, 0.0],
    ...                     mounts=m)
    >>> round(float(eng.natural_frequencies()[0]), 3)
    13.858
    """

    def __init__(self, *, mass, inertia, cg, mounts, name="engine on mounts", source=None):
        self.mass = check_positive(mass, "mass", error=ModelError)
        j = check_finite_array(inertia, "inertia", error=ModelError)
        if j.shape == (3,):
            j = np.diag(j)
        if j.shape != (3, 3):
            raise ModelError(f"inertia must be 3 principal values or a 3x3 matrix, got shape "
                             f"{j.shape}")
        if not np.allclose(j, j.T, rtol=1e-12, atol=0):
            raise ModelError("inertia must be a symmetric matrix")
        if np.linalg.eigvalsh(j).min() <= 0:
            raise ModelError("inertia must be positive definite (kg m²)")
        self.inertia = j
        self.cg = _vec3(cg, "cg")
        self.mounts = tuple(mounts)
        if not self.mounts:
            raise ModelError("mounts must list at least one Mount")
        self.name = name
        self.source = source
        # singular = some rigid-body motion (practically) unrestrained. Judged on the
        # Jacobi-scaled stiffness D^-1/2 K D^-1/2 (D = diag K): unit-free (K mixes N/m and
        # N·m/rad) and blind to a direction that is merely soft, which stays exactly
        # computable. Its condition number κ bounds the relative error of the softest mode
        # (~eps·κ, Demmel & Veselić 1992); κ > 1e10 (error > ~1e-6) is refused
        k = self.stiffness_matrix()
        d = np.sqrt(np.diag(k))
        if np.any(d <= 0):
            lam = np.zeros(1)
        else:
            lam = np.linalg.eigvalsh(k / np.outer(d, d))
        if lam.min() <= 1e-10 * lam.max():
            raise ModelError("the mounts do not restrain all six rigid-body motions (the "
                             "stiffness matrix is singular); add mounts or stiffness components")

    # ---------------------------------------------------------------- matrices
    def mass_matrix(self) -> np.ndarray:
        """6×6 mass matrix about the CG, (kg, kg·m²)."""
        m = np.zeros((6, 6))
        m[:3, :3] = self.mass * np.eye(3)
        m[3:, 3:] = self.inertia
        return m

    def _assemble(self, attr) -> np.ndarray:
        out = np.zeros((6, 6))
        for mt in self.mounts:
            t = _transfer(mt.position - self.cg)
            out += t.T @ np.diag(getattr(mt, attr)) @ t
        return out

    def stiffness_matrix(self) -> np.ndarray:
        """6×6 stiffness matrix about the CG (N/m, N·m/rad)."""
        return self._assemble("stiffness")

    def damping_matrix(self) -> np.ndarray:
        """6×6 viscous damping matrix about the CG."""
        return self._assemble("damping")

    def _hysteretic(self) -> np.ndarray:
        out = np.zeros((6, 6))
        for mt in self.mounts:
            t = _transfer(mt.position - self.cg)
            out += mt.loss_factor * (t.T @ np.diag(mt.stiffness) @ t)
        return out

    # ---------------------------------------------------------------- modes
    def modes(self) -> MountModes:
        """Undamped rigid-body modes (symmetric generalised eigenproblem, exact).

        Returns
        -------
        MountModes

        Examples
        --------
        >>> m = [Mount(position=[x, y, 0.0], stiffness=[1e6, 1e6, 2e6])
        ...      for x in (-0.5, 0.5) for y in (-0.3, 0.3)]
        >>> eng = MountedEngine(mass=400.0, inertia=[20.0, 40.0, 45.0], cg=[0, 0, 0], mounts=m)
        >>> modes = eng.modes()
        >>> modes.dominant[-1], round(float(modes.natural_frequencies[-1]), 3)
        ('ry', 35.588)
        """
        from scipy.linalg import eigh

        k, m = self.stiffness_matrix(), self.mass_matrix()
        # scale to unit diagonal mass so translations and rotations are comparable
        s = 1.0 / np.sqrt(np.diag(m))
        lam, v = eigh(k * np.outer(s, s), m * np.outer(s, s))
        v = v * s[:, None]
        lam = np.clip(lam, 0.0, None)
        energy = (v * (m @ v))
        energy = energy / energy.sum(axis=0, keepdims=True)
        dominant = tuple(DOF_NAMES[int(np.argmax(energy[:, j]))] for j in range(6))
        return MountModes(natural_frequencies=np.sqrt(lam) / (2 * np.pi), mode_shapes=v,
                          dominant=dominant, energy_fraction=energy)

    def natural_frequencies(self) -> np.ndarray:
        """Undamped natural frequencies, Hz, ascending."""
        return self.modes().natural_frequencies

    # ---------------------------------------------------------------- response
    def response(self, forces, moments=None, freq_hz=None, *, point=(0.0, 0.0, 0.0), at=None):
        """Harmonic response to forces and moments applied at ``point``.

        Parameters
        ----------
        forces : array_like
            Complex force amplitudes (F_x, F_y, F_z), N: shape (3,) for all frequencies or
            (nf, 3) one per frequency.
        moments : array_like, optional
            Complex moment amplitudes about ``point``, N·m, same shapes.
        freq_hz : float or array_like
            Excitation frequencies, Hz.
        point : array_like
            Where the forces act, m (default the origin on the crankshaft axis).
        at : array_like, optional
            (np, 3) points whose motion is wanted (default: the CG).

        Returns
        -------
        MountResponse

        Examples
        --------
        >>> m = [Mount(position=[x, y, -0.3], stiffness=[2e6, 2e6, 4e6])
        ...      for x in (0.0, 1.0) for y in (-0.4, 0.4)]
        >>> eng = MountedEngine(mass=800.0, inertia=[40.0, 90.0, 90.0], cg=[0.5, 0.0, 0.0],
        ...                     mounts=m)
        >>> r = eng.response([0, 0, 1000.0], freq_hz=0.0, point=[0.5, 0, 0])
        >>> round(float(r.body[0, 2].real * 1e6), 3)   # static: F / Σk_z, µm
        62.5
        """
        if freq_hz is None:
            raise ModelError("freq_hz is required (Hz)")
        f = np.atleast_1d(check_finite_array(freq_hz, "freq_hz", error=ModelError))
        if (f < 0).any():
            raise ModelError("freq_hz must be >= 0")
        nf = f.size
        fo = self._amplitudes(forces, "forces", nf)
        mo = self._amplitudes(moments, "moments", nf) if moments is not None else np.zeros(
            (nf, 3), complex)
        p = _vec3(point, "point")
        d = p - self.cg
        gen = np.concatenate([fo, mo + np.cross(np.broadcast_to(d, fo.shape), fo)], axis=1)
        k, m, c = self.stiffness_matrix(), self.mass_matrix(), self.damping_matrix()
        h = self._hysteretic()
        body = np.empty((nf, 6), dtype=complex)
        for i, fi in enumerate(f):
            w = 2 * np.pi * fi
            dyn = k + 1j * h - w * w * m + 1j * w * c
            body[i] = np.linalg.solve(dyn, gen[i])
        pts = self.cg[None, :] if at is None else check_finite_array(at, "at", error=ModelError)
        pts = np.atleast_2d(pts)
        if pts.shape[1] != 3:
            raise ModelError(f"at must be (n, 3) points, got shape {pts.shape}")
        disp = np.stack([body @ _transfer(q - self.cg).T for q in pts], axis=1)
        w = 2 * np.pi * f[:, None, None]
        mf = np.empty((nf, len(self.mounts), 3), dtype=complex)
        for j, mt in enumerate(self.mounts):
            u = body @ _transfer(mt.position - self.cg).T
            kc = mt.stiffness * (1 + 1j * mt.loss_factor)
            mf[:, j] = u * kc + 1j * w[:, 0] * u * mt.damping
        return MountResponse(freq_hz=f, body=body, points=pts, displacement=disp,
                             velocity=1j * w * disp, acceleration=-(w**2) * disp,
                             mount_forces=mf, transmitted=mf.sum(axis=1),
                             mount_names=tuple(mt.name or f"mount {j + 1}"
                                               for j, mt in enumerate(self.mounts)))

    @staticmethod
    def _amplitudes(values, name, nf):
        arr = np.asarray(values, dtype=complex)
        if not np.all(np.isfinite(arr)):
            raise ModelError(f"{name} contains NaN/inf")
        if arr.shape == (3,):
            return np.broadcast_to(arr, (nf, 3)).copy()
        if arr.shape == (nf, 3):
            return arr
        raise ModelError(f"{name} must have shape (3,) or ({nf}, 3), got {arr.shape}")

    def receptance(self, freq_hz, *, at, directions, point=(0.0, 0.0, 0.0)):
        """Displacement of sensor points along their directions per unit generalised load.

        Parameters
        ----------
        freq_hz : float or array_like
            Excitation frequencies, Hz.
        at : array_like
            (n, 3) sensor points, m.
        directions : array_like
            (n, 3) unit vectors of the sensors' sensitive axes (see :func:`direction_vector`).
        point : array_like
            Where the loads act, m: forces at ``point``, moments about it.

        Returns
        -------
        ndarray (nf, n, 6), complex
            ``G[f, s, k]``: displacement (m) of sensor ``s`` along its direction per unit
            component ``k`` of (F_x, F_y, F_z (N), M_x, M_y, M_z (N·m)) at frequency ``f``
            (:data:`LOAD_NAMES`): the same exact 6×6 solve as :meth:`response`. Velocity and
            acceleration are ``i w G`` and ``-w**2 G``.

        Examples
        --------
        >>> m = [Mount(position=[x, y, -0.3], stiffness=[2e6, 2e6, 4e6])
        ...      for x in (0.0, 1.0) for y in (-0.4, 0.4)]
        >>> eng = MountedEngine(mass=800.0, inertia=[40.0, 90.0, 90.0], cg=[0.5, 0.0, 0.0],
        ...                     mounts=m)
        >>> g = eng.receptance(0.0, at=[[0.5, 0.0, 0.0]], directions=[[0, 0, 1]],
        ...                    point=[0.5, 0, 0])
        >>> round(float(g[0, 0, 2].real * 1e9), 3)       # static: 1 / sum k_z, nm per N
        62.5
        """
        f = np.atleast_1d(check_finite_array(freq_hz, "freq_hz", error=ModelError))
        if (f < 0).any():
            raise ModelError("freq_hz must be >= 0")
        pts = np.atleast_2d(check_finite_array(at, "at", error=ModelError))
        dirs = np.atleast_2d(check_finite_array(directions, "directions", error=ModelError))
        if pts.shape[1] != 3 or dirs.shape != pts.shape:
            raise ModelError(f"at and directions must both be (n, 3), got {pts.shape} and "
                             f"{dirs.shape}")
        d = _vec3(point, "point") - self.cg
        # generalised load about the CG: [F; M + d x F]
        gamma = np.eye(6)
        gamma[3:, :3] = _skew(d)
        # row s: direction_s . T(p_s - cg)
        rows = np.stack([u @ _transfer(p - self.cg) for p, u in zip(pts, dirs)])   # (n, 6)
        k, m, c = self.stiffness_matrix(), self.mass_matrix(), self.damping_matrix()
        h = self._hysteretic()
        w = 2 * np.pi * f[:, None, None]
        dyn = (k + 1j * h)[None] - w * w * m[None] + 1j * w * c[None]          # (nf, 6, 6)
        return rows[None] @ np.linalg.solve(dyn, np.broadcast_to(gamma, dyn.shape))

    def transmissibility(self, freq_hz, *, direction="z", point=None):
        """Force transmissibility |F_foundation| / |F_applied| for a unit force along one axis.

        Parameters
        ----------
        freq_hz : array_like
            Hz.
        direction : {"x", "y", "z"}
        point : array_like, optional
            Where the force acts (default the CG).

        Returns
        -------
        ndarray
            Ratio of the magnitude of the total transmitted force vector to the applied force.

        Examples
        --------
        >>> m = [Mount(position=[x, y, -0.3], stiffness=[2e6, 2e6, 4e6])
        ...      for x in (0.0, 1.0) for y in (-0.4, 0.4)]
        >>> eng = MountedEngine(mass=800.0, inertia=[40.0, 90.0, 90.0], cg=[0.5, 0.0, 0.0],
        ...                     mounts=m)
        >>> fz = float(np.sqrt(16e6 / 800) / (2 * np.pi))
        >>> round(float(eng.transmissibility([fz * np.sqrt(2)], direction="z")[0]), 6)
        1.0
        """
        from ._validate import check_option

        axis = "xyz".index(check_option(direction, "direction", ["x", "y", "z"],
                                        error=ModelError))
        unit = np.zeros(3)
        unit[axis] = 1.0
        r = self.response(unit, freq_hz=freq_hz, point=self.cg if point is None else point)
        return np.linalg.norm(r.transmitted, axis=1)

    def to_frame(self):
        """Table of the mounts (positions m, stiffness N/m, damping N·s/m)."""
        import pandas as pd

        rows = []
        for j, mt in enumerate(self.mounts):
            rows.append({"mount": mt.name or f"mount {j + 1}",
                         **{f"{a}_m": v for a, v in zip("xyz", mt.position)},
                         **{f"k{a}_n_per_m": v for a, v in zip("xyz", mt.stiffness)},
                         **{f"c{a}_ns_per_m": v for a, v in zip("xyz", mt.damping)},
                         "loss_factor": mt.loss_factor})
        return pd.DataFrame(rows)

    @classmethod
    def from_toml(cls, path):
        """Load the top-level ``[mounts]`` table.

        Keys: ``mass`` (kg), ``inertia`` (3 values or 3×3, kg·m², about the CG), ``cg``
        (x, y, z m), and ``[[mounts.mount]]`` entries with ``position``, ``stiffness``
        (N/m per axis), optional ``damping`` (N·s/m per axis), ``loss_factor`` and ``name``.
        Other top-level tables are ignored.

        Raises
        ------
        ModelError
            Naming the file and key.
        """
        doc = load_toml(path)
        t = doc.table("mounts", default=None)
        if t is None:
            raise ModelError(f"{path}: has no [mounts] table")
        inertia_raw = t.raw("inertia")
        if isinstance(inertia_raw, list) and inertia_raw and isinstance(inertia_raw[0], list):
            try:
                inertia = np.array(inertia_raw, dtype=float)
            except (TypeError, ValueError):
                t.fail("inertia", "must be 3 numbers or a 3x3 array of numbers")
        else:
            inertia = t.numbers("inertia", length=3, low=0.0, strict_low=True, unit="kg*m^2",
                                plausible=(1e-3, 1e7))
        mounts = []
        for mt in t.tables("mount"):
            mounts.append(Mount(
                position=mt.numbers("position", length=3, unit="m", plausible=(1e-4, 100.0)),
                stiffness=mt.numbers("stiffness", length=3, low=0.0, unit="N/m",
                                     plausible=(1e2, 1e11)),
                damping=mt.numbers("damping", [0.0, 0.0, 0.0], length=3, low=0.0, unit="N*s/m",
                                   plausible=(1e-2, 1e9)),
                loss_factor=mt.number("loss_factor", 0.0, low=0.0, unit="1",
                                      plausible=(1e-5, 2.0)),
                name=mt.string("name", "")))
            mt.check_unknown()
        if not mounts:
            t.fail("mount", "must list at least one [[mounts.mount]]")
        kwargs = dict(mass=t.positive("mass", unit="kg", plausible=(0.1, 1e7)), inertia=inertia,
                      cg=t.numbers("cg", length=3, unit="m", plausible=(1e-4, 100.0)),
                      name=t.string("name", "engine on mounts"))
        t.check_unknown(["description"])
        try:
            return cls(mounts=mounts, source=str(path), **kwargs)
        except ModelError as exc:
            raise ModelError(f"{path}: [mounts] {exc}") from None


def excitation_from_unbalance(unbalance, order):
    """Force and moment phasors in the mount frame for one order of a balance result.

    Parameters
    ----------
    unbalance : xarray.Dataset
        From :func:`predict.balance.unbalance` (needs the phasor variables).
    order : int
        Which order.

    Returns
    -------
    dict
        ``force`` (3,) complex N, ``moment`` (3,) complex N·m about ``point``, ``point``
        (reference position on the crankshaft axis, m), ``freq_hz`` (order × speed), such that
        the real signal is Re(amplitude · e^{i n ω t}) with θ = ω t.

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> from crankbench.predict.balance import unbalance
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
    ...            reciprocating_mass=2.0)
    >>> ex = excitation_from_unbalance(unbalance(e, omega=100.0, orders=(1,)), 1)
    >>> np.abs(ex["force"]).round(6).tolist(), round(ex["freq_hz"], 4)
    ([0.0, 0.0, 1000.0], 15.9155)
    """
    sel = unbalance.sel(order=order)
    P = complex(sel["force_forward_phasor"])
    Q = complex(sel["force_backward_phasor"])
    PM = complex(sel["moment_forward_phasor"])
    QM = complex(sel["moment_backward_phasor"])
    vertical = P + np.conj(Q)
    horizontal = -1j * (P - np.conj(Q))
    pitch = PM + np.conj(QM)            # Σ dz · F_vertical
    yaw = -1j * (PM - np.conj(QM))      # Σ dz · F_horizontal
    omega = float(unbalance.attrs["omega"])
    return {"force": np.array([0.0, horizontal, vertical], dtype=complex),
            "moment": np.array([0.0, -pitch, yaw], dtype=complex),
            "point": np.array([float(unbalance.attrs["reference_position"]), 0.0, 0.0]),
            "freq_hz": order * omega / (2 * np.pi)}


def direction_vector(direction) -> np.ndarray:
    """Unit vector of a sensor's sensitive axis in the mount frame.

    Parameters
    ----------
    direction : str or array_like
        ``"x"``, ``"y"``, ``"z"`` with an optional sign (``"-y"``), the words ``"axial"``
        (x), ``"horizontal"``/``"lateral"``/``"transverse"`` (y), ``"vertical"`` (z), or
        three numbers (normalised here).

    Returns
    -------
    ndarray (3,)

    Raises
    ------
    ModelError
        An unknown word or a zero vector.

    Examples
    --------
    >>> direction_vector("-y").tolist(), direction_vector([0, 3, 4]).tolist()
    ([0.0, -1.0, 0.0], [0.0, 0.6, 0.8])
    """
    if isinstance(direction, str):
        text = direction.strip().lower()
        sign = -1.0 if text.startswith("-") else 1.0
        key = text.lstrip("+-").strip()
        if key not in _AXES:
            raise ModelError(f"direction={direction!r} is not one of x, y, z (optionally signed), "
                             f"{', '.join(k for k in _AXES if len(k) > 1)} or three numbers")
        out = np.zeros(3)
        out[_AXES[key]] = sign
        return out
    arr = _vec3(direction, "direction")
    norm = float(np.linalg.norm(arr))
    if norm == 0.0:
        raise ModelError(f"direction={arr.tolist()} must not be the zero vector")
    return arr / norm


@dataclass(frozen=True)
class BlockExcitation:
    """Per-order shaking loads on the engine block, in the mount frame.

    Each order ``q``'s load (F_x, F_y, F_z, M_x, M_y, M_z) about ``point`` is
    ``Re[(load(Omega) gas_q + Omega**2 inertia_q) e^{i q psi}]``, ``psi`` the crank angle of
    cylinder 1 from its firing TDC: ``inertia`` holds the free inertia forces and moments of
    the balance model (integer orders, rotating masses, counterweights, added masses) and the
    inertia part of the torque reaction, ``gas`` the gas-torque reaction (roll, ``M_x``) per
    unit gas load.

    Attributes
    ----------
    orders : ndarray (n_o,)
    inertia : ndarray (n_o, 6), complex
        Per unit speed squared: N/(rad/s)², N·m/(rad/s)².
    gas : ndarray (n_o, 6), complex
        N, N·m per unit load factor.
    point : ndarray (3,)
        The reference point on the crankshaft axis (x = the engine's reference position), m.
    """

    orders: np.ndarray
    inertia: np.ndarray
    gas: np.ndarray
    point: np.ndarray

    def at(self, omega, load=1.0) -> np.ndarray:
        """Loads (n_s, n_o, 6) at crank speeds ``omega`` (rad/s) and gas-load factors."""
        w = np.atleast_1d(np.asarray(omega, float))
        lf = np.broadcast_to(np.asarray(load, float), w.shape)
        return lf[:, None, None] * self.gas[None] + (w**2)[:, None, None] * self.inertia[None]


def _roll_harmonics(engine, excitation, orders):
    """Total crankshaft torque per order: gas part and inertia part per unit speed squared,
    N·m, ``T(psi) = Re[(gas + Omega**2 inertia) e^{i q psi}]`` summed over the cylinders with
    their firing angles."""
    g = excitation.harmonics(np.array([0.0]), orders)[0]            # (n_o, z)
    i1 = excitation.harmonics(np.array([1.0]), orders)[0] - g
    phase = np.exp(-1j * np.deg2rad(np.outer(orders, engine.firing_angles_deg())))
    return (g * phase).sum(axis=1), (i1 * phase).sum(axis=1)


def block_excitation(engine, orders, *, excitation=None, counterweights=(),
                     torque_reaction=True):
    """Shaking loads per order on the block of an engine: inertia forces and moments of every
    layout (:func:`predict.balance.unbalance`) and the crankshaft-torque reaction.

    Parameters
    ----------
    engine : predict.engine.Engine
    orders : sequence of float
        Orders of the cycle (half orders for a 4-stroke carry only the torque reaction).
    excitation : predict.torsion.excitation.Excitation, optional
        Cylinder torque harmonics (gas and inertia) covering ``orders``. None: the inertia
        part of the torque reaction alone, from :func:`predict.forces.engine_torque` (an
        engine without combustion data), unless ``torque_reaction`` is False.
    counterweights : sequence of predict.balance.Counterweight
        Masses fixed to the crankshaft (counterweights, added or trial masses).
    torque_reaction : bool
        Include the reaction to the crankshaft torque (roll, ``M_x``).

    Returns
    -------
    BlockExcitation

    Notes
    -----
    The balance model's phasors refer to the shaft angle θ of throw 1; θ = ψ + θ_f with θ_f
    the shaft angle of cylinder 1's firing TDC, so an order-n phasor gains ``e^{i n θ_f}``.
    The reaction on the block is the crankshaft torque about +x (the crank turns about −x).

    Examples
    --------
    >>> from crankbench.predict.engine import Engine
    >>> e = Engine(crank_angles_deg=[0], crank_radius=0.05, rod_length=0.2,
    ...            reciprocating_mass=2.0)
    >>> ex = block_excitation(e, [1.0, 2.0])
    >>> # vertical force, N: m r w² (1, A₂), A₂ = λ + λ³/4 + 15λ⁵/128 + … = 0.25403 (λ = 1/4)
    >>> np.abs(ex.at(100.0)[0, :, 2]).round(2).tolist()
    [1000.0, 254.03]
    """
    from .balance import unbalance

    orders = np.atleast_1d(check_finite_array(orders, "orders", error=ModelError))
    if (orders <= 0).any():
        raise ModelError(f"orders={orders.tolist()} must all be > 0")
    n_o = orders.size
    inertia = np.zeros((n_o, 6), complex)
    gas = np.zeros((n_o, 6), complex)
    theta_f = float(engine.firing_tdc_shaft_angle)
    integer = sorted({int(round(q)) for q in orders if abs(q - round(q)) < 1e-9})
    ub = unbalance(engine, omega=1.0, orders=tuple(integer),
                   counterweights=tuple(counterweights)) if integer else None
    point = np.array([float(engine.reference_position), 0.0, 0.0])
    for i, q in enumerate(orders):
        n = int(round(q))
        if ub is not None and abs(q - n) < 1e-9:
            ex = excitation_from_unbalance(ub, n)
            shift = np.exp(1j * n * theta_f)
            inertia[i, :3] = ex["force"] * shift
            inertia[i, 3:] = ex["moment"] * shift
    if excitation is not None and torque_reaction:
        roll_gas, roll_in = _roll_harmonics(engine, excitation, orders)
        inertia[:, 3] += roll_in
        gas[:, 3] += roll_gas
    elif torque_reaction:
        from .forces import engine_torque

        # inertia torque per unit speed squared over one working cycle (exact to round-off
        # for the orders a 1440-point cycle resolves)
        n = 1440
        psi = np.arange(n) * (np.pi * engine.cycle) / n
        torque = engine_torque(engine, psi, omega=1.0)
        inertia[:, 3] += 2.0 * np.exp(-1j * np.outer(orders, psi)) @ torque / n
    return BlockExcitation(orders=orders, inertia=inertia, gas=gas, point=point)
