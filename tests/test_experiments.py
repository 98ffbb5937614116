"""The paper's experiments as configuration, and the lerobot-train command they make."""

from __future__ import annotations

import pytest

from langgap.catalog.catalog import load_catalog
from langgap.errors import LangGapError
from langgap.training.lerobot_train import EXPERIMENTS, load_experiment, train_command
from tests.support.harness import run_cli

# Table III of the paper: tasks, demos, LoRA rank, steps, eval tasks, episodes.
TABLE_III = {
    "exp1": ("1 ext", 56, 32, 20_000, "1", 10),
    "exp2": ("1+5 ext", 300, 64, 200_000, "5 ext", 10),
    "exp3": ("40+5 ext", 2000, 64, 200_000, "5 ext", 10),
    "exp4": ("16 ext", 2400, 64, 200_000, "16 ext", 5),
    "exp5": ("40+16 ext", 4093, 64, 200_000, "16 ext", 5),
}
EVAL_TASKS = {"exp1": 1, "exp2": 5, "exp3": 5, "exp4": 16, "exp5": 16}
TRAIN_TASKS = {"exp1": 1, "exp2": 6, "exp3": 45, "exp4": 16, "exp5": 56}


@pytest.mark.parametrize("name", EXPERIMENTS)
def test_experiment_matches_table_iii_and_selects_catalog_tasks(name):
    experiment = load_experiment(name)
    paper = experiment.paper
    row = (paper["tasks"], paper["demos"], paper["lora_rank"], paper["steps"], paper["eval_tasks"], paper["episodes"])
    assert row == TABLE_III[name]
    assert experiment.lerobot["peft.r"] == paper["lora_rank"] and experiment.lerobot["steps"] == paper["steps"]
    assert experiment.episodes == paper["episodes"]
    assert experiment.lerobot["batch_size"] == 8 and experiment.lerobot["policy.optimizer_lr"] == 1e-4
    catalog = load_catalog("langgap99")
    assert len(catalog.select(experiment.train_tasks)) == TRAIN_TASKS[name]
    evaluated = catalog.select(experiment.eval_tasks)
    assert len(evaluated) == EVAL_TASKS[name] and all(t.kind == "extended" for t in evaluated)


def test_train_command_is_a_lerobot_train_argv():
    command = train_command(
        load_experiment("exp2", {"steps": "10"}), dataset_root="/data/c/lerobot", repo_id="me/d", output_dir="/o"
    )
    assert command[0] == "lerobot-train"
    flags = dict(arg[2:].split("=", 1) for arg in command[1:])
    assert flags["policy.type"] == "pi05" and flags["peft.method_type"] == "LORA" and flags["peft.r"] == "64"
    assert flags["steps"] == "10" and flags["dataset.root"] == "/data/c/lerobot" and flags["dataset.repo_id"] == "me/d"
    assert flags["policy.push_to_hub"] == "false" and flags["output_dir"] == "/o"


def test_unknown_experiment_is_an_error():
    with pytest.raises(LangGapError, match="unknown experiment"):
        load_experiment("exp9")
    result = run_cli("train", "lerobot", "exp9", "--dataset-root", "d", "--output-dir", "o", "--dry-run")
    assert result.returncode == 2 and result.stderr.startswith("error: unknown experiment")
