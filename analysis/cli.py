"""The ``crankbench`` command line.

Each sub-command lives in its own module ``analysis/commands/<name>.py`` exposing ``HELP``
(one line), ``configure(parser)`` (adds its arguments) and ``run(args) -> int``. Modules import
their heavy dependencies inside ``run`` so ``crankbench --help`` stays fast.

Errors of the project's family (bad file, channel, key, option) are printed as one line naming
what was wrong, with exit status 2; ``-v`` adds the traceback for debugging.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys
import warnings

from crankbench.predict.errors import CrankbenchError

__all__ = ["main", "build_parser", "verbosity_parent", "COMMANDS"]

log = logging.getLogger("crankbench")

#: how Python displays a warning when nobody records them (see main)
_DEFAULT_SHOWWARNMSG = getattr(warnings, "_showwarnmsg_impl", None)

#: Sub-commands in the order ``--help`` lists them.
COMMANDS = ("info", "import", "demo", "synth", "predict", "analyse", "balance", "compare",
            "report", "batch", "campaign", "bench", "pressure")
#: commands whose module name differs (``import`` is a Python keyword)
_MODULES = {"import": "import_"}


def _load(name: str):
    module = _MODULES.get(name, name)
    try:
        return importlib.import_module(f"crankbench.analysis.commands.{module}")
    except ModuleNotFoundError as exc:
        if exc.name == f"crankbench.analysis.commands.{module}":
            return None  # command not part of this build
        raise


def verbosity_parent() -> argparse.ArgumentParser:
    """Parent parser giving a sub-command ``-v``/``-q`` after its name too
    (``crankbench report ... -q``); SUPPRESS keeps the top-level value unless given there."""
    common = argparse.ArgumentParser(add_help=False)
    group = common.add_mutually_exclusive_group()
    group.add_argument("-v", "--verbose", action="count", default=argparse.SUPPRESS,
                       help="more log output (-vv for debug, with tracebacks on error)")
    group.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS,
                       help="only warnings and errors")
    return common


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser with every available sub-command configured."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        ver = version("crankbench")
    except PackageNotFoundError:
        ver = "unknown (not installed)"
    parser = argparse.ArgumentParser(
        prog="crankbench",
        description="Vibration-measurement analysis workbench for reciprocating engines.",
    )
    parser.add_argument("--version", action="version", version=f"crankbench {ver}")
    verbosity = parser.add_mutually_exclusive_group()
    verbosity.add_argument("-v", "--verbose", action="count", default=0,
                           help="more log output: each step's details and timings (-vv: with "
                            "tracebacks on error)")
    verbosity.add_argument("-q", "--quiet", action="store_true", help="only warnings and errors")
    common = verbosity_parent()
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        module = _load(name)
        if module is None:
            continue
        p = sub.add_parser(name, help=module.HELP, description=module.HELP, parents=[common])
        module.configure(p)
        p.set_defaults(_run=module.run)
    return parser


class _BarSafeHandler(logging.StreamHandler):
    """Writes log lines through ``tqdm.write`` so they never break a progress bar."""

    def emit(self, record):
        try:
            from tqdm import tqdm

            tqdm.write(self.format(record), file=self.stream)
        except Exception:  # noqa: BLE001 - logging must never raise
            self.handleError(record)


def _setup_logging(verbose: int, quiet: bool) -> None:
    """-q: warnings and errors; default: progress and results (INFO); -v: also the steps'
    details and timings (DEBUG); -vv: the same, with tracebacks on error."""
    level = logging.WARNING if quiet else (logging.DEBUG if verbose >= 1 else logging.INFO)
    handler = _BarSafeHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("%(levelname)s: %(message)s" if verbose else "%(message)s"))
    log.handlers[:] = [handler]
    log.setLevel(level)
    log.propagate = False


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the process exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    saved = (log.handlers[:], log.level, log.propagate)
    _setup_logging(args.verbose, args.quiet)
    try:
        if not getattr(args, "_run", None):
            parser.print_help()
            return 1
        with warnings.catch_warnings():  # restores showwarning on the way out
            # a warning (masked dropout, clipped channel...) reads as one log line, not as
            # Python's "file:line: Category: message" with a source line -- unless the caller
            # records warnings itself (catch_warnings(record=True), pytest.warns): then leave
            # them to it
            if getattr(warnings, "_showwarnmsg_impl", None) is _DEFAULT_SHOWWARNMSG:
                warnings.showwarning = _log_warning
            return _run(args)
    finally:  # main() may be called in-process (tests, notebooks): leave logging as found
        log.handlers[:], log.level, log.propagate = saved


def _log_warning(message, category, filename, lineno, file=None, line=None):
    log.warning("warning: %s", message)


def _run(args) -> int:
    try:
        return int(args._run(args) or 0)
    except (CrankbenchError, FileNotFoundError, FileExistsError, IsADirectoryError,
            PermissionError) as exc:
        if args.verbose >= 2:
            raise
        print(f"crankbench {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"crankbench {args.command}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # output piped into e.g. `head`, which closed early: not an error of ours
        import os

        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
