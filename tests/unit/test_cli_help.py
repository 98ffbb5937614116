"""Every help text of the `langgap` command formats: the top level, every verb and sub-verb, and a bare `langgap`;
every flag and argument of every command has one, and every command's own `--help` says what it does.

argparse formats a help string only when it is shown, with `%`-formatting: a stray `%` in one help text crashes
`langgap --help` while every other command works, so each parser's help is formatted here."""

from __future__ import annotations

import argparse
import contextlib
import io

import pytest

from langgap.cli.main import build_parser, main
from tests.support.harness import cli_parsers

PARSERS = dict(cli_parsers(build_parser()))


def test_the_walk_reaches_verbs_and_sub_verbs():
    assert {"langgap", "langgap eval", "langgap tasks gate", "langgap train small-bc"} <= set(PARSERS)


@pytest.mark.parametrize("command", sorted(PARSERS))
def test_help_formats(command):
    text = PARSERS[command].format_help()
    assert text.startswith(f"usage: {command}")


@pytest.mark.parametrize("argv", [["--help"], ["-h"], []], ids=["--help", "-h", "bare"])
def test_the_top_level_help_prints_every_verb_and_exits_0(argv):
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        try:
            code = main(argv)
        except SystemExit as exc:  # argparse's --help exits; a bare command returns
            code = exc.code
    assert code == 0
    verbs = next(a for a in PARSERS["langgap"]._actions if isinstance(a, argparse._SubParsersAction)).choices
    assert all(f"    {verb}" in out.getvalue() for verb in verbs)


def test_every_flag_and_argument_of_every_command_has_help():
    missing = [
        f"{command} {action.option_strings[0] if action.option_strings else action.dest}"
        for command, parser in PARSERS.items()
        for action in parser._actions
        if not isinstance(action, argparse._SubParsersAction) and not action.help
    ]
    assert missing == []


def test_every_command_says_what_it_does_in_its_own_help():
    undescribed = [command for command, parser in PARSERS.items() if not parser.description]
    assert undescribed == []
    assert "check BDDL files" in PARSERS["langgap bddl"].format_help()
    assert "replay each demonstration's actions" in PARSERS["langgap verify-demos"].format_help()
