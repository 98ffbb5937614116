"""`LANGGAP_SMOKE=1` shrinks what a command simulates, says how, and leaves everything else as given."""

from __future__ import annotations

import contextlib
import io

import pytest

from langgap.cli import smoke
from langgap.cli.main import build_parser


def _shrunk(monkeypatch, argv: list[str], value: str = "1"):
    monkeypatch.setenv(smoke.ENV, value)
    args = build_parser().parse_args(argv)
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        smoke.apply(args)
    return args, err.getvalue()


def test_eval_keeps_two_tasks_one_episode_two_workers_and_says_so(monkeypatch):
    argv = ["eval", "--policy", "oracle", "--tasks", "spatial/s0/*", "--episodes", "20", "--workers", "8", "--run", "r"]
    args, note = _shrunk(monkeypatch, argv)
    assert args.tasks == "spatial/s0/black-bowl-1-on-plate,spatial/s0/black-bowl-2-on-plate"
    assert (args.episodes, args.workers, args.policy, args.run) == (1, 2, "oracle", "r")
    assert note.startswith("note: LANGGAP_SMOKE is set") and note.count("\n") == 1
    assert "--episodes 20 -> 1" in note and "--workers 8 -> 2" in note and "the first 2 of 13 tasks" in note


def test_the_default_selection_and_validate_s_positional_one_shrink_too(monkeypatch):
    args, note = _shrunk(monkeypatch, ["eval", "--policy", "blind", "--run", "r"])
    assert len(args.tasks.split(",")) == 2 and "the default selection" in note
    args, note = _shrunk(monkeypatch, ["validate", "--inits", "50"])
    assert len(args.tasks.split(",")) == 2 and "--inits 50 -> 1" in note


def test_small_values_and_other_commands_are_left_alone(monkeypatch):
    task = "spatial/s0/black-bowl-1-on-plate"
    argv = ["eval", "--policy", "oracle", "--tasks", task, "--episodes", "1", "--run", "r"]
    args, note = _shrunk(monkeypatch, argv)
    assert (args.tasks, args.episodes, note) == ("spatial/s0/black-bowl-1-on-plate", 1, "")
    args, note = _shrunk(monkeypatch, ["tasks", "list", "--tasks", "spatial/*"])
    assert (args.tasks, note) == ("spatial/*", "")


@pytest.mark.parametrize("value", ["", "0", "no"])
def test_unset_or_off_changes_nothing(monkeypatch, value):
    argv = ["collect", "--tasks", "train", "--demos", "150", "--out", "d", "--workers", "8"]
    args, note = _shrunk(monkeypatch, argv, value)
    assert (args.tasks, args.demos, args.workers, note) == ("train", 150, 8, "")


def test_training_and_audits_shrink_their_own_counts(monkeypatch):
    args, _ = _shrunk(monkeypatch, ["train", "small-bc", "--data", "d", "--steps", "4000", "--out", "c"])
    assert args.steps == smoke.CAPS["steps"]
    args, _ = _shrunk(monkeypatch, ["tasks", "audit", "--catalog", "libero-pro", "--starts", "50"])
    assert args.starts == 1 and len(args.tasks.split(",")) == 2
