"""Shared test configuration: non-interactive matplotlib, sample-data paths."""

import importlib.abc
import os
import sys
from pathlib import Path

import matplotlib
import pytest
from hypothesis import settings

matplotlib.use("Agg")

# Property tests draw the same examples on every run (reproducible CI); set
# HYPOTHESIS_PROFILE=explore to let them search afresh.
settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
settings.register_profile("explore", deadline=None, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

ROOT = Path(__file__).resolve().parents[1]
SAMPLE_DATA = ROOT / "sample_data"

# The tests import this checkout, whichever one the editable install points at (a second
# working tree included), and so do the commands they run in a subprocess:
# crankbench/__init__.py maps the sibling folders in.
if str(ROOT) not in sys.path[:1]:
    sys.path.insert(0, str(ROOT))
os.environ["PYTHONPATH"] = os.pathsep.join(
    p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p)


class _NoBareTopLevel(importlib.abc.MetaPathFinder):
    """Refuse ``import measure`` / ``analysis`` / ``predict``: only ``crankbench.*`` is installed,
    so code that still imports a bare name would break next to an unrelated package of that name
    (the repository root is on ``sys.path`` under pytest, which would hide the mistake)."""

    NAMES = {"measure", "analysis", "predict"}

    def find_spec(self, fullname, path=None, target=None):
        if fullname.split(".")[0] in self.NAMES:
            raise ModuleNotFoundError(f"bare top-level import {fullname!r}: use "
                                      f"'crankbench.{fullname}' (one installed namespace)")
        return None


sys.meta_path.insert(0, _NoBareTopLevel())


@pytest.fixture
def sample_data() -> Path:
    """Path of the repository's ``sample_data/`` folder."""
    return SAMPLE_DATA


@pytest.fixture(autouse=True)
def _close_figures():
    """Close every matplotlib figure after each test (plots return figures, never show)."""
    yield
    import matplotlib.pyplot as plt

    plt.close("all")
