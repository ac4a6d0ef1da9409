"""Resonance identification on order tracks.

A run-up (or run-down) sweeps every engine order through the shaft line's natural frequencies.
Where order ``k`` meets mode frequency ``f_n`` the order amplitude peaks at the critical speed
``n_c = 60 f_n / k`` rpm. :func:`find_resonances` finds those peaks in an order track, separates
them from order amplitude that merely grows with speed, and identifies each one as a single
degree of freedom (SDOF) mode:

* the **half-power bandwidth** estimate, with the exact SDOF relations for displacement,
  velocity and acceleration responses (not the small-damping approximation);
* a **modal (circle) fit** of the complex order track around the peak: the SDOF frequency
  response plus a complex background, fitted by variable projection; on the Nyquist plane this
  is the classical circle fit with residual terms (Ewins, *Modal Testing*, 2nd ed., §4.3);
* the **sweep-rate effect**: a finite sweep lowers and shifts the peak. The loss is estimated by
  integrating the SDOF envelope equation through the measured sweep at the identified natural
  frequency and damping, the apparent damping is de-inflated by inverting that simulation, and
  the critical speed and amplitude are corrected.

The natural frequency follows as ``f_n = n_c k / 60``. Each resonance carries a confidence built
from its signal-to-noise ratio, the quality of the modal fit and whether both half-power points
were observed.

Errors: for a noiseless SDOF track sampled at >= 10 points per half-power band, the modal fit is
exact to the solver tolerance (relative 1e-8); the half-power estimate is exact for an SDOF with
constant excitation and is biased by O(ζ · d ln F / d ln ω) when the excitation amplitude ``F``
varies with speed (inertia torques grow as ω²). The sweep correction assumes an SDOF mode and a
constant sweep rate across the peak; its residual error is below 1 % of the peak for sweep
parameters η = α/(ζ f_n)² ≤ 1 (α the sweep rate of the excitation frequency in Hz/s).
"""

from .finder import OrderCurve, Resonance, ResonanceTable, find_resonances
from .sdof import RESPONSES, _modal_fit, _parabolic, half_power_damping, sdof_response
from .sweep import sweep_peak_loss

__all__ = ["Resonance", "ResonanceTable", "OrderCurve", "find_resonances",
           "half_power_damping", "sdof_response", "sweep_peak_loss", "RESPONSES"]
