"""Torsional vibration of engine shaft lines.

Natural frequencies and mode shapes (structured, high-relative-accuracy solvers), critical
speeds with phase-vector sums, excitation by the harmonics of the cylinder tangential torque,
forced response over speed, stresses against limit curves, dampers; shaft lines built from
elements or read from TOML.

Public names are imported lazily (no work at import time).
"""

from __future__ import annotations

from .._lazy import lazy_names


__all__ = ["chain", "TorsionalSystem", "Modes", "from_toml", "forced_response",
           "ForcedResponse", "ShaftLine", "resonance_amplitudes", "engine_excitation",
           "Excitation", "StressLimits", "check_stress", "CrankThrow", "throw_stiffness",
           "throw_stiffness_fe", "uniform_shaft_frequencies", "friction_damper_response",
           "friction_dissipation", "optimum_slip_torque", "FrictionDamper",
           "friction_forced_response"]

_LAZY = {
    "chain": "system",
    "TorsionalSystem": "system",
    "Modes": "modes",
    "forced_response": "forced",
    "ForcedResponse": "forced",
    "ShaftLine": "elements",
    "from_toml": "toml",
    "resonance_amplitudes": "resonance",
    "engine_excitation": "excitation",
    "Excitation": "excitation",
    "StressLimits": "stress",
    "check_stress": "stress",
    "CrankThrow": "throws",
    "throw_stiffness": "throws",
    "throw_stiffness_fe": "throw_fe",
    "uniform_shaft_frequencies": "throws",
    "friction_damper_response": "friction",
    "friction_dissipation": "friction",
    "optimum_slip_torque": "friction",
    "FrictionDamper": "friction",
    "friction_forced_response": "friction_line",
}

__getattr__, __dir__, _names = lazy_names(__name__, _LAZY)
