"""Shared test configuration: non-interactive matplotlib, sample-data paths."""

from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")

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
