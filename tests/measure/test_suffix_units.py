"""Units stated as the last word of a column name (``time_ms``, ``speed_hz``, ``acc_g``): a
common export style, read without a channel map; words that are names stay names."""

import numpy as np
import pytest

from crankbench.measure import read
from crankbench.measure.readers.table import suffix_unit
from crankbench.predict.errors import RecordError


def test_suffix_units_are_converted_to_si(tmp_path):
    fs = 2000.0
    t = np.arange(400) / fs
    path = tmp_path / "rig.csv"
    rows = ["time_ms,speed_hz,acc_g,p_cyl_bar"]
    rows += [f"{1e3 * a:.4f},{25 + a:.6f},{0.5 * np.sin(60 * a):.8f},{40 + a:.5f}" for a in t]
    path.write_text("\n".join(rows) + "\n")
    rec = read(path)
    assert rec["speed_hz"].attrs["units"] == "rad/s"
    np.testing.assert_allclose(rec["speed_hz"].values, 2 * np.pi * (25 + t), rtol=1e-6)
    np.testing.assert_allclose(rec["acc_g"].values, 9.80665 * 0.5 * np.sin(60 * t), atol=1e-6)
    np.testing.assert_allclose(rec["p_cyl_bar"].values, 1e5 * (40 + t), rtol=1e-6)
    assert rec["speed_hz"].attrs["sample_rate"] == pytest.approx(fs, rel=1e-6)
    assert "speed_hz -> hz" in rec.attrs["units_from_names"]


def test_name_words_are_not_units(tmp_path):
    assert [suffix_unit(n) for n in ("acc_x", "cyl_1", "valve_in", "pos_m", "time", "_g")] == \
        [None] * 6
    path = tmp_path / "rig.csv"
    path.write_text("time_s,acc_x\n0,1\n0.001,2\n0.002,3\n")
    with pytest.raises(RecordError, match="'acc_x' names no unit"):
        read(path)
