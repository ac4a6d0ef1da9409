"""A workbook that opens with a cover/notes sheet: the data sheet is found and named; a
workbook with no table anywhere is refused naming every sheet."""

import numpy as np
import pytest

from crankbench.measure import read
from crankbench.predict.errors import RecordError

openpyxl = pytest.importorskip("openpyxl")


def test_first_sheet_with_numbers_is_read(tmp_path, caplog):
    fs = 1000.0
    t = np.arange(500) / fs
    wb = openpyxl.Workbook()
    wb.active.title = "Info"
    wb.active.append(["Test", "Run-up 3"])
    ws = wb.create_sheet("Data")
    ws.append(["Measurement export"])
    ws.append([])
    ws.append(["Time", "Engine speed", "Block acc"])
    ws.append(["s", "1/min", "g"])
    for a in t:
        ws.append([float(a), 1500.0, float(0.1 * np.sin(2 * np.pi * 50 * a))])
    path = tmp_path / "rig.xlsx"
    wb.save(path)
    with caplog.at_level("INFO", logger="crankbench"):
        rec = read(path)
    np.testing.assert_allclose(rec["Engine speed"].values, 1500 * 2 * np.pi / 60)
    np.testing.assert_allclose(rec["Block acc"].values,
                               9.80665 * 0.1 * np.sin(2 * np.pi * 50 * t), atol=1e-9)
    assert rec["Block acc"].attrs["sample_rate"] == pytest.approx(fs)
    assert any("reading sheet 'Data'" in r.getMessage() for r in caplog.records)


def test_no_sheet_with_numbers(tmp_path):
    wb = openpyxl.Workbook()
    wb.active.title = "Cover"
    wb.active.append(["nothing here"])
    wb.create_sheet("Notes").append(["still nothing"])
    path = tmp_path / "empty.xlsx"
    wb.save(path)
    with pytest.raises(RecordError, match="no sheet holds a table of numbers.*'Cover'.*'Notes'"):
        read(path)
