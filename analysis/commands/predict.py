"""``crankbench predict WHAT MODEL.toml``: run one prediction module on a model file.

Each prediction lives in ``analysis/commands/predict_<what>.py`` with ``HELP``,
``configure(parser)`` and ``run(args)`` like a top-level command.
"""

from __future__ import annotations

import importlib

HELP = "run a prediction (balance, torsion, lateral, flywheel, crankshaft) on a model TOML"

#: prediction modules in the order help lists them
PREDICTIONS = ("balance", "torsion", "lateral", "flywheel", "crankshaft")


def configure(parser) -> None:
    from crankbench.analysis.cli import verbosity_parent

    common = verbosity_parent()
    sub = parser.add_subparsers(dest="prediction", metavar="WHAT", required=True)
    for what in PREDICTIONS:
        try:
            module = importlib.import_module(f"crankbench.analysis.commands.predict_{what}")
        except ModuleNotFoundError as exc:
            if exc.name == f"crankbench.analysis.commands.predict_{what}":
                continue
            raise
        p = sub.add_parser(what, help=module.HELP, description=module.HELP, parents=[common])
        module.configure(p)
        from crankbench.analysis.cli import flag_names, list_flags

        p.set_defaults(_predict=module.run, _flags=flag_names(p), _lists=list_flags(p))


def run(args) -> int:
    return args._predict(args)
