"""One reader/writer module per test-bench file format, looked up by file extension.

Each format module defines

* ``FORMAT`` — a human label ("HDF5 (crankbench layout)"),
* ``check_magic(head: bytes) -> bool`` — does the file start like this format,
* ``read(path, *, channels=None) -> xarray.Dataset`` — channels already in SI with Record attrs
  (``measure.io.read`` adds ``source``/``source_stat``, masks and validates),
* ``write(record, path, *, truth=None) -> dict`` — writes to ``path`` (a temporary name chosen
  by ``measure.io.write``) and returns extra files to place beside the target, as
  ``{suffix: bytes}`` (the WAV sidecar),
* optionally ``open(path, *, chunk_seconds, channels=None) -> xarray.Dataset`` — lazy, dask
  chunked access with bounded memory.

Formats whose modules define ``open`` stream; the others are loaded whole by ``measure.io.open``.
"""

from __future__ import annotations

import importlib

from crankbench.predict._validate import suggest
from crankbench.predict.errors import RecordError

__all__ = ["EXTENSIONS", "FORMAT_MODULES", "module_for", "format_of_magic"]

#: File extension -> format module name (inside ``measure.readers``).
EXTENSIONS = {
    ".csv": "csv",
    ".h5": "hdf5",
    ".hdf5": "hdf5",
    ".nc": "netcdf",
    ".mf4": "mdf",
    ".mdf": "mdf",
    ".tdms": "tdms",
    ".uff": "uff",
    ".unv": "uff",
    ".wav": "wav",
    ".txt": "csv",
    ".tsv": "csv",
    ".tab": "csv",
    ".asc": "csv",
    ".dat": "csv",
    ".xlsx": "xlsx",
    ".xlsm": "xlsx",
}

#: Format module names, in the order files are probed by magic bytes.
FORMAT_MODULES = ("hdf5", "mdf", "tdms", "wav", "uff", "xlsx", "csv")

# Common near-misses that difflib does not rank well.
_ALIASES = {".hdf": ".h5", ".he5": ".h5", ".h4": ".h5", ".mf3": ".mf4", ".mdf4": ".mf4",
            ".wave": ".wav", ".netcdf": ".nc", ".cdf": ".nc", ".tdm": ".tdms",
            ".tdms_index": ".tdms", ".58": ".uff"}
# formats read after a conversion
_CONVERT = {".xls": "a legacy Excel workbook: save it as .xlsx (or CSV) and read that",
            ".ods": "an OpenDocument sheet: save it as .xlsx (or CSV) and read that"}


def module_for(path) -> object:
    """Return the format module for ``path``'s extension.

    Raises
    ------
    RecordError
        Unknown extension, suggesting the likely one ("did you mean '.h5'?") and listing all.

    Examples
    --------
    >>> module_for("run.h5").FORMAT
    'HDF5 (crankbench layout)'
    """
    from pathlib import Path

    suffix = Path(path).suffix.lower()
    if suffix in _CONVERT:
        raise RecordError(f"{path}: {suffix!r} is {_CONVERT[suffix]}")
    if suffix not in EXTENSIONS:
        hint = f" (did you mean {_ALIASES[suffix]!r}?)" if suffix in _ALIASES else suggest(
            suffix, EXTENSIONS)
        if not hint and not suffix:
            hint = " (the file name has no extension)"
        raise RecordError(f"{path}: unknown record file extension {suffix!r}{hint}; known: "
                          f"{', '.join(EXTENSIONS)}")
    return importlib.import_module(f"{__name__}.{EXTENSIONS[suffix]}")


def format_of_magic(head: bytes) -> str | None:
    """Name the format whose magic bytes ``head`` starts with (None if none matches).

    Examples
    --------
    >>> format_of_magic(b"\\x89HDF\\r\\n\\x1a\\n" + bytes(8))
    'hdf5'
    """
    for name in FORMAT_MODULES:
        module = importlib.import_module(f"{__name__}.{name}")
        if name != "csv" and module.check_magic(head):
            return name
    return None
