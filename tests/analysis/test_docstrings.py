"""The Examples sections of the order/harmonic analysis modules run and print what they say."""

import doctest
import importlib

import pytest

MODULES = ["analysis.resample", "analysis.orders", "analysis.vkf", "analysis.harmonic",
           "analysis.spectra", "analysis.speedref", "analysis.plots"]


@pytest.mark.parametrize("name", MODULES)
def test_examples(name):
    import matplotlib

    matplotlib.use("Agg")
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0
    assert result.failed == 0
