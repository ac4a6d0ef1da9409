"""Shared test configuration: non-interactive matplotlib, sample-data paths."""

import os
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
