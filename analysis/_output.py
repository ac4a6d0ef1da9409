"""Printing command results: aligned text tables for people, JSON for programs."""

from __future__ import annotations

import json
import math
import sys
from typing import Any

import numpy as np

__all__ = ["to_jsonable", "print_json", "print_table"]


def to_jsonable(obj: Any) -> Any:
    """Convert numpy/pandas/xarray objects into JSON-serialisable Python values.

    Non-finite floats become ``None`` (JSON has no NaN).
    """
    import dataclasses

    import pandas as pd

    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return to_jsonable({f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)
                            if f.repr})
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, pd.DataFrame):
        return [to_jsonable(r) for r in obj.to_dict(orient="records")]
    if isinstance(obj, pd.Series):
        return to_jsonable(obj.to_dict())
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.floating, float)):
        value = float(obj)
        return value if math.isfinite(value) else None
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if isinstance(obj, complex):
        return {"re": obj.real, "im": obj.imag}
    if hasattr(obj, "isoformat"):
        return obj.isoformat()
    return obj


def print_json(obj: Any, file=None) -> None:
    """Print ``obj`` as indented JSON."""
    print(json.dumps(to_jsonable(obj), indent=2, ensure_ascii=False), file=file or sys.stdout)


def print_table(frame, *, title: str | None = None, float_format: str = "{:.6g}", file=None) -> None:
    """Print a pandas DataFrame as an aligned text table."""
    out = file or sys.stdout
    if title:
        print(title, file=out)
    if len(frame) == 0:
        print("  (none)", file=out)
        return
    text = frame.to_string(index=False, float_format=lambda v: float_format.format(v))
    print(text, file=out)
