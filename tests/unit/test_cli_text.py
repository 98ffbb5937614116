"""What the command line says: a value argparse refuses ends in one `error:` line as every other bad input does,
`tasks list --suite` takes a suite as task ids name it, an invalid `switch:K` says what K must be, and the help
texts say what their flags mean in plain words."""

from __future__ import annotations

import argparse

import pytest

from langgap.cli.main import build_parser, main
from langgap.engine.spec import RunSpec, SpecError
from tests.support.harness import cli_parsers

PARSERS = dict(cli_parsers(build_parser()))


def _flag(command: str, flag: str):
    return next(a for a in PARSERS[command]._actions if flag in a.option_strings)


@pytest.mark.parametrize(
    ("argv", "line"),
    [
        (
            ["eval", "--policy", "noop", "--run", "r", "--episodes", "abc"],
            "error: langgap eval: --episodes takes a whole number, got 'abc' (see langgap eval --help)",
        ),
        (
            ["eval", "--policy", "noop", "--run", "r", "--timeout", "soon"],
            "error: langgap eval: --timeout takes a number, got 'soon' (see langgap eval --help)",
        ),
        (
            ["tasks", "list", "--kind", "new"],
            "error: langgap tasks list: argument --kind: invalid choice: 'new' (choose from 'original', 'extended') "
            "(see langgap tasks list --help)",
        ),
        (["eval", "--run", "r"], "error: langgap eval: the following arguments are required: --policy"),
    ],
)
def test_a_value_argparse_refuses_is_one_error_line(argv, line, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    out, err = capsys.readouterr()
    assert exit_.value.code == 2 and out == ""
    assert err.splitlines() == [err.strip()] and err.startswith(line)
    assert not (tmp_path / "r").exists()


def test_tasks_list_takes_a_suite_as_task_ids_name_it(capsys):
    assert build_parser().parse_args(["tasks", "list", "--suite", "spatial"]).suite == "libero_spatial"
    assert main(["tasks", "list", "--suite", "spatial"]) == 0
    short = capsys.readouterr().out
    assert main(["tasks", "list", "--suite", "libero_spatial"]) == 0
    assert short == capsys.readouterr().out and "spatial/s0/black-bowl-1-on-plate" in short


@pytest.mark.parametrize("condition", ["switch:abc", "switch:0", "switch:"])
def test_a_switch_without_a_whole_k_says_what_k_must_be(condition):
    with pytest.raises(SpecError) as error:
        RunSpec.create("noop", tasks="spatial/s0/black-bowl-1-on-plate", episodes=1, conditions=(condition,))
    assert str(error.value) == (
        f"'{condition}': switch:K takes K, the policy step at which the instruction changes, as a whole number of 1 "
        "or more"
    )


def test_an_unknown_condition_still_lists_the_conditions():
    with pytest.raises(SpecError, match=r"^unknown condition\(s\) \['loud'\] \(given: the task's instruction; "):
        RunSpec.create("noop", tasks="spatial/s0/black-bowl-1-on-plate", episodes=1, conditions=("loud",))


def test_the_help_texts_say_what_they_mean():
    attempts = _flag("langgap collect", "--max-task-attempts").help
    assert "gap" not in attempts and "collecting a task" in attempts
    assert "stored as a gap, with no verdict on the policy" in _flag("langgap eval", "--max-attempts").help
    for command in ("langgap tasks audit", "langgap tasks list", "langgap tasks gate", "langgap tasks replay"):
        selection = _flag(command, "--tasks").help
        assert "commas (any of them), & (all of them), ! before one (not it)" in selection, command
    assert "spatial, object, goal, libero10 name them too" in _flag("langgap tasks list", "--suite").help
    assert "small-vla" in PARSERS["langgap train"].format_usage()
    verbs = next(a for a in PARSERS["langgap"]._actions if isinstance(a, argparse._SubParsersAction))
    assert "small-vla" in next(a.help for a in verbs._choices_actions if a.dest == "train")
