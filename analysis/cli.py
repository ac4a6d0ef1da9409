"""The ``crankbench`` command line.

Each sub-command lives in its own module ``analysis/commands/<name>.py`` exposing ``HELP``
(one line), ``configure(parser)`` (adds its arguments) and ``run(args) -> int``. Modules import
their heavy dependencies inside ``run`` so ``crankbench --help`` stays fast.

Errors of the project's family (bad file, channel, key, option) are printed as one line naming
what was wrong, with exit status 2; a library message naming a keyword that is also a flag
names the flag (``--samples-per-rev``). Anything else is a bug of ours: one line, exit status
3. ``-vv`` re-raises with the traceback for debugging. A list option takes one
comma-separated value (``--orders 2,4``) or is repeated; ``--orders 2 4`` is refused with that
hint.
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
        p.set_defaults(_run=module.run, _flags=flag_names(p), _lists=list_flags(p))
    return parser


def flag_names(parser) -> dict:
    """``{dest: '--flag'}`` of a parser's options (for messages naming flags)."""
    out = {}
    for action in parser._actions:
        longs = [o for o in action.option_strings if o.startswith("--")]
        if longs and action.dest not in ("help", "verbose", "quiet"):
            out[action.dest] = longs[0]
    return out


def list_flags(parser) -> list:
    """The list options of a parser (one comma-separated value each, repeatable)."""
    from crankbench.analysis.commands._args import ListAction

    return [a.option_strings[-1] for a in parser._actions if isinstance(a, ListAction)]


#: library keyword names that mean exactly what the flag of the same name means (same unit):
#: an error naming the keyword is shown naming the flag ("samples_per_rev=4" ->
#: "--samples-per-rev 4"); others (imep in Pa against --imep in bar) are left alone
_SAME_AS_FLAG = ("samples_per_rev", "revolutions", "bandwidth_hz", "bandwidth_orders",
                 "filter_order", "speed_channel", "orders", "method", "amplitude", "gate",
                 "tolerance", "machine_class", "reference_rpm", "steady_fraction",
                 "min_change", "coefficient", "balance_factor", "max_order", "min_vector_sum",
                 "json_points", "workers", "speed_tolerance")


def _name_flags(message: str, flags: dict) -> str:
    """Replace ``keyword=value`` / ``use keyword`` of library messages by the flag."""
    import re

    for dest in _SAME_AS_FLAG:
        flag = flags.get(dest)
        if not flag:
            continue
        message = re.sub(rf"(?<![\w.\[-]){dest}=", f"{flag} ", message)
        message = re.sub(rf"(?<=use ){dest}\b", flag, message)
    return message




#: libraries whose own log lines are shown from -vv only
_QUIET_LIBRARIES = ("matplotlib", "fontTools", "weasyprint", "PIL")


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
    # third-party libraries' own log lines (matplotlib's font-cache fallbacks, fontTools...)
    # are not crankbench's messages: shown from -vv only
    for name in _QUIET_LIBRARIES:
        logging.getLogger(name).setLevel(logging.DEBUG if verbose >= 2 else logging.ERROR)


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the process exit status."""
    parser = build_parser()
    argv = sys.argv[1:] if argv is None else list(argv)
    args, extra = parser.parse_known_args(argv)
    if extra:
        _unrecognized(parser, args, argv, extra)
    saved = (log.handlers[:], log.level, log.propagate)
    saved_levels = {name: logging.getLogger(name).level for name in _QUIET_LIBRARIES}
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
        for name, level in saved_levels.items():
            logging.getLogger(name).setLevel(level)


def _unrecognized(parser, args, argv, extra):
    """Exit 2 on arguments no option takes, with a hint when a list was written with spaces
    (``--orders 2 4``)."""
    command = " ".join(x for x in (getattr(args, "command", None),
                                   getattr(args, "prediction", None)) if x)
    stray = " ".join(extra)
    hint = ""
    lists = getattr(args, "_lists", None) or []
    for i, token in enumerate(argv[:-2]):   # a list flag whose value is followed by a stray
        if token in lists and argv[i + 2] == extra[0]:
            a, b = argv[i + 1], argv[i + 2]
            hint = (f"; {token} takes one comma-separated list: write {token} {a},{b} (or "
                    f"repeat {token} {a} {token} {b})")
            break
    print(f"usage: crankbench {command} ... (see crankbench {command} --help)".replace(
        "  ", " "), file=sys.stderr)
    print(f"crankbench {command}: error: unrecognized arguments: {stray}{hint}".replace(
        "  ", " "), file=sys.stderr)
    raise SystemExit(2)


def _log_warning(message, category, filename, lineno, file=None, line=None):
    log.warning("warning: %s", message)


def _run(args) -> int:
    name = " ".join(x for x in (args.command, getattr(args, "prediction", None)) if x)
    try:
        return int(args._run(args) or 0)
    except (CrankbenchError, FileNotFoundError, FileExistsError, IsADirectoryError,
            NotADirectoryError, PermissionError) as exc:
        if args.verbose >= 2:
            raise
        text = _name_flags(str(exc), getattr(args, "_flags", {}) or {})
        print(f"crankbench {name}: error: {text}", file=sys.stderr)
        return 2
    except MemoryError as exc:
        if args.verbose >= 2:
            raise
        print(f"crankbench {name}: error: out of memory ({exc or 'MemoryError'}); the request "
              "is larger than this machine can hold: reduce it (shorter record, fewer orders, "
              "coarser model)", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"crankbench {name}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # output piped into e.g. `head`, which closed early: not an error of ours
        import os

        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0
    except OSError as exc:   # disk full, I/O error: one line, never a traceback
        if args.verbose >= 2:
            raise
        print(f"crankbench {name}: error: {exc}", file=sys.stderr)
        return 2
    except Exception as exc:  # noqa: BLE001 - a bug of ours: one line, the traceback on -vv
        if args.verbose >= 2:
            raise
        log.debug("internal error", exc_info=True)
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        print(f"crankbench {name}: internal error (a bug in crankbench, please report it with "
              f"the output of -vv): {type(exc).__name__}: {first}", file=sys.stderr)
        return 3


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
