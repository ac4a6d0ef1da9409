"""Getting signals in: readers/writers, the Record schema, tacho and pulse timing, instrument
models and the synthetic test bench.

May import ``predict`` (the synthetic bench drives the prediction models), never ``analysis``.
Public functions are loaded on first use so ``import measure`` does no work.
"""

from crankbench.predict._lazy import lazy_names
from crankbench.predict.errors import RecordError

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
    "find_edges": "edges",
    "decode_wheel": "wheel",
    "decode_marks": "wheel",
    "ChannelMap": "channelmap",
    "pulse_channel_speed": "tacho",
    "angular_vibration": "torsiograph",
}

__getattr__, __dir__, __all__ = lazy_names(__name__, _LAZY, extra=("RecordError",))
