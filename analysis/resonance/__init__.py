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

Errors: for a noiseless SDOF track the modal fit returns f_n and ζ to about 1e-7 relative
(solver tolerance); the half-power estimate is exact for an SDOF with constant excitation and
biased by O(ζ · d ln F / d ln ω) when the excitation amplitude ``F`` varies with speed. Through
a linear sweep (lsim-generated tracks, ``analysis/bench/suite_resonance.py``) the swept-SDOF
fit recovers the critical speed to < 0.03 % and the steady-state amplitude to < 0.1 % for
η = α/(ζ f_n)² ≤ 20, and to 0.2 % / 1.5 % at η ≈ 65. On a multi-mode point response a weak
resonance on a large background of other modes is biased by the background (≈ 0.8 % in speed
and up to 8 % in the sweep-corrected amplitude for the damper mode of the 6L32 scene at the free
end); see ``tests/analysis/test_pipeline.py``.
"""

from .finder import OrderCurve, Resonance, ResonanceTable, find_resonances
from .sdof import RESPONSES, _modal_fit, _parabolic, half_power_damping, sdof_response
from .sweep import correct_sweep_delay, sweep_expectation, sweep_peak_loss

__all__ = ["Resonance", "ResonanceTable", "OrderCurve", "find_resonances",
           "half_power_damping", "sdof_response", "sweep_peak_loss", "sweep_expectation",
           "correct_sweep_delay", "RESPONSES"]
