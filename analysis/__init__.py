"""Order and harmonic analysis, resonance finding, comparison with prediction, reports, CLI.

Top of the import graph: may import ``measure`` and ``predict``. Public functions are loaded
on first use so ``import analysis`` does no work.
"""

from crankbench.predict._lazy import lazy_names


#: public name -> submodule that defines it
_LAZY = {
    "order_track": "orders",
    "order_map": "orders",
    "order_spectrum": "orders",
    "campbell_map": "orders",
    "angle_resample": "resample",
    "order_track_stream": "stream",
    "order_map_stream": "stream",
    "decimate_stream": "stream",
    "vold_kalman": "vkf",
    "harmonics": "harmonic",
    "runge12": "harmonic",
    "band_amplitude": "orders",
    "speed_reference": "speedref",
    "spectrum": "spectra",
    "synchronous_average": "spectra",
    "integrate": "spectra",
    "differentiate": "spectra",
    "find_resonances": "resonance",
    "match_criticals": "compare",
    "compare_balance": "compare",
    "analyse": "pipeline",
    "indicator_analysis": "pressure",
    "indicator_analyses": "pressure",
    "measured_excitation": "pressure",
    "Report": "report",
    "Verdict": "verdict",
}

__getattr__, __dir__, __all__ = lazy_names(__name__, _LAZY)
