"""Every option of every verb has a check of its effect (`tests/support/flag_table.py`; `tests/test_flags.py`
runs them), and the help and messages name what the code does."""

from __future__ import annotations

import re

import pytest

from tests.support.flag_table import FLAG_CHECKS, REPO, ProvenBy, cli_options, proof_problem


def test_every_option_of_every_verb_has_a_check_and_every_check_an_option():
    options = cli_options()
    assert sorted(options - set(FLAG_CHECKS)) == [], "options with no check of their effect in FLAG_CHECKS"
    assert sorted(set(FLAG_CHECKS) - options) == [], "checks of options the parser no longer has"
    assert all(FLAG_CHECKS.values())


@pytest.mark.parametrize(
    ("option", "test"),
    [(option, c.test) for option, checks in FLAG_CHECKS.items() for c in checks if isinstance(c, ProvenBy)],
)
def test_the_test_that_proves_an_option_exists_and_uses_it(option, test):
    assert proof_problem(test, option.split()[-1]) is None


def test_eval_help_names_the_default_selection():
    from langgap.catalog.catalog import load_catalog
    from langgap.cli.main import build_parser

    eval_parser = build_parser()._subparsers._group_actions[0].choices["eval"]
    (tasks,) = [a for a in eval_parser._actions if "--tasks" in a.option_strings]
    assert "default: feasible" in tasks.help
    full = load_catalog("full")
    assert full.select(None) == full.select("feasible") != full.select("all")


def test_messages_name_only_options_setup_sh_has():
    usage = re.search(r"usage: \./setup\.sh (.*)\"", (REPO / "setup.sh").read_text()).group(1)
    known = set(re.findall(r"--[a-z-]+", usage))
    named = {
        (str(path.relative_to(REPO)), flag)
        for path in (REPO / "src").rglob("*.py")
        for flag in re.findall(r"setup\.sh (--[a-z-]+)", path.read_text())
    }
    assert {(path, flag) for path, flag in named if flag not in known} == set()
