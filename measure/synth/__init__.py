"""The synthetic test bench: records whose truth is known.

``synthesize(scene)`` drives the prediction models (engine, torque excitation, shaft line,
mounts) through an operating profile, samples the scene's sensors with their imperfections and
returns a :class:`SyntheticRun` holding the Record and its ground truth. Scenes are TOML files
(:meth:`Scene.from_toml`, see :mod:`measure.synth.scene`).

Modules: :mod:`.scene` (scene files), :mod:`.profile` (rpm(t)), :mod:`.torsional` (time-domain
torsional response), :mod:`.vibrograph` (mount channels), :mod:`.pulses` (tacho/encoder
trains), :mod:`.imperfections`, :mod:`.run` (``synthesize``). Names are loaded on first use.
"""

import importlib

_LAZY = {
    "synthesize": "run",
    "SyntheticRun": "run",
    "Scene": "scene",
    "SensorSpec": "scene",
    "SpeedProfile": "profile",
    "Imperfections": "imperfections",
}

__all__ = sorted(_LAZY)


def __getattr__(name):
    if name in _LAZY:
        module = importlib.import_module(f"{__name__}.{_LAZY[name]}")
        return getattr(module, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return __all__
