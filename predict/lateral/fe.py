"""Beam finite-element rotor model: critical speeds, Campbell diagram, unbalance response.

A rotor is a line of shaft sections (hollow or solid circular, each of its own material), rigid
disks (mass, diametral and polar inertia) and bearings (linear springs and dampers to ground,
cross-coupling allowed; an infinite stiffness makes the support rigid). Each node carries four
degrees of freedom: the lateral displacements u (x), v (y) and the slopes φu = ∂u/∂z,
φv = ∂v/∂z. Spin is about +z (x towards y); forward whirl turns the same way.

Shaft elements are two-node Hermite beams, Euler-Bernoulli or Timoshenko (shear deformation
with Cowper's shear coefficient and rotary inertia, interdependent interpolation). Their
frequencies converge to the continuum as O(h⁴) in the element length h for Euler-Bernoulli and
as O(h²) for Timoshenko (the element's shear strain is constant per element; measured rates
2.00 and 4.00, see tests); each result carries a Richardson estimate of that discretisation
error from a mesh twice as coarse.

Eigen-solves are symmetric wherever the physics allows: M φ = (1/ω²) K φ at rest, and for an
undamped gyroscopic rotor the Hermitian pencil ω diag(M, K) x = −i [[−ΩG, −K], [K, 0]] x;
only damped or cross-coupled rotors use the general (non-symmetric) solver. All are solved in
inverse (flexibility) form when the rotor is supported, so the lowest modes keep full relative
precision; the remaining round-off grows like ε·n⁴ (≈1e-8 relative at 256 elements of one
span), so beyond ~100 elements per span refining no longer helps.

Equations of motion: M q̈ + (C + Ω G) q̇ + K q = f, with G skew-symmetric (gyroscopic
coupling of the two bending planes by the polar inertia of disks and shaft).

References
----------
.. [1] M. I. Friswell, J. E. T. Penny, S. D. Garvey, A. W. Lees, *Dynamics of Rotating
   Machines*, Cambridge University Press (2010), ch. 5 (finite-element rotor models, element
   matrices eq. 5.x, Campbell diagrams, critical speeds §5.9) and ch. 3 (Jeffcott rotor).
.. [2] J. S. Przemieniecki, *Theory of Matrix Structural Analysis*, McGraw-Hill (1968),
   §5.6 and §11.6 (beam element with shear deformation and rotary inertia).
.. [3] G. R. Cowper, "The shear coefficient in Timoshenko's beam theory", J. Appl. Mech. 33
   (1966) 335-340.
.. [4] Shi Zhiqing, *Engine Dynamics*, ch. 4 §27 (critical speeds of shafts), §28.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.linalg

from crankbench.predict._deprecate import renamed

from .._validate import check_finite_array, check_int, check_option, check_positive
from ..errors import ModelError
from .elements import STEEL, Bearing, Disk, Material, ShaftSection, element_matrices
from .results import CampbellDiagram, CriticalSpeeds, LateralModes, UnbalanceResponse

__all__ = ["Material", "STEEL", "ShaftSection", "Disk", "Bearing", "Rotor", "THEORIES"]

log = logging.getLogger("crankbench")

THEORIES = ("timoshenko", "euler-bernoulli")
_TOL = 1e-9  # m: positions closer than this are the same node


def _small_blas(n_dof: int):
    """Single-threaded BLAS for small dense problems (:func:`predict._threads.limit_blas`).

    Threaded BLAS on matrices of a few hundred rows costs more in synchronisation than it
    gains, badly so on a loaded machine (measured 5-20x slower); large models keep the
    default threading.
    """
    from .._threads import limit_blas

    return limit_blas(size=n_dof)


def _hermitian_eigh(h_re, h_im, s, top=None):
    """Eigenpairs of the Hermitian pencil (h_re + i h_im) x = λ s x, s real positive definite
    (None: identity),
    through the real symmetric form [[h_re, −h_im], [h_im, h_re]] of twice the size (every
    eigenvalue appears twice; [x_r; x_i] and [−x_i; x_r] are x and i x). Real LAPACK is used
    because small complex solves are much slower under threaded BLAS.

    ``top``: compute only the ``top`` largest complex eigenvalues (a subset solve; a few
    extra are computed so that repeated pairs are not cut).

    Returns ascending eigenvalues and complex eigenvectors (columns), one per complex pair.
    Raises numpy.linalg.LinAlgError if ``s`` is not positive definite.
    """
    n = h_re.shape[0]
    big = np.block([[h_re, -h_im], [h_im, h_re]])
    subset = None
    if top is not None and 2 * (top + 2) < 2 * n:
        subset = [2 * n - 2 * (top + 2), 2 * n - 1]
    if s is None:  # standard problem
        lam, vec = scipy.linalg.eigh(big, subset_by_index=subset)
    else:
        zero = np.zeros_like(s)
        lam, vec = scipy.linalg.eigh(big, np.block([[s, zero], [zero, s]]),
                                     subset_by_index=subset)
    cvec = vec[:n] + 1j * vec[n:]
    tol = 1e-9 * max(np.abs(lam).max(), 1e-300)
    values, vectors = [], []
    i = 0
    while i < lam.size:
        j = i + 1
        while j < lam.size and lam[j] - lam[i] <= tol + 1e-9 * abs(lam[i]):
            j += 1
        m = (j - i) // 2 or 1
        u, _, _ = np.linalg.svd(cvec[:, i:j], full_matrices=False)
        values.extend([lam[i:j].mean()] * m)
        vectors.append(u[:, :m])
        i = j
    return np.asarray(values), np.concatenate(vectors, axis=1)


@dataclass(frozen=True)
class _Model:
    """Assembled matrices with the rigid dofs removed."""

    positions: np.ndarray
    n_elements: int
    K: np.ndarray
    M: np.ndarray
    C: np.ndarray
    G: np.ndarray
    free: np.ndarray  # indices of kept dofs in the full 4·n_nodes vector


@dataclass(frozen=True)
class Rotor:
    """Rotor model built from shaft sections, disks and bearings.

    Parameters
    ----------
    shaft : sequence of ShaftSection
        Sections from left to right; the shaft starts at z = 0.
    disks : sequence of Disk
    bearings : sequence of Bearing
    theory : {"timoshenko", "euler-bernoulli"}
        Shaft element theory. Timoshenko adds shear deformation; both include rotary inertia
        unless ``rotary_inertia=False`` (classical Euler-Bernoulli beam).
    max_element_length : float, optional
        Fidelity: longest shaft element, m (default: total length / 20). A section's own
        ``n_elements`` takes precedence.
    rotary_inertia : bool
        Include the shaft's rotary inertia (and its gyroscopic effect).
    name : str

    Examples
    --------
    >>> r = Rotor(shaft=[ShaftSection(length=1.0, outer_diameter=0.05)],
    ...           bearings=[Bearing(0.0, float("inf")), Bearing(1.0, float("inf"))],
    ...           theory="euler-bernoulli", rotary_inertia=False)
    >>> round(float(r.natural_frequencies(n_modes=1).frequency_hz[0]), 2)  # closed form 102.06
    102.06
    """

    shaft: tuple
    disks: tuple = ()
    bearings: tuple = ()
    theory: str = "timoshenko"
    max_element_length: float | None = None
    rotary_inertia: bool = True
    name: str = ""
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self):
        put = object.__setattr__
        put(self, "shaft", tuple(self.shaft))
        put(self, "disks", tuple(self.disks))
        put(self, "bearings", tuple(self.bearings))
        if not self.shaft:
            raise ModelError("shaft must contain at least one ShaftSection")
        for name, items, cls in (("shaft", self.shaft, ShaftSection), ("disks", self.disks, Disk),
                                 ("bearings", self.bearings, Bearing)):
            for i, item in enumerate(items):
                if not isinstance(item, cls):
                    raise ModelError(f"{name}[{i}] must be a {cls.__name__}, got "
                                     f"{type(item).__name__}")
        put(self, "theory", check_option(self.theory, "theory", THEORIES, error=ModelError))
        total = self.length
        if self.max_element_length is not None:
            put(self, "max_element_length", check_positive(
                self.max_element_length, "max_element_length", error=ModelError))
        for name, items in (("disks", self.disks), ("bearings", self.bearings)):
            for i, item in enumerate(items):
                if item.position > total + _TOL:
                    raise ModelError(f"{name}[{i}].position={item.position!r} m lies beyond the "
                                     f"shaft end at {total:g} m")
        self._check_size()

    def _check_size(self):
        """Refuse a mesh whose dense matrices cannot fit in memory (before any is allocated)."""
        from .._memory import check_allocation

        count = sum(n for *_, n in self._intervals(1))
        n_dof = 4.0 * (count + 1)
        # assembly holds K, M, C, G and their constrained copies: 8 dense n_dof² float64
        what = (f"shaft mesh of {count} elements ({n_dof:.0f} degrees of freedom; "
                + (f"max_element_length={self.max_element_length:g} m" if self.max_element_length
                   else "n_elements of the sections") + ")")
        check_allocation(8 * 8 * n_dof**2, what=what,
                         hint="use longer elements (max_element_length, n_elements)",
                         error=ModelError)

    @property
    def length(self) -> float:
        """Total shaft length, m."""
        return float(sum(s.length for s in self.shaft))

    @property
    def mass(self) -> float:
        """Total mass of shaft and disks, kg."""
        return float(sum(s.material.density * s.area * s.length for s in self.shaft)
                     + sum(d.mass for d in self.disks))

    # -- assembly --------------------------------------------------------------------------
    def _intervals(self, coarsen: int):
        """(section index, start m, end m, number of elements) of every meshed interval."""
        h_default = self.max_element_length or self.length / 20
        marks = sorted({d.position for d in self.disks} | {b.position for b in self.bearings})
        z0 = 0.0
        for si, sec in enumerate(self.shaft):
            z1 = z0 + sec.length
            cuts = [z0] + [m for m in marks if z0 + _TOL < m < z1 - _TOL] + [z1]
            h = sec.length / sec.n_elements if sec.n_elements else h_default
            for a, b in zip(cuts[:-1], cuts[1:]):
                n = max(1, math.ceil((b - a) / h - 1e-9))
                yield si, a, b, max(1, math.ceil(n / coarsen))
            z0 = z1

    def _mesh(self, coarsen: int):
        nodes, owner = [0.0], []
        for si, a, b, n in self._intervals(coarsen):
            nodes.extend(a + (b - a) * np.arange(1, n + 1) / n)
            owner.extend([si] * n)
        return np.asarray(nodes), owner

    def _assemble(self, coarsen: int = 1) -> _Model:
        key = ("model", coarsen)
        if key in self._cache:
            return self._cache[key]
        z, owner = self._mesh(coarsen)
        n = 4 * z.size
        K, M, C, G = (np.zeros((n, n)) for _ in range(4))
        for e, si in enumerate(owner):
            sec = self.shaft[si]
            L = z[e + 1] - z[e]
            mat = sec.material
            ei = mat.youngs_modulus * sec.area_moment
            phi = 0.0
            if self.theory == "timoshenko":
                phi = 12 * ei / (sec.shear_coefficient * mat.shear_modulus * sec.area * L**2)
            rho_i = mat.density * sec.area_moment if self.rotary_inertia else 0.0
            k, mt, mr = element_matrices(L, ei, mat.density * sec.area, rho_i, phi)
            iu = np.array([4 * e, 4 * e + 2, 4 * e + 4, 4 * e + 6])
            iv = iu + 1
            for idx in (iu, iv):
                K[np.ix_(idx, idx)] += k
                M[np.ix_(idx, idx)] += mt + mr
            # polar inertia ρ I_p = 2 ρ I couples the planes: Friswell et al. eq. 5.70
            G[np.ix_(iu, iv)] += 2 * mr
            G[np.ix_(iv, iu)] -= 2 * mr
        fixed = set()
        for d in self.disks:
            i = 4 * int(np.argmin(np.abs(z - d.position)))
            M[i, i] += d.mass
            M[i + 1, i + 1] += d.mass
            M[i + 2, i + 2] += d.diametral_inertia
            M[i + 3, i + 3] += d.diametral_inertia
            G[i + 2, i + 3] += d.polar_inertia
            G[i + 3, i + 2] -= d.polar_inertia
        for b in self.bearings:
            i = 4 * int(np.argmin(np.abs(z - b.position)))
            rx, ry = b.rigid
            if rx:
                fixed.add(i)
            if ry:
                fixed.add(i + 1)
            if b.clamp:
                fixed.update((i + 2, i + 3))
            K[i, i] += 0.0 if rx else b.kxx
            K[i + 1, i + 1] += 0.0 if ry else b.kyy
            K[i, i + 1] += b.kxy
            K[i + 1, i] += b.kyx
            C[i, i] += b.cxx
            C[i + 1, i + 1] += b.cyy
            C[i, i + 1] += b.cxy
            C[i + 1, i] += b.cyx
        free = np.array([i for i in range(n) if i not in fixed])
        sub = np.ix_(free, free)
        model = _Model(z, len(owner), K[sub], M[sub], C[sub], G[sub], free)
        self._cache[key] = model
        return model

    def _full(self, model: _Model, vec: np.ndarray) -> np.ndarray:
        out = np.zeros((4 * model.positions.size,) + vec.shape[1:], dtype=vec.dtype)
        out[model.free] = vec
        return out

    @staticmethod
    @staticmethod
    def _planes(vecs: np.ndarray):
        """(u, v, φu, φv) parts used for the whirl direction. Slopes count too (rad as m/m) so
        that tilting-only modes (a single pinned element) still have an orbit; a tilt whirls
        in the same sense as the translation it accompanies."""
        return vecs[0::4] + 0j, vecs[1::4] + 0j, vecs[2::4] + 0j, vecs[3::4] + 0j

    @classmethod
    def _circularise(cls, values: np.ndarray, full_vecs: np.ndarray, rtol: float = 1e-6):
        """Within clusters of repeated eigenvalues (isotropic rotor, no gyroscopic split),
        rotate the basis to the circular forward/backward combinations: eigenvectors of the
        whirl form Σ 2 Im(u v̄) relative to the displacement norm inside the cluster."""
        out = full_vecs.astype(complex)
        i = 0
        while i < values.size:
            j = i + 1
            while j < values.size and abs(values[j] - values[i]) <= rtol * max(abs(values[i]),
                                                                                1e-300):
                j += 1
            if j - i > 1:
                phi = out[:, i:j]
                u, v, pu, pv = cls._planes(phi)
                whirl = 1j * (u.conj().T @ v + pu.conj().T @ pv) - 1j * (
                    v.conj().T @ u + pv.conj().T @ pu)
                norm = (u.conj().T @ u + v.conj().T @ v + pu.conj().T @ pu
                        + pv.conj().T @ pv)
                try:
                    _, rot = scipy.linalg.eigh(whirl, norm)
                except np.linalg.LinAlgError:  # dependent basis: leave as computed
                    rot = np.eye(j - i)
                out[:, i:j] = phi @ rot
            i = j
        return out

    @classmethod
    def _whirl(cls, model_full_vecs: np.ndarray):
        u, v, pu, pv = cls._planes(model_full_vecs)
        num = 2 * np.sum(np.imag(u * np.conj(v)) + np.imag(pu * np.conj(pv)), axis=0)
        den = np.sum(np.abs(u) ** 2 + np.abs(v) ** 2 + np.abs(pu) ** 2 + np.abs(pv) ** 2,
                     axis=0)
        index = np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)
        labels = np.where(index > 0.1, "forward", np.where(index < -0.1, "backward", "mixed"))
        return index, labels

    # -- eigen-analysis --------------------------------------------------------------------
    def _eig(self, model: _Model, speed: float, n_modes: int):
        with _small_blas(model.K.shape[0]):
            return self._eig_dense(model, speed, n_modes)

    def _eig_dense(self, model: _Model, speed: float, n_modes: int):
        """Lowest modes, solved in inverse (flexibility) form when K is invertible: the
        wanted small eigenvalues then become the largest ones and keep full relative
        precision (a direct solve loses ~ε λ_max/λ_min, 1e-6 on a 128-element shaft)."""
        K, M = model.K, model.M
        D = model.C + speed * model.G
        scale = 1.0 / np.sqrt(np.diag(M))  # balance translations against slopes
        Ks, Ms, Ds = (scale[:, None] * A * scale[None, :] for A in (K, M, D))
        n = K.shape[0]
        symmetric = np.allclose(Ks, Ks.T, rtol=0, atol=1e-12 * np.abs(Ks).max())
        undamped = not np.any(model.C)
        lk = None
        if symmetric:
            try:
                lk = np.linalg.cholesky(Ks)
            except np.linalg.LinAlgError:
                lk = None  # unsupported (free) rotor: direct forms below
        omega = None
        if symmetric and not np.any(Ds):
            if lk is not None:
                k = min(n, n_modes + 3)  # subset solve of the largest μ
                mu, vec = scipy.linalg.eigh(Ms, Ks, subset_by_index=[n - k, n - 1])
                # M φ = μ K φ, μ = 1/ω²
                omega, vec = 1.0 / np.sqrt(mu[::-1]), vec[:, ::-1]
            else:
                lam, vec = scipy.linalg.eigh(Ks, Ms)
                omega = np.sqrt(np.clip(lam, 0.0, None))
            vec = vec.astype(complex)
        elif symmetric and undamped and lk is not None:
            # undamped gyroscopic rotor: ω diag(M, K) x = −i [[−ΩG, −K], [K, 0]] x is a
            # Hermitian pencil; with M = Lm Lmᵀ, K = Lk Lkᵀ its inverse is the standard
            # Hermitian problem i S y = (1/ω) y, S = [[0, Pᵀ], [−P, −Q]], P = Lk⁻¹ Lm,
            # Q = Lk⁻¹ ΩG Lk⁻ᵀ (skew), and q = Lk⁻ᵀ y₂.
            lm = np.linalg.cholesky(Ms)
            p = scipy.linalg.solve_triangular(lk, lm, lower=True)
            q = scipy.linalg.solve_triangular(
                lk, scipy.linalg.solve_triangular(lk, Ds.T, lower=True).T, lower=True)
            q = (q - q.T) / 2
            big = np.block([[np.zeros((n, n)), p.T], [-p, -q]])
            nu, y = _hermitian_eigh(np.zeros_like(big), big, None, top=n_modes + 1)
            keep = nu > 0
            omega = 1.0 / nu[keep]
            vec = scipy.linalg.solve_triangular(lk.T, y[n:, keep], lower=False)
        if omega is not None:
            zeta = np.zeros_like(omega)
        else:
            eye, zero = np.eye(n), np.zeros((n, n))
            try:  # inverse form: E z = σ z, σ = 1/s, E = [[−K⁻¹D, −K⁻¹M], [I, 0]]
                lu = scipy.linalg.lu_factor(Ks, check_finite=False)
                if not np.all(np.isfinite(lu[0])) or np.min(np.abs(np.diag(lu[0]))) <= (
                        1e-14 * np.abs(lu[0]).max()):
                    raise np.linalg.LinAlgError("singular stiffness")
                e = np.block([[-scipy.linalg.lu_solve(lu, Ds), -scipy.linalg.lu_solve(lu, Ms)],
                              [eye, zero]])
                sigma, vec = scipy.linalg.eig(e)
                ok = np.abs(sigma) > 1e-300
                s_val = np.full(sigma.shape, np.inf + 0j)
                s_val[ok] = 1.0 / sigma[ok]
            except (np.linalg.LinAlgError, ValueError):
                a = np.block([[zero, eye], [-Ks, -Ds]])
                b = np.block([[eye, zero], [zero, Ms]])
                s_val, vec = scipy.linalg.eig(a, b)
            finite = np.isfinite(s_val)
            keep = finite & (s_val.imag > 1e-9 * max(1.0, np.abs(s_val[finite]).max()))
            s_val, vec = s_val[keep], vec[:n, keep]
            omega = s_val.imag
            zeta = -s_val.real / np.abs(s_val)
        order = np.argsort(omega)[:n_modes + 1]  # one extra to close a repeated pair
        vec = self._circularise(omega[order], self._full(model, scale[:, None] * vec[:, order]))
        return omega[order][:n_modes], zeta[order][:n_modes], vec[:, :n_modes]

    @renamed(speed="spin_omega")
    def natural_frequencies(self, spin_omega: float = 0.0, *, n_modes: int = 6,
                            error_estimate: bool = True) -> LateralModes:
        """Damped natural frequencies and whirl directions at spin speed ``speed``.

        Parameters
        ----------
        spin_omega : float
            Spin speed Ω, rad/s.
        n_modes : int
            Number of lowest modes returned (an isotropic rotor at rest gives each frequency
            twice, one per bending plane).
        error_estimate : bool
            Also solve a mesh twice as coarse and report the Richardson estimate
            |ω_h − ω_2h|/(2^p − 1), p = 4 (Euler-Bernoulli) or 2 (Timoshenko).

        Returns
        -------
        LateralModes

        References
        ----------
        Friswell et al., *Dynamics of Rotating Machines*, §5.8 (eigenvalues, whirl directions).

        Examples
        --------
        >>> r = Rotor(shaft=[ShaftSection(length=1.0, outer_diameter=0.05)],
        ...           bearings=[Bearing(0.0, 1e7), Bearing(1.0, 1e7)],
        ...           disks=[Disk(0.5, mass=20.0, diametral_inertia=0.1, polar_inertia=0.2)])
        >>> m = r.natural_frequencies(spin_omega=300.0, n_modes=2)
        >>> m.whirl
        ('backward', 'forward')
        """
        spin_omega = float(check_finite_array(spin_omega, "spin_omega", ndim=0, error=ModelError))
        n_modes = check_int(n_modes, "n_modes", minimum=1, error=ModelError)
        model = self._assemble()
        omega, zeta, vec = self._eig(model, spin_omega, n_modes)
        index, labels = self._whirl(vec)
        err = np.full(omega.size, np.nan)
        if error_estimate:
            coarse = self._eig(self._assemble(coarsen=2), spin_omega, n_modes)[0]
            k = min(coarse.size, omega.size)
            rate = 4 if self.theory == "euler-bernoulli" else 2
            err[:k] = np.abs(omega[:k] - coarse[:k]) / (2**rate - 1)
        shapes = np.stack([vec[0::4].T, vec[1::4].T], axis=-1)
        peak = np.abs(shapes).reshape(shapes.shape[0], -1).max(axis=1)
        shapes = shapes / np.where(peak > 0, peak, 1.0)[:, None, None]
        return LateralModes(speed=spin_omega, omega=omega, damping_ratio=zeta,
                            whirl=tuple(labels.tolist()), whirl_index=index, error_estimate=err,
                            positions=model.positions, shapes=shapes, theory=self.theory,
                            n_elements=model.n_elements)

    def critical_speeds(self, orders=(1.0,), *, n_modes: int = 4,
                        speed_range_rpm=None) -> CriticalSpeeds:
        """Undamped critical speeds for excitation orders, by an exact eigen-solve.

        Setting the whirl frequency to k Ω in the undamped equations gives
        K φ = Ω² (k² M − i k G) φ, a Hermitian pencil solved directly (no Campbell-diagram
        interpolation, no root-finding); damping is ignored as in the classical definition.
        Exact for the discretised model; the discretisation error is O(h⁴) (Euler-Bernoulli)
        or O(h²) (Timoshenko).

        Parameters
        ----------
        orders : sequence of float
            Excitation orders (1 = unbalance, synchronous).
        n_modes : int
            Number of lowest critical speeds kept per order.
        speed_range_rpm : (float, float), optional
            Keep only critical speeds inside this range, rpm.

        Returns
        -------
        CriticalSpeeds

        References
        ----------
        Friswell et al., *Dynamics of Rotating Machines*, §5.9 (critical speeds);
        Shi, *Engine Dynamics* ch. 4 §27.

        Examples
        --------
        >>> r = Rotor(shaft=[ShaftSection(length=1.0, outer_diameter=0.05)],
        ...           bearings=[Bearing(0.0, float("inf")), Bearing(1.0, float("inf"))],
        ...           theory="euler-bernoulli", rotary_inertia=False)
        >>> round(float(r.critical_speeds(n_modes=1).speed_rpm[0]), 1)  # 60 × 102.058 Hz
        6123.5
        """
        orders = check_finite_array(orders, "orders", ndim=1, min_length=1, error=ModelError)
        if np.any(orders <= 0):
            raise ModelError(f"orders must be > 0, got {orders.tolist()}")
        n_modes = check_int(n_modes, "n_modes", minimum=1, error=ModelError)
        model = self._assemble()
        K, M, G = model.K, model.M, model.G
        scale = 1.0 / np.sqrt(np.diag(M))
        Ks, Ms, Gs = (scale[:, None] * A * scale[None, :] for A in (K, M, G))
        symmetric = np.allclose(Ks, Ks.T, rtol=0, atol=1e-12 * np.abs(Ks).max())
        rows = []
        with _small_blas(K.shape[0]):
            for k in orders:
                rows.extend(self._criticals_for_order(model, float(k), Ks, Ms, Gs, scale,
                                                      symmetric, n_modes, speed_range_rpm))
        omega = np.array([r[2] for r in rows])
        mode = np.ones(len(rows), dtype=int)
        seen: dict = {}
        for i, (k, w, _) in enumerate(rows):
            seen[(k, w)] = seen.get((k, w), 0) + 1
            mode[i] = seen[(k, w)]
        return CriticalSpeeds(omega=omega, order=np.array([r[0] for r in rows]),
                              whirl=tuple(r[1] for r in rows), mode=mode,
                              method="hermitian eigen-solve K φ = Ω² (k² M − i k G) φ",
                              n_elements=model.n_elements, theory=self.theory)

    def _criticals_for_order(self, model, k, Ks, Ms, Gs, scale, symmetric, n_modes,
                             speed_range_rpm):
        """Critical speeds of one order: rows (order, whirl, Ω)."""
        if symmetric:
            try:
                mu, vec = _hermitian_eigh(k**2 * Ms, -k * Gs, Ks,
                                          top=None if speed_range_rpm is not None
                                          else n_modes + 1)
            except np.linalg.LinAlgError:
                raise ModelError("the rotor is not supported (singular stiffness): add "
                                 "bearings before asking for critical speeds") from None
            keep = mu > 1e-14 * np.abs(mu).max()
            om = 1.0 / np.sqrt(mu[keep])
            vec = vec[:, keep]
        else:
            lam, vec = scipy.linalg.eig(Ks, k**2 * Ms - 1j * k * Gs)
            keep = (np.isfinite(lam) & (lam.real > 0)
                    & (np.abs(lam.imag) < 1e-8 * np.abs(lam)))
            om, vec = np.sqrt(lam[keep].real), vec[:, keep]
        order = np.argsort(om)
        om = om[order]
        full = self._circularise(om, self._full(model, scale[:, None] * vec[:, order]))
        labels = self._whirl(full)[1]
        if speed_range_rpm is not None:
            lo, hi = np.asarray(speed_range_rpm, dtype=float) * np.pi / 30
            inside = (om >= lo) & (om <= hi)
            om, labels = om[inside], labels[inside]
        return [(k, w, o) for o, w in zip(om[:n_modes], labels[:n_modes])]

    @renamed(speeds="spin_omega")
    def campbell(self, spin_omega, *, n_modes: int = 6, orders=(1.0,)) -> CampbellDiagram:
        """Campbell diagram: natural frequencies and whirl at each spin speed.

        Parameters
        ----------
        spin_omega : array_like
            Spin speeds, rad/s (>= 0).
        n_modes : int
            Modes per speed.
        orders : sequence of float
            Excitation orders whose lines and exact critical speeds are included.

        Returns
        -------
        CampbellDiagram

        Examples
        --------
        >>> r = Rotor(shaft=[ShaftSection(length=1.0, outer_diameter=0.05)],
        ...           bearings=[Bearing(0.0, 1e7), Bearing(1.0, 1e7)],
        ...           disks=[Disk(0.5, mass=20.0, diametral_inertia=0.1, polar_inertia=0.2)])
        >>> c = r.campbell([0.0, 500.0], n_modes=2)
        >>> c.omega.shape
        (2, 2)
        """
        spin_omega = check_finite_array(spin_omega, "spin_omega", ndim=1, min_length=1,
                                        error=ModelError)
        if np.any(spin_omega < 0):
            raise ModelError("speeds must be >= 0 rad/s")
        n_modes = check_int(n_modes, "n_modes", minimum=1, error=ModelError)
        model = self._assemble()
        omega = np.full((spin_omega.size, n_modes), np.nan)
        whirl = np.full((spin_omega.size, n_modes), "mixed", dtype=object)
        for i, s in enumerate(spin_omega):
            w, _, vec = self._eig(model, float(s), n_modes)
            omega[i, :w.size] = w
            whirl[i, :w.size] = self._whirl(vec)[1]
        crit = self.critical_speeds(orders, n_modes=n_modes,
                                    speed_range_rpm=(spin_omega.min() * 30 / np.pi,
                                                     spin_omega.max() * 30 / np.pi))
        return CampbellDiagram(speeds=spin_omega, omega=omega, whirl=whirl.astype(str),
                               orders=tuple(float(o) for o in np.atleast_1d(orders)),
                               criticals=crit)

    @renamed(speeds="spin_omega")
    def unbalance_response(self, spin_omega, unbalances, *, probes=None) -> UnbalanceResponse:
        """Synchronous steady-state response to rotating unbalances.

        Solves (K − Ω² M + iΩ (C + Ω G)) q = f with f = m e Ω² e^{iβ} (1, −i) on (u, v) of
        each unbalanced node (force rotating forward with the shaft).

        Parameters
        ----------
        spin_omega : array_like
            Spin speeds, rad/s.
        unbalances : sequence of (position, magnitude, angle)
            Axial position (m), unbalance m·e (kg·m) and angle β (rad) from the x axis.
        probes : array_like, optional
            Positions whose response is returned, m (default: each unbalance position).

        Returns
        -------
        UnbalanceResponse

        References
        ----------
        Friswell et al., *Dynamics of Rotating Machines*, §5.10 (unbalance response).

        Examples
        --------
        >>> r = Rotor(shaft=[ShaftSection(length=1.0, outer_diameter=0.05)],
        ...           bearings=[Bearing(0.0, 1e7, cxx=500.0), Bearing(1.0, 1e7, cxx=500.0)],
        ...           disks=[Disk(0.5, mass=20.0)])
        >>> res = r.unbalance_response([100.0], [(0.5, 1e-4, 0.0)])
        >>> res.response.shape
        (1, 1, 2)
        """
        spin_omega = check_finite_array(spin_omega, "spin_omega", ndim=1, min_length=1,
                                        error=ModelError)
        model = self._assemble()
        z = model.positions
        force = np.zeros(4 * z.size, dtype=complex)
        if not len(unbalances):
            raise ModelError("unbalances must list at least one (position, magnitude, angle)")
        for i, item in enumerate(unbalances):
            try:
                pos, mag, ang = (float(v) for v in item)
            except (TypeError, ValueError):
                raise ModelError(f"unbalances[{i}]={item!r} must be (position m, magnitude "
                                 "kg·m, angle rad)") from None
            node = self._node(z, pos, f"unbalances[{i}]")
            force[4 * node] += mag * np.exp(1j * ang)
            force[4 * node + 1] += -1j * mag * np.exp(1j * ang)
        probes = ([u[0] for u in unbalances] if probes is None
                  else check_finite_array(probes, "probes", ndim=1, min_length=1,
                                          error=ModelError))
        nodes = [self._node(z, float(p), "probes") for p in probes]
        f = force[model.free]
        out = np.empty((spin_omega.size, len(nodes), 2), dtype=complex)
        with _small_blas(model.K.shape[0]):
            self._solve_response(model, spin_omega, f, nodes, out)
        return UnbalanceResponse(speeds=spin_omega, positions=np.asarray(probes, dtype=float),
                                 response=out)

    def _solve_response(self, model, speeds, f, nodes, out):
        for i, s in enumerate(speeds):
            dyn = model.K - s**2 * model.M + 1j * s * (model.C + s * model.G)
            try:
                q = self._full(model, np.linalg.solve(dyn, s**2 * f))
            except np.linalg.LinAlgError:
                raise ModelError(f"speed {s:g} rad/s is exactly on an undamped critical speed: "
                                 "the response is unbounded; add bearing damping") from None
            out[i, :, 0] = q[[4 * n for n in nodes]]
            out[i, :, 1] = q[[4 * n + 1 for n in nodes]]

    @staticmethod
    def _node(z, pos, what) -> int:
        i = int(np.argmin(np.abs(z - pos)))
        if abs(z[i] - pos) > max(_TOL, 1e-6 * z[-1]):
            raise ModelError(f"{what} position {pos!r} m is not a node; nodes lie at disks, "
                             f"bearings and mesh points (nearest {z[i]:.6g} m) — add a Disk "
                             "or a section boundary there")
        return i

    def refined(self, factor: int = 2) -> "Rotor":
        """The same rotor with elements ``factor`` times shorter (for convergence studies)."""
        factor = check_int(factor, "factor", minimum=1, error=ModelError)
        h = (self.max_element_length or self.length / 20) / factor
        shaft = [replace(s, n_elements=s.n_elements * factor) if s.n_elements else s
                 for s in self.shaft]
        return replace(self, shaft=shaft, max_element_length=h)
