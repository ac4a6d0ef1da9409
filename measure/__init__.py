"""Getting signals in: readers/writers, the Record schema, tacho and pulse timing, instrument
models and the synthetic test bench.

May import ``predict`` (the synthetic bench drives the prediction models), never ``analysis``.
Public functions are loaded on first use so ``import measure`` does no work.
"""

import importlib

from predict.errors import RecordError

_LAZY = {
    "read": "io",
    "write": "io",
    "open": "io",
    "validate": "record",
    "read_truth": "io",
    "make_record": "record",
    "iter_blocks": "io",
    "channel_time": "record",
    "list_channels": "record",
    "RecordWarning": "record",
    "to_si": "units",
    "synthesize": "synth",
    "Scene": "synth",
    "SyntheticRun": "synth",
    "speed_from_pulses": "tacho",
    "angle_from_pulses": "tacho",
    "detect_edges": "tacho",
    "angular_vibration": "torsiograph",
}

__all__ = sorted([*_LAZY, "RecordError"])


def __getattr__(name):
    if name in _LAZY:
        module = importlib.import_module(f"{__name__}.{_LAZY[name]}")
        return getattr(module, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return __all__
