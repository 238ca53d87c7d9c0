"""Every ``casa`` option explains itself, and the defaults its help states are the code's."""

from __future__ import annotations

import argparse
import re

import pytest

from casa_core.cli import all_parsers, build_parser
from casa_core.defaults import EPSILON
from casa_core.learning import IRLConfig

#: Options whose parser default is None (the code fills it in later): the value the code uses.
CODE_DEFAULTS = {
    ("casa learn", "max_iterations"): IRLConfig().max_iterations,
    ("casa replay", "epsilon"): EPSILON,
}
_SKIPPED = (argparse._HelpAction, argparse._SubParsersAction, argparse._VersionAction)
_STATED = re.compile(r"default:? (-?\d[\d.e+-]*)")


def _options():
    for parser in all_parsers(build_parser()):
        for action in parser._actions:
            if not isinstance(action, _SKIPPED):
                yield parser, action


def _rendered(parser, action) -> str:
    """The help as ``--help`` prints it (argparse expands ``%(default)s`` and the like)."""
    return parser._get_formatter()._expand_help(action)


def test_every_option_and_argument_has_help():
    silent = [f"{p.prog} {a.option_strings or a.dest}" for p, a in _options() if not a.help]
    assert not silent, f"options without help: {silent}"


@pytest.mark.parametrize("parser", all_parsers(build_parser()), ids=lambda p: p.prog)
def test_no_help_prints_an_escaped_percent(parser):
    # A description is not %-formatted, so "%%" in it reaches the user as it is.
    assert "%%" not in parser.format_help()


def test_every_stated_default_is_the_one_the_code_uses():
    wrong, stated = [], 0
    for parser, action in _options():
        for number in _STATED.findall(_rendered(parser, action)):
            stated += 1
            used = CODE_DEFAULTS.get((parser.prog, action.dest), action.default)
            if used is None or float(number) != float(used):
                wrong.append(f"{parser.prog} {action.dest}: help says {number}, code uses {used}")
    assert not wrong, wrong
    assert stated >= 10  # the check reads the help it means to: casa has that many stated


def test_the_power_steps_name_the_target_that_runs_them_all():
    (power,) = [p for p in all_parsers(build_parser()) if p.prog == "casa power"]
    help_text = " ".join(power.format_help().split())
    assert "snakemake --cores all power" in help_text
