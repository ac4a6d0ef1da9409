"""The synthetic test bench: records whose truth is known.

``synthesize(scene)`` drives the prediction models (engine, torque excitation, shaft line,
mounts) through an operating profile, samples the scene's sensors with their imperfections and
returns a :class:`SyntheticRun` holding the Record and its ground truth. Scenes are TOML files
(:meth:`Scene.from_toml`, see :mod:`measure.synth.scene`).

Modules: :mod:`.scene` (scene files), :mod:`.profile` (rpm(t)), :mod:`.torsional` (time-domain
torsional response), :mod:`.vibrograph` (mount channels), :mod:`.pulses` (tacho/encoder
trains), :mod:`.imperfections`, :mod:`.run` (``synthesize``). Names are loaded on first use.
"""

from crankbench.predict._lazy import lazy_names


_LAZY = {
    "synthesize": "run",
    "SyntheticRun": "run",
    "Scene": "scene",
    "SensorSpec": "scene",
    "SpeedProfile": "profile",
    "Imperfections": "imperfections",
}

__getattr__, __dir__, __all__ = lazy_names(__name__, _LAZY)
