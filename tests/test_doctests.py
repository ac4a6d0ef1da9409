"""Every docstring Example in the installed ``crankbench`` namespace runs and prints what it says.

The modules are imported by their installed names (``crankbench.analysis.orders``), not by file
path, so the examples exercise the same objects users import. Examples run from the repository
root, where the ``sample_data/`` paths they name resolve.
"""

import doctest
import importlib
import pkgutil
from pathlib import Path

import pytest

import crankbench

ROOT = Path(__file__).resolve().parents[1]


def _modules():
    names = ["crankbench"]
    for sub in ("predict", "measure", "analysis"):
        package = importlib.import_module(f"crankbench.{sub}")
        names.append(package.__name__)
        names += [info.name for info in pkgutil.walk_packages(package.__path__, f"{package.__name__}.")
                  if not info.name.endswith("__main__")]
    return sorted(names)


MODULES = _modules()

# modules whose Examples are their specification: each must hold at least one
MUST_HAVE_EXAMPLES = ["crankbench", "crankbench.analysis.resample", "crankbench.analysis.orders",
                      "crankbench.analysis.vkf", "crankbench.analysis.harmonic",
                      "crankbench.analysis.spectra", "crankbench.analysis.speedref",
                      "crankbench.analysis.plots", "crankbench.predict.kinematics"]


def test_the_walk_finds_every_module():
    """Each ``*.py`` under the three folders is reached by the walk (nothing skipped silently)."""
    on_disk = set()
    for sub in ("predict", "measure", "analysis"):
        for path in (ROOT / sub).rglob("*.py"):
            parts = path.relative_to(ROOT).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            on_disk.add(".".join(("crankbench", *parts)))
    assert on_disk - set(MODULES) == set()


@pytest.mark.parametrize("name", MODULES)
def test_examples(name, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    monkeypatch.chdir(ROOT)
    module = importlib.import_module(name)
    finder = doctest.DocTestFinder(exclude_empty=True)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    tests = [t for t in finder.find(module, name) if t.examples]
    report = []
    for test in tests:
        runner.run(test, out=report.append)
    if name in MUST_HAVE_EXAMPLES:
        assert tests, f"{name} lost its docstring Examples"
    assert runner.failures == 0, "".join(report)
