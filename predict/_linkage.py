"""Second-order jets (value, d/dθ, d²/dθ²) of the crank-train linkages: exact derivatives of
the plain slider crank, its truncated harmonic series and the articulated (link) rod, used by
:meth:`predict.engine.Engine.piston_motion`."""

from __future__ import annotations

import numpy as np

__all__ = ["plain_jet", "series_jet", "articulated_jet"]


def _jmul(f, g):
    return (f[0] * g[0], f[1] * g[0] + f[0] * g[1], f[2] * g[0] + 2 * f[1] * g[1] + f[0] * g[2])


def _jsqrt(f):
    h0 = np.sqrt(f[0])
    h1 = f[1] / (2 * h0)
    return (h0, h1, (f[2] - 2 * h1 * h1) / (2 * h0))


def _jlin(f, a, g=None, b=0.0, c=0.0):
    """a f + b g + c."""
    if g is None:
        return (a * f[0] + c, a * f[1], a * f[2])
    return (a * f[0] + b * g[0] + c, a * f[1] + b * g[1], a * f[2] + b * g[2])


def _jtrig(psi):
    s, c = np.sin(psi), np.cos(psi)
    return (c, -s, -c), (s, c, -s)


def plain_jet(psi, r, l, e):
    """Slider crank x = r cos ψ + l cos φ, sin φ = (r sin ψ − e)/l."""
    cj, sj = _jtrig(psi)
    s = _jlin(sj, r / l, c=-e / l)
    c = _jsqrt(_jlin(_jmul(s, s), -1.0, c=1.0))
    return _jlin(cj, r, c, l)


def series_jet(psi, r, l, c):
    """Truncated series x = r cos ψ + l Σ c_2k cos 2kψ and its θ-derivatives."""
    k = np.arange(2, c.size, 2)
    ck = c[2::2]
    ang = np.multiply.outer(psi, k)
    x = r * np.cos(psi) + l * (c[0] + np.cos(ang) @ ck)
    dx = -r * np.sin(psi) - l * (np.sin(ang) @ (k * ck))
    d2x = -r * np.cos(psi) - l * (np.cos(ang) @ (k * k * ck))
    return x, dx, d2x


def articulated_jet(psi_m, art, delta, r, l, e):
    """Piston on a link rod pinned to the master rod (radial engines)."""
    cj, sj = _jtrig(psi_m)
    s = _jlin(sj, r / l, c=-e / l)                       # sin φ of the master rod
    c = _jsqrt(_jlin(_jmul(s, s), -1.0, c=1.0))           # cos φ
    g = np.deg2rad(art.link_angle_deg)
    cg, sg = np.cos(g), np.sin(g)
    # link-pin direction: master-rod line (cos φ, −sin φ) turned by γ
    ca = _jlin(c, cg, s, sg)                              # cos(γ − φ)
    sa = _jlin(s, -cg, c, sg)                             # sin(γ − φ)
    a_m = _jlin(cj, r, ca, art.link_radius)               # link pin, master axial
    p_m = _jlin(sj, r, sa, art.link_radius)               # link pin, master sideways
    cd, sd = np.cos(delta), np.sin(delta)
    a_j = _jlin(a_m, cd, p_m, sd)
    p_j = _jlin(a_m, -sd, p_m, cd)
    root = _jsqrt(_jlin(_jmul(p_j, p_j), -1.0, c=art.rod_length**2))
    return _jlin(a_j, 1.0, root, 1.0)
