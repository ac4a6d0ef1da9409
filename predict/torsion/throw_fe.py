"""Crank-throw torsional stiffness from a 3-D elastic finite-element model of the throw.

A second method beside the empirical equivalent-length formulas of
:mod:`predict.torsion.throws`, and the only one of them that holds for throws outside their
range (overlapped pin and journal, thick webs).

Model
-----
The :class:`~predict.torsion.throws.CrankThrow` as an isotropic linear-elastic solid
(E = 2G(1 + ν)), coordinates z along the shaft, x towards the pin:

* two half journals of length l_j/2 and diameter D_j (bore d_j) at the ends;
* two webs of thickness h whose outline is the *obround* of width b around the journal and pin
  centres (two discs of diameter b about the journal and pin axes and the b-wide strip between
  them), solid (the bores do not pass through the webs);
* the pin of length l_p, diameter D_p (bore d_p) at crank radius R.

Corners are sharp: no fillets, counterweights, oil bores or undercuts; this is the idealised
throw the formulas' dimensions describe, not a drawing of a real one (fillets stiffen a throw,
so a real one is somewhat stiffer than this model).

The two mid-journal end sections are turned rigidly in their own plane by θ against each
other (u_x = -θ y, u_y = θ x) and are free to warp axially; the stiffness is the reaction
torque over θ. Reported as an equivalent length of plain shaft of the reference diameter,
``L_e = G π D_ref⁴ / (32 k)``, as the formulas are.

Discretisation and accuracy
---------------------------
A regular grid of trilinear hexahedra (finite-cell method): elements wholly inside the throw
take the exact 2×2×2 Gauss stiffness; elements cut by a cylinder or web edge are integrated
on 8 × 8 points across the section (× 2 Gauss points along z), so the geometry is resolved
below the element size; the axial layers follow the journal, web and pin boundaries exactly.
Jacobi-preconditioned conjugate gradients solve the system.

With imposed end rotations, a conforming displacement model has at least the true strain
energy: the grid's stiffness is an upper bound of the idealised throw's (up to the sub-point
geometry integration), and it falls as the grid is refined, about linearly in the element size
(the re-entrant corners where webs meet journal and pin). :func:`throw_stiffness_fe` solves on
two grids (``element_size`` and ``element_size / 1.5``) and extrapolates to zero size assuming
first order; ``uncertainty`` is the relative step from the finer grid to the extrapolated
value. Checked (tests/predict/test_throw_fe.py) against the closed form of a plain shaft
(a throw with the pin on the axis and webs of the journal's width, G J / L of the series of
its sections) within 0.5 %, solid and bored; the grid stiffness falls from the coarser to the
finer grid as the bound says; on the I6 sample throw the results at two element sizes
(10 mm and the default 7 mm) agree within the stated ``uncertainty``.

References
----------
.. [1] J. Parvizian, A. Düster, E. Rank, "Finite cell method", *Computational Mechanics* 41
   (2007) 121-133 (cut cells integrated on sub-points of a regular grid).
.. [2] O. C. Zienkiewicz, R. L. Taylor, *The Finite Element Method*, vol. 1 (the bound
   property of conforming displacement models).
"""

from __future__ import annotations

import functools
import logging

import numpy as np

from .._threads import limit_blas
from .._validate import check_positive, check_range
from ..errors import ModelError

__all__ = ["throw_stiffness_fe"]

log = logging.getLogger("crankbench")

#: refinement ratio between the two grids
_REFINE = 1.5
#: largest number of elements of one grid (memory: about 16 kB per element while assembling)
_MAX_ELEMENTS = 60_000
#: sub-points per element edge across the section for cut elements
_SUB = 8
_CORNERS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                     [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], float)


def _elasticity(young, poisson):
    lam = young * poisson / ((1 + poisson) * (1 - 2 * poisson))
    mu = young / (2 * (1 + poisson))
    d = np.zeros((6, 6))
    d[:3, :3] = lam
    d[np.arange(3), np.arange(3)] += 2 * mu
    d[3:, 3:] = mu * np.eye(3)
    return d


def _point_stiffness(size, points, weights, d):
    """Stiffness contribution of each local point (n, 24, 24) of a box hexahedron of
    edge lengths ``size`` (m); local coordinates in [-1, 1]³, weights summing to 8."""
    out = np.empty((len(points), 24, 24))
    jac = size[0] * size[1] * size[2] / 8.0
    sx, sy, sz = _CORNERS.T
    for q, (a, b, c) in enumerate(points):
        # dN_i/dx of N_i = (1 + s_x a)(1 + s_y b)(1 + s_z c)/8, local -> physical: 2/size
        dn = np.stack([sx * (1 + sy * b) * (1 + sz * c) / (4 * size[0]),
                       sy * (1 + sx * a) * (1 + sz * c) / (4 * size[1]),
                       sz * (1 + sx * a) * (1 + sy * b) / (4 * size[2])], axis=1)
        bm = np.zeros((6, 24))
        bm[0, 0::3], bm[1, 1::3], bm[2, 2::3] = dn[:, 0], dn[:, 1], dn[:, 2]
        bm[3, 0::3], bm[3, 1::3] = dn[:, 1], dn[:, 0]
        bm[4, 1::3], bm[4, 2::3] = dn[:, 2], dn[:, 1]
        bm[5, 0::3], bm[5, 2::3] = dn[:, 2], dn[:, 0]
        out[q] = bm.T @ d @ bm * weights[q] * jac
    return out


def _pcg(a, b, *, rtol=1e-10, maxiter=20000):
    """Jacobi-preconditioned conjugate gradients; returns (x, iterations)."""
    diag = a.diagonal()
    x = np.zeros_like(b)
    r = b.copy()
    z = r / diag
    p = z.copy()
    rz = r @ z
    stop = rtol * np.sqrt(b @ b)
    for it in range(1, maxiter + 1):
        ap = a @ p
        alpha = rz / (p @ ap)
        x += alpha * p
        r -= alpha * ap
        if np.sqrt(r @ r) <= stop:
            return x, it
        z = r / diag
        rz, rz_old = r @ z, rz
        p = z + (rz / rz_old) * p
    raise ModelError(f"throw FE: conjugate gradients did not converge in {maxiter} iterations; "
                     "use a larger element_size")


def _twist_stiffness(xs, ys, zs, inside, *, young, poisson):
    """Torsional stiffness (N·m/rad) of the solid ``inside(x, y, z) -> bool`` on the grid
    ``xs × ys × zs`` (node coordinates, m; inside must be constant along z within a layer),
    its end sections z = zs[0] and z = zs[-1] turned rigidly in their plane, free to warp."""
    import scipy.sparse as sp

    d = _elasticity(young, poisson)
    g = 1 / np.sqrt(3)
    gauss = np.array([(a, b, c) for a in (-g, g) for b in (-g, g) for c in (-g, g)])
    s = (np.arange(_SUB) + 0.5) / _SUB * 2 - 1
    sub = np.array([(a, b, c) for a in s for b in s for c in (-g, g)])
    sub_w = np.full(len(sub), 8.0 / len(sub))
    nx, ny, nz = len(xs) - 1, len(ys) - 1, len(zs) - 1
    if nx * ny * nz > 5 * _MAX_ELEMENTS:
        raise ModelError(f"throw FE: a grid of {nx} x {ny} x {nz} cells is too fine (more than "
                         f"{5 * _MAX_ELEMENTS}); use a larger element_size")
    i, j, k = (v.ravel() for v in np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz),
                                              indexing="ij"))
    zc = 0.5 * (zs[k] + zs[k + 1])
    frac = (s + 1) / 2
    chi = np.stack([inside(xs[i] + (xs[i + 1] - xs[i]) * fa, ys[j] + (ys[j + 1] - ys[j]) * fb, zc)
                    for fa in frac for fb in frac for _ in (0, 1)], axis=1)
    keep = chi.any(axis=1)
    i, j, k, chi = i[keep], j[keep], k[keep], chi[keep].astype(float)
    if len(i) > _MAX_ELEMENTS:
        raise ModelError(f"throw FE: {len(i)} elements exceed {_MAX_ELEMENTS}; use a larger "
                         "element_size")
    full = chi.all(axis=1)
    node = lambda a, b, c: (a * (ny + 1) + b) * (nz + 1) + c  # noqa: E731
    conn = np.stack([node(i + a, j + b, k + c) for a, b, c in
                     ((_CORNERS + 1) / 2).astype(int)], axis=1)
    used, conn = np.unique(conn, return_inverse=True)
    conn = conn.reshape(-1, 8)
    n_nodes = len(used)
    x = xs[used // ((ny + 1) * (nz + 1))]
    y = ys[(used // (nz + 1)) % (ny + 1)]
    z = zs[used % (nz + 1)]
    dofs = (3 * conn[:, :, None] + np.arange(3)).reshape(-1, 24).astype(np.int32)
    sizes = np.stack([xs[i + 1] - xs[i], ys[j + 1] - ys[j], zs[k + 1] - zs[k]], axis=1)
    keys, which = np.unique(np.round(sizes * 1e12).astype(np.int64), axis=0,
                            return_inverse=True)
    which = which.ravel()
    data = np.empty((len(i), 576))
    for q, key in enumerate(keys):
        size = key / 1e12
        whole = _point_stiffness(size, gauss, np.ones(8), d).sum(axis=0).ravel()
        parts = _point_stiffness(size, sub, sub_w, d).reshape(len(sub), 576)
        mine = which == q
        data[mine & full] = whole
        cut = mine & ~full
        # a vanishing share of the whole element keeps nearly empty cut elements regular
        data[cut] = chi[cut] @ parts + 1e-8 * whole
    rows = np.repeat(dofs, 24, axis=1).ravel()
    cols = np.tile(dofs, (1, 24)).ravel()
    stiff = sp.csr_matrix((data.ravel(), (rows, cols)), shape=(3 * n_nodes, 3 * n_nodes))
    del data, rows, cols
    theta = 1e-3
    u = np.zeros(3 * n_nodes)
    fixed = np.zeros(3 * n_nodes, bool)
    start, end = np.isclose(z, zs[0]), np.isclose(z, zs[-1])
    for face in (start, end):
        fixed[3 * np.flatnonzero(face)] = True
        fixed[3 * np.flatnonzero(face) + 1] = True
    e = np.flatnonzero(end)
    u[3 * e], u[3 * e + 1] = -theta * y[e], theta * x[e]
    fixed[3 * np.flatnonzero(start)[np.argmin(x[start] ** 2 + y[start] ** 2)] + 2] = True
    free = ~fixed
    a = stiff[free][:, free]
    with limit_blas():      # threaded BLAS on the CG's vector products is mostly sync cost
        u[free], _ = _pcg(a, -(stiff[free][:, fixed] @ u[fixed]))
    force = stiff @ u
    torque = np.sum(x[e] * force[3 * e + 1] - y[e] * force[3 * e])
    return float(torque / theta), len(i)


def _layers(bounds, size):
    """Node coordinates along z: each section [bounds[m], bounds[m+1]] in equal layers of at
    most ``size`` (at least two)."""
    out = [np.array([bounds[0]])]
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        n = max(2, int(np.ceil((hi - lo) / size - 1e-9)))
        out.append(np.linspace(lo, hi, n + 1)[1:])
    return np.concatenate(out)


def _throw_grid_stiffness(throw, size, *, young, poisson):
    dj, dp, b, r, h = (throw.journal_diameter, throw.pin_diameter, throw.web_width,
                       throw.crank_radius, throw.web_thickness)
    z1 = throw.journal_length / 2
    z2, z3 = z1 + h, z1 + h + throw.pin_length
    z4, z5 = z3 + h, z3 + h + z1
    zs = _layers([0.0, z1, z2, z3, z4, z5], size)
    lo, hi = min(-dj, -b) / 2, max(r + dp / 2, r + b / 2)
    half_y = max(dj, dp, b) / 2
    # grid lines offset from the axes so that no cylinder is tangent to a line
    xs = lo - size / 3 + size * np.arange(int(np.ceil((hi - lo + size / 3) / size)) + 1)
    ys = -half_y - size / 3 + size * np.arange(int(np.ceil((2 * half_y + size / 3) / size)) + 1)
    rj2, rp2 = (dj / 2) ** 2, (dp / 2) ** 2
    bj2, bp2 = (throw.journal_bore / 2) ** 2, (throw.pin_bore / 2) ** 2
    bw2 = (b / 2) ** 2

    def inside(x, y, z):
        oj = x * x + y * y
        op = (x - r) ** 2 + y * y
        journal = ((z < z1) | (z > z4)) & (oj <= rj2) & (oj >= bj2)
        pin = (z > z2) & (z < z3) & (op <= rp2) & (op >= bp2)
        web = (((z > z1) & (z < z2)) | ((z > z3) & (z < z4))) & (
            (oj <= bw2) | (op <= bw2) | ((x >= 0) & (x <= r) & (np.abs(y) <= b / 2)))
        return journal | pin | web

    return _twist_stiffness(xs, ys, zs, inside, young=young, poisson=poisson)


def throw_stiffness_fe(throw, *, shear_modulus: float = 80.0e9, poisson_ratio: float = 0.3,
                       element_size=None, reference_diameter=None):
    """Torsional stiffness of one crank throw from a 3-D elastic finite-element model.

    Parameters
    ----------
    throw : CrankThrow
        Dimensions, m (module docstring for the solid they describe).
    shear_modulus : float
        G, Pa.
    poisson_ratio : float
        ν (E = 2G(1 + ν)); 0.3 for steel.
    element_size : float, optional
        Edge of the coarser grid's elements, m (default: the smaller of the journal and pin
        diameters over 10, and at most half the web thickness); the finer grid uses
        ``element_size / 1.5``. Time and memory grow as the inverse cube (about 1-5 s at
        the default on a truck-sized throw).
    reference_diameter : float, optional
        D_ref of the equivalent length, m (default the journal diameter).

    Returns
    -------
    ThrowStiffness
        ``method="fe"``, ``stiffness`` (N·m/rad) extrapolated from the two grids,
        ``equivalent_length`` (m), ``uncertainty`` the relative step from the finer grid to
        the extrapolated value (the discretisation error estimate), ``within_validity=True``
        (no empirical range), empty ``parts``; ``note`` names the grids.

    Notes
    -----
    The model's idealisation (sharp corners, obround webs, no counterweights) is a modelling
    error of its own that the ``uncertainty`` does not include.

    Examples
    --------
    >>> from crankbench.predict.torsion.throws import CrankThrow
    >>> t = CrankThrow(journal_diameter=0.085, journal_length=0.036, pin_diameter=0.07,
    ...                pin_length=0.042, web_thickness=0.026, web_width=0.13,
    ...                crank_radius=0.08)
    >>> r = throw_stiffness_fe(t, element_size=0.01)
    >>> round(r.equivalent_length, 2), round(r.stiffness / 1e6, 1)
    (0.26, 1.6)
    """
    from .throws import CrankThrow, ThrowStiffness

    if not isinstance(throw, CrankThrow):
        raise ModelError(f"throw must be a CrankThrow, got {type(throw).__name__}")
    g = check_positive(shear_modulus, "shear_modulus", error=ModelError)
    nu = check_range(poisson_ratio, "poisson_ratio", 0.0, 0.5, inclusive=(True, False),
                     error=ModelError)
    dref = throw.journal_diameter if reference_diameter is None else check_positive(
        reference_diameter, "reference_diameter", error=ModelError)
    if element_size is None:
        element_size = min(min(throw.journal_diameter, throw.pin_diameter) / 10.0,
                           throw.web_thickness / 2.0)
    size = check_positive(element_size, "element_size", error=ModelError)
    if size > min(throw.journal_diameter, throw.pin_diameter) / 4.0:
        log.warning("throw_stiffness_fe: element_size=%.4g m is more than a quarter of the "
                    "smaller of the journal and pin diameters: the two-grid extrapolation and "
                    "its uncertainty are not reliable that coarse", size)
    young = 2.0 * g * (1.0 + nu)
    k_coarse, n_coarse = _throw_grid_stiffness(throw, size, young=young, poisson=nu)
    k_fine, n_fine = _throw_grid_stiffness(throw, size / _REFINE, young=young, poisson=nu)
    # first-order extrapolation in the element size, on the flexibility (1/k)
    c_coarse, c_fine = 1.0 / k_coarse, 1.0 / k_fine
    c_zero = c_fine + (c_fine - c_coarse) / (_REFINE - 1.0)
    if not c_zero > 0:
        raise ModelError("throw FE: the two grids disagree too much to extrapolate; use a "
                         "smaller element_size")
    k = 1.0 / c_zero
    uncertainty = abs(k_fine - k) / k
    le = g * np.pi * dref ** 4 / (32.0 * k)
    note = (f"3-D elastic FE of the idealised throw (sharp corners, obround webs): "
            f"{n_coarse} and {n_fine} elements ({size * 1e3:.3g} and "
            f"{size / _REFINE * 1e3:.3g} mm), extrapolated to zero size")
    log.debug("throw_stiffness_fe: k = %.6g N·m/rad (grids %.6g, %.6g)", k, k_coarse, k_fine)
    return ThrowStiffness(method="fe", stiffness=float(k), equivalent_length=float(le),
                          reference_diameter=float(dref), parts={}, within_validity=True,
                          uncertainty=float(uncertainty), note=note)


@functools.lru_cache(maxsize=64)
def _cached_fe(throw, shear_modulus, reference_diameter):
    """:func:`throw_stiffness_fe` at its defaults, once per throw (a crankshaft repeats one
    throw; ``CrankThrow`` is frozen and hashable)."""
    return throw_stiffness_fe(throw, shear_modulus=shear_modulus,
                              reference_diameter=reference_diameter)
