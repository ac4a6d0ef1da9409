"""Fuzzing the text-export path: any text given to ``measure.read`` (with or without a channel
map) gives a valid Record or one of our errors naming the file — never another exception or a
hang. The texts are raw rig exports in every dialect, damaged by hypothesis (cut, a run of
characters replaced, lines dropped or repeated)."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from crankbench.measure import io as mio
from crankbench.measure.record import validate
from crankbench.measure.synth.rawrig import DIALECTS, raw_rig
from crankbench.predict.errors import CrankbenchError
from hang_guard import time_limit

FUZZ = settings(max_examples=25, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])
TEXT_DIALECTS = [d for d in DIALECTS if d != "xlsx"]
_RIGS: dict = {}


def _rig(folder, dialect):
    if dialect not in _RIGS:
        rig = raw_rig(folder / dialect, dialect=dialect, duration=0.06, fs=20_000.0,
                      speed_rpm=(1500.0, 1500.0), runt_teeth=())
        _RIGS[dialect] = (rig.path.read_bytes(), rig.map_path)
    return _RIGS[dialect]


@FUZZ
@given(dialect=st.sampled_from(TEXT_DIALECTS), use_map=st.booleans(),
       cut=st.floats(0.0, 1.0), junk_at=st.floats(0.0, 1.0),
       junk=st.text(alphabet=" \t;,.-e+0123456789abcxyz\n\r\"", min_size=0, max_size=40),
       repeat=st.booleans())
def test_damaged_text_export_reads_or_names_the_fault(tmp_path_factory, dialect, use_map, cut,
                                                      junk_at, junk, repeat):
    folder = tmp_path_factory.mktemp("fuzz_text")
    data, map_path = _rig(tmp_path_factory.getbasetemp(), dialect)
    text = data.decode("utf-8", errors="replace") if dialect != "tab_decimal_comma_crlf" \
        else data.decode("cp1252")
    lines = text.splitlines(keepends=True)
    if repeat and len(lines) > 10:
        lines = lines[:5] + lines[3:]
    text = "".join(lines)
    i = int(junk_at * len(text))
    text = text[:i] + junk + text[i + len(junk):]
    text = text[:max(1, int(cut * len(text)))]
    path = folder / "rig.txt"
    path.write_text(text, encoding="utf-8")
    try:
        with time_limit(30, "read"):
            rec = mio.read(path, map=map_path if use_map else None)
    except CrankbenchError as exc:
        assert str(exc)
        return
    validate(rec)
    for name in rec.data_vars:
        assert np.all(np.isfinite(rec[name].values)), name
