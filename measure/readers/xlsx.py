"""Excel workbooks (``.xlsx``, ``.xlsm``): one worksheet read as a table (openpyxl).

Read-only: a sheet's columns become channels from its header rows (``name [unit]`` or a units
row) and its time column or a sample rate stated above the header, exactly as a delimited text
table (:func:`measure.readers.table.table_record`); a channel map picks the sheet, the columns,
their units and calibrations (:mod:`measure.channelmap`). Workbooks are not written: export a
Record to ``.h5`` or ``.csv``.
"""

from __future__ import annotations

from crankbench.predict.errors import RecordError

from .table import SheetTable, table_record

__all__ = ["FORMAT", "check_magic", "read", "write"]

FORMAT = "Excel workbook (.xlsx)"


def check_magic(head: bytes) -> bool:
    """A ZIP container (Office Open XML)."""
    return head.startswith(b"PK\x03\x04")


def read(path, *, channels=None):
    """Read the first worksheet as a Record from its headers (see the module docstring)."""
    return table_record(SheetTable(path), channels=channels)


def write(record, path, *, truth=None) -> dict:
    """Workbooks are input only."""
    raise RecordError(f"{path}: crankbench does not write spreadsheets; write the record as "
                      ".h5 (or .csv, which a spreadsheet opens)")
