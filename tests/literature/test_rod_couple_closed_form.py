"""The two-mass rod's error in closed form (the bound of the textbook bench row).

Dropping the residual couple of the two-point rod (``rod_inertia_correction = 0``) loses the
couple −ΔI ε of the rod (ΔI = I_G − m a b, ε the rod's angular acceleration), which reaches the
crank through the arm r cos θ/(l cos β) (torque positive in the direction of rotation). With sin β = λ sin θ and
ε = −ω² λ sin θ (1 − λ²)/cos³β (constant ω):
ΔT = ΔI ω² λ² (1 − λ²) sin θ cos θ / (1 − λ² sin² θ)², derived here independently of the
code; the model's torque difference must equal it.
"""

import numpy as np
import pytest

from crankbench.predict.engine import Engine
from crankbench.predict.forces import engine_torque
from crankbench.predict.masses import Rod


@pytest.mark.parametrize("lam", [0.25, 0.3, 0.4])
def test_dropped_residual_couple_is_the_closed_form(lam):
    rod = Rod(mass=3.0, length=0.2, cg_from_big_end=0.06, inertia_cg=0.012)
    two = rod.two_point()
    r = lam * 0.2
    kw = dict(crank_angles_deg=[0], crank_radius=r, rod_length=0.2,
              reciprocating_mass=two.small_end + 1.5, rotating_mass=two.big_end)
    simple, exact = Engine(**kw), Engine(rod_inertia_correction=two.inertia_error, **kw)
    th = np.linspace(0, 4 * np.pi, 2001)
    w = 400.0
    diff = engine_torque(exact, th, omega=w) - engine_torque(simple, th, omega=w)
    closed = (two.inertia_error * w * w * lam ** 2 * (1 - lam ** 2) * np.sin(th) * np.cos(th)
              / (1 - (lam * np.sin(th)) ** 2) ** 2)
    scale = np.max(np.abs(closed))
    assert np.max(np.abs(diff - closed)) < 1e-9 * scale        # exact − two-mass, with sign
    # the cruder product of maxima |ΔI| ω² λ²/(1 − λ²) bounds it from above
    assert scale <= abs(two.inertia_error) * w * w * lam ** 2 / (1 - lam ** 2)
