"""The paper's five fine-tuning experiments as data, and the `lerobot-train` command that runs one.

An experiment file (`experiments/expN.yaml`) names the training tasks and demonstrations per task
(for `langgap collect`), the evaluation tasks and episodes (for `langgap eval`), the paper's Table III
row, and the `lerobot-train` options; `experiments/_lerobot_common.yaml` holds the options all five
share. `train_command` turns one into an argv for a GPU machine with LeRobot installed.
"""

from __future__ import annotations

import shutil
import subprocess
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import yaml

from langgap.errors import DependencyNotInstalled, LangGapError

EXPERIMENTS = ("exp1", "exp2", "exp3", "exp4", "exp5")
_REQUIRED = ("name", "title", "paper", "train_tasks", "demos_per_task", "eval_tasks", "episodes", "lerobot")


@dataclass(frozen=True)
class Experiment:
    name: str
    title: str
    paper: dict
    train_tasks: str
    demos_per_task: int
    eval_tasks: str
    episodes: int
    lerobot: dict


def _experiment_dir():
    return resources.files("langgap.training") / "experiments"


def _read_yaml(path) -> dict:
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError) as exc:
        raise LangGapError(f"cannot read experiment {path}: {exc}") from None
    if not isinstance(data, dict):
        raise LangGapError(f"experiment {path}: expected a mapping")
    return data


def _coerce(value: str, like):
    if isinstance(like, bool):
        return value.lower() in ("1", "true", "yes")
    if isinstance(like, int | float):
        return type(like)(value)
    return value


def load_experiment(name_or_path: str, overrides: dict[str, str] | None = None) -> Experiment:
    """One of `EXPERIMENTS` or a YAML file of the same form; `overrides` set `lerobot` options (`steps=10`)."""
    path = Path(name_or_path)
    if name_or_path in EXPERIMENTS:
        path = _experiment_dir() / f"{name_or_path}.yaml"
    elif not path.is_file():
        raise LangGapError(f"unknown experiment {name_or_path!r} (known: {', '.join(EXPERIMENTS)}, or a YAML file)")
    data = _read_yaml(path)
    missing = [k for k in _REQUIRED if k not in data]
    if missing:
        raise LangGapError(f"experiment {path}: missing {', '.join(missing)}")
    common = _read_yaml(_experiment_dir() / "_lerobot_common.yaml")
    options = {**common, **data["lerobot"]}
    for key, value in (overrides or {}).items():
        options[key] = _coerce(value, options.get(key, ""))
    return Experiment(**{k: data[k] for k in _REQUIRED if k != "lerobot"}, lerobot=options)


def _flag(key: str, value) -> str:
    text = str(value).lower() if isinstance(value, bool) else str(value)
    return f"--{key}={text}"


def train_command(experiment: Experiment, *, dataset_root: str, repo_id: str, output_dir: str) -> list[str]:
    """The `lerobot-train` argv for `experiment` on the LeRobot dataset at `dataset_root`."""
    options = {
        **experiment.lerobot,
        "dataset.repo_id": repo_id,
        "dataset.root": str(dataset_root),
        "output_dir": str(output_dir),
        "job_name": f"langgap_{experiment.name}",
    }
    return ["lerobot-train", *(_flag(k, v) for k, v in options.items())]


def launch(command: list[str]) -> int:
    """Run `lerobot-train` (from the LeRobot environment); returns its exit code."""
    if shutil.which(command[0]) is None:
        raise DependencyNotInstalled(f"{command[0]} is not on PATH: run this in .venv-lerobot (./setup.sh makes it)")
    return subprocess.call(command)
