"""A lazily opened record never hands out NaN/inf silently: the block that holds them raises."""

import numpy as np
import pytest

from crankbench.measure.io import iter_blocks, open as open_record, write
from crankbench.measure.record import make_record
from crankbench.predict.errors import RecordError


@pytest.mark.parametrize("ext", [".h5", ".wav", ".tdms"])
def test_lazy_block_with_nan_raises_naming_channel_and_time(tmp_path, ext):
    x = np.sin(np.arange(8000) / 10.0)
    x[5000:5003] = np.nan
    path = tmp_path / f"rec{ext}"
    rec = make_record({"acc": dict(data=x, sample_rate=1000.0, units="m/s^2",
                                   quantity="acceleration")}, allow_nonfinite=True)
    write(rec, path)
    lazy = open_record(path, chunk_seconds=2.0)
    blocks = iter_blocks(lazy, "acc")
    first, second = next(blocks), next(blocks)                   # 0-2 s and 2-4 s are clean
    assert np.isfinite(first[1]).all() and np.isfinite(second[1]).all()
    with pytest.raises(RecordError, match=rf"rec{ext}: channel 'acc' has 3 NaN/inf value\(s\) "
                                          r"in the block from sample 4000, first at sample 5000 "
                                          r"\(t = 5 s\)"):
        next(blocks)
    kept = open_record(path, chunk_seconds=2.0, allow_nonfinite=True)["acc"].values
    assert np.isnan(kept[5000:5003]).all() and np.isfinite(kept[:5000]).all()
