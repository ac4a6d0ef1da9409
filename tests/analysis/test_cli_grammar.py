"""One grammar for every command line (issue 19): lists comma-separated or repeated, every
number checked on entry, messages naming flags."""

from __future__ import annotations

import argparse

import pytest

from crankbench.analysis.cli import _name_flags, build_parser, flag_names
from crankbench.analysis.commands._args import ListAction


def _subparsers(parser, prefix=()):
    """(command words, parser) of every (nested) sub-command."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield prefix + (name,), sub
                yield from _subparsers(sub, prefix + (name,))


PARSER = build_parser()
COMMANDS = dict(_subparsers(PARSER))
POSITIONALS = {  # enough positionals for each command to parse
    ("info",): ["r.h5"], ("analyse",): ["r.h5", "--channel", "x", "--orders", "1"],
    ("synth",): ["s.toml", "-o", "o.h5"], ("compare",): ["r.h5", "m.toml"],
    ("report",): ["r.h5", "m.toml", "-o", "o.html"], ("batch",): ["r.h5", "--model", "m.toml"],
    ("balance",): ["a.toml"], ("predict", "balance"): ["e.toml"],
    ("predict", "torsion"): ["m.toml"], ("predict", "lateral"): ["m.toml"],
    ("predict", "flywheel"): ["e.toml", "--speed-rpm", "1000"], ("pressure",): ["r.h5"],
    ("import",): ["r.txt"], ("campaign",): ["c.duckdb"],
}


def _list_options():
    for words, parser in COMMANDS.items():
        for action in parser._actions:
            if isinstance(action, ListAction):
                yield words, action.option_strings[-1], action


def _parse(words, extra):
    return PARSER.parse_args(list(words) + POSITIONALS.get(words, []) + extra)


@pytest.mark.parametrize("words, flag, action", list(_list_options()),
                         ids=[" ".join(w) + " " + f for w, f, _ in _list_options()])
def test_list_options_take_commas_or_repetition_alike(words, flag, action):
    values = {"--orders": ("2", "4"), "--shafts": ("1", "2"), "--channels": ("a", "b"),
              "--channel": ("a", "b")}[flag]
    if words == ("analyse",) and flag == "--orders":
        base = POSITIONALS[words][:-2]
        comma = PARSER.parse_args(["analyse"] + base + [flag, ",".join(values)])
        repeat = PARSER.parse_args(["analyse"] + base + [flag, values[0], flag, values[1]])
    else:
        comma = _parse(words, [flag, ",".join(values)])
        repeat = _parse(words, [flag, values[0], flag, values[1]])
    assert getattr(comma, action.dest) == getattr(repeat, action.dest)
    assert len(getattr(comma, action.dest)) == 2


@pytest.mark.parametrize("text, message", [
    ("2,2", "2 is given twice"),
    ("2 4", "items are separated by commas"),
    ("2,,4", "has an empty item"),
    (",", "has an empty item"),
    ("", "empty value"),
])
def test_bad_lists_are_refused_naming_the_flag(text, message, capsys):
    with pytest.raises(SystemExit):
        PARSER.parse_args(["compare", "r.h5", "m.toml", "--orders", text])
    err = capsys.readouterr().err
    assert "argument --orders:" in err and message in err


def _numeric_options():
    for words, parser in COMMANDS.items():
        for action in parser._actions:
            if action.option_strings and action.type not in (None, str, str.upper) and \
                    not isinstance(action, ListAction) and action.choices is None:
                yield words, action.option_strings[-1], action


@pytest.mark.parametrize("words, flag, action", list(_numeric_options()),
                         ids=[" ".join(w) + " " + f for w, f, _ in _numeric_options()])
@pytest.mark.parametrize("bad", ["nan", "inf", "-1e400", "x"])
def test_every_numeric_option_refuses_non_finite_values(words, flag, action, bad, capsys):
    """No number reaches the work unchecked: NaN, infinity and garbage are usage errors."""
    nargs = action.nargs if isinstance(action.nargs, int) else 1
    with pytest.raises(SystemExit):
        _parse(words, [flag] + [bad] * nargs)
    assert f"argument {flag}" in capsys.readouterr().err


def test_no_numeric_option_uses_a_bare_float_or_int():
    """Every number option has a checking type (finite, bounded), not float/int."""
    bare = [f"{' '.join(w)} {a.option_strings[-1]}" for w, p in COMMANDS.items()
            for a in p._actions if a.type in (float, int) and a.choices is None]
    assert not bare, bare


def test_library_keywords_are_shown_as_flags():
    flags = flag_names(COMMANDS[("analyse",)])
    assert _name_flags("samples_per_rev=4 must be >= 8", flags) == "--samples-per-rev 4 must be >= 8"
    assert _name_flags("order 24 too high; use samples_per_rev >= 96", flags) == \
        "order 24 too high; use --samples-per-rev >= 96"
    # TOML keys (dotted, with spaces around =) and keywords of another unit stay as they are
    text = "m.toml: shaftline.revolutions = 3 bad; imep=2.4e6 Pa"
    assert _name_flags(text, flags) == text


def test_speed_range_takes_a_pair_in_either_form():
    from crankbench.analysis.commands._args import check_pair
    from crankbench.predict.errors import ConfigError

    assert check_pair(["800", "6000"], "--speed-range") == (800.0, 6000.0)
    assert check_pair(["800,6000"], "--speed-range") == (800.0, 6000.0)
    for bad, message in ((["800"], "expected two numbers"), (["6000", "800"], "LOW must be"),
                         (["-5", "10"], "must be >= 0"), (["1", "nan"], "not a finite")):
        with pytest.raises(ConfigError, match=message):
            check_pair(bad, "--speed-range", low=0.0)


def test_quantities_with_units_on_the_command_line():
    args = _parse(("predict", "flywheel"), ["--imep", "12 bar", "--radius", "250 mm"])
    assert args.imep == pytest.approx(1.2e6) and args.radius == pytest.approx(0.25)
    args = PARSER.parse_args(["predict", "flywheel", "e.toml", "--speed-rpm", "50 Hz"])
    assert args.speed_rpm == pytest.approx(3000.0)
