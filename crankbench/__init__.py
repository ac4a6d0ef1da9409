"""crankbench: vibration-measurement analysis workbench for reciprocating engines.

One installed namespace with three subpackages, imported on first use::

    crankbench.predict   engine and shaft-line prediction models (bottom of the import graph)
    crankbench.measure   records in: readers, the Record schema, tacho, the synthetic bench
    crankbench.analysis  order analysis, resonances, comparison, reports, the CLI (top)

In the repository the three live in the top-level folders ``predict/``, ``measure/`` and
``analysis/`` (fixed by the design card); ``pyproject.toml`` maps them into this package for
wheels and editable installs alike.

Examples
--------
>>> import crankbench
>>> crankbench.__version__
'0.2.0'
>>> float(crankbench.predict.torsion.chain([1.0, 1.0], [1.0]).natural_frequencies()[0])
0.0
"""

import importlib
from pathlib import Path

__version__ = "0.2.0"
__all__ = ["__version__", "analysis", "measure", "predict"]

_SUBPACKAGES = ("analysis", "measure", "predict")

# A source checkout imported directly (``PYTHONPATH=<clone>``, or a second working tree of an
# editable install): the subpackages are this package's sibling folders. An installed wheel
# has them inside this folder and never takes this branch.
_here = Path(__file__).resolve().parent
if not (_here / "predict").is_dir() and (_here.parent / "predict" / "__init__.py").is_file():
    __path__.append(str(_here.parent))  # noqa: F821  (module __path__ of a package)


def __getattr__(name):
    if name in _SUBPACKAGES:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module 'crankbench' has no attribute {name!r}")


def __dir__():
    return sorted(__all__)
