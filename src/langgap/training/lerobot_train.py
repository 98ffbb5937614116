"""The paper's five fine-tuning experiments and the LeRobot policies that run them, as data, and the
`lerobot-train` command they make.

An experiment file (`experiments/expN.yaml`) says what is trained and evaluated: groups of training tasks with
their demonstrations per task (for `langgap collect`), the evaluation task sets (trained, held-out, original) and
episodes, the training steps and LoRA rank, and the paper's Table III row. A recipe file (`recipes/<policy>.yaml`)
says how one LeRobot policy trains: its `lerobot-train` options, its tunings (which parameters train and which
stay frozen: LoRA targets and alpha written out, never left to a default) and the options of its tiny version (a
random-weight model of a few hundred thousand parameters built offline, for a rehearsal on a CPU) where one can
be built. `train_command` joins the three into one argv.
"""

from __future__ import annotations

import shutil
import subprocess
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import yaml

from langgap.errors import DependencyNotInstalled, LangGapError

EXPERIMENTS = ("exp1", "exp2", "exp3", "exp4", "exp5")
POLICIES = ("pi05", "pi0", "smolvla", "act")
EVAL_SETS = ("trained", "heldout", "original")
TINY_VLM = "{tiny_vlm}"  # in a tiny recipe: the local SmolVLM directory the rehearsal builds
_EXPERIMENT_KEYS = ("name", "title", "train", "eval", "episodes", "steps", "lora_rank")  # and `paper`, the paper's
_RECIPE_KEYS = ("name", "title", "reads_instruction", "image_size", "lerobot", "tunings", "tiny")


@dataclass(frozen=True)
class TrainingGroup:
    """Tasks collected with the same number of demonstrations each."""

    tasks: str
    demos: int


@dataclass(frozen=True)
class Experiment:
    """One of the paper's fine-tuning experiments (or a file of the same form).

    Attributes:
        name: Its name (`exp1`).
        title: What it trains, in words.
        paper: The paper's Table III row (tasks, demos, lora_rank, steps, eval_tasks, episodes, baseline, result);
            empty for an experiment of one's own (a YAML file without `paper`).
        train: The training groups: a task selection and demonstrations per task each.
        eval: Evaluation task selections by set (`trained`, `heldout`, `original`).
        episodes: Evaluation episodes per task.
        steps: Training steps.
        lora_rank: The LoRA rank of the recipes that train with LoRA.
    """

    name: str
    title: str
    train: tuple[TrainingGroup, ...]
    eval: dict[str, str]
    episodes: int
    steps: int
    lora_rank: int
    paper: dict = field(default_factory=dict)

    def demonstrations(self, catalog, demos: int | None = None) -> int:
        """How many demonstrations it trains on: each group's tasks in `catalog` times their demonstrations per
        task (`demos` per task instead, for a rehearsal)."""
        return sum(len(catalog.select(g.tasks)) * (demos or g.demos) for g in self.train)


@dataclass(frozen=True)
class Tuning:
    """Which parameters of a policy train: its description, and the `lerobot-train` options that make it so."""

    name: str
    trains: str
    frozen: str
    options: dict


@dataclass(frozen=True)
class Recipe:
    """How one LeRobot policy is fine-tuned: `lerobot-train` options, tunings, and its tiny version's options."""

    name: str
    title: str
    reads_instruction: bool
    image_size: int
    lerobot: dict
    tunings: dict[str, Tuning]
    tiny: dict | None
    tiny_blocked_by: str = ""

    @property
    def default_tuning(self) -> str:
        """The first tuning the file lists (the paper's setting where it has one)."""
        return next(iter(self.tunings))

    def tuning(self, name: str | None) -> Tuning:
        """The tuning called `name` (None: the default)."""
        name = name or self.default_tuning
        if name not in self.tunings:
            raise LangGapError(f"{self.name} has no tuning {name!r} (it has: {', '.join(self.tunings)})")
        return self.tunings[name]


def _package_dir(name: str):
    return resources.files("langgap.training") / name


def _read_yaml(path, keys: tuple[str, ...], what: str) -> dict:
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError) as exc:
        raise LangGapError(f"cannot read {what} {path}: {exc}") from None
    if not isinstance(data, dict):
        raise LangGapError(f"{what} {path}: expected a mapping")
    missing = [k for k in keys if k not in data]
    if missing:
        raise LangGapError(f"{what} {path}: missing {', '.join(missing)}")
    return data


def _named_file(name_or_path: str, known: tuple[str, ...], folder: str, what: str):
    if name_or_path in known:
        return _package_dir(folder) / f"{name_or_path}.yaml"
    path = Path(name_or_path)
    if not path.is_file():
        raise LangGapError(f"unknown {what} {name_or_path!r} (known: {', '.join(known)}, or a YAML file)")
    return path


def load_experiment(name_or_path: str) -> Experiment:
    """One of `EXPERIMENTS` or a YAML file of the same form."""
    path = _named_file(name_or_path, EXPERIMENTS, "experiments", "experiment")
    data = _read_yaml(path, _EXPERIMENT_KEYS, "experiment")
    try:
        groups = tuple(TrainingGroup(tasks=str(g["tasks"]), demos=int(g["demos"])) for g in data["train"])
    except (TypeError, KeyError, ValueError):
        raise LangGapError(f"experiment {path}: train: expected a list of {{tasks, demos}}") from None
    unknown = set(data["eval"]) - set(EVAL_SETS)
    if not groups or unknown or "trained" not in data["eval"]:
        raise LangGapError(f"experiment {path}: needs training groups and eval sets among {', '.join(EVAL_SETS)}")
    if any(g.demos < 1 for g in groups):
        raise LangGapError(f"experiment {path}: demos must be at least 1")
    fields = {k: data[k] for k in _EXPERIMENT_KEYS if k not in ("train", "eval")}
    paper = data.get("paper") or {}
    if not isinstance(paper, dict):
        raise LangGapError(f"experiment {path}: paper: expected the paper's row as a mapping")
    evals = {s: data["eval"][s] for s in EVAL_SETS if s in data["eval"]}
    return Experiment(**fields, train=groups, eval=evals, paper=paper)


def load_recipe(name_or_path: str) -> Recipe:
    """One of `POLICIES` or a YAML file of the same form."""
    path = _named_file(name_or_path, POLICIES, "recipes", "policy recipe")
    data = _read_yaml(path, _RECIPE_KEYS, "policy recipe")
    tunings = {}
    for name, tuning in data["tunings"].items():
        options = dict(tuning.get("lerobot") or {})
        if "target_modules" in tuning:  # a LoRA tuning: targets and alpha are always stated
            if "lora_alpha" not in tuning:
                raise LangGapError(f"policy recipe {path}: tuning {name} sets LoRA targets without lora_alpha")
            options |= {
                "peft.method_type": "LORA",
                "peft.target_modules": tuning["target_modules"],
                "peft.lora_alpha": tuning["lora_alpha"],
            }
        tunings[name] = Tuning(name=name, trains=tuning["trains"], frozen=tuning["frozen"], options=options)
    if data["tiny"] is None and not data.get("tiny_blocked_by"):
        raise LangGapError(f"policy recipe {path}: without a tiny version, say why (tiny_blocked_by)")
    fields = {k: data[k] for k in _RECIPE_KEYS if k != "tunings"}
    return Recipe(**fields, tunings=tunings, tiny_blocked_by=data.get("tiny_blocked_by", ""))


def _flag(key: str, value) -> str:
    text = str(value).lower() if isinstance(value, bool) else "null" if value is None else str(value)
    return f"--{key}={text}"


def train_options(
    experiment: Experiment,
    recipe: Recipe,
    *,
    tuning: str | None = None,
    tiny: dict[str, str] | None = None,
    overrides: dict[str, str] | None = None,
) -> dict:
    """The `lerobot-train` options (without the dataset and output) of `experiment` trained as `recipe` says.

    Args:
        experiment: What is trained (its steps and LoRA rank are used).
        recipe: The policy and its options.
        tuning: Which of the recipe's tunings (None: its default).
        tiny: For a rehearsal with the recipe's tiny model: values of its placeholders (`tiny_vlm`,
            `image_size`); None trains the real policy.
        overrides: `lerobot-train` options set last (`steps=10`); values are strings, read as YAML scalars.
    """
    chosen = recipe.tuning(tuning)
    options = {**recipe.lerobot, "steps": experiment.steps, **chosen.options}
    if "peft.method_type" in options:
        options["peft.r"] = experiment.lora_rank
        if options["peft.lora_alpha"] == "rank":
            options["peft.lora_alpha"] = experiment.lora_rank
    if tiny is not None:
        if recipe.tiny is None:
            raise LangGapError(f"{recipe.name} has no tiny version: {recipe.tiny_blocked_by}")
        for key, value in recipe.tiny.items():
            options[key] = value.format(**tiny) if isinstance(value, str) else value
    for key, value in (overrides or {}).items():
        options[key] = yaml.safe_load(value) if value else value
    return options


def train_command(options: dict, *, dataset_root: str, repo_id: str, output_dir: str, job_name: str) -> list[str]:
    """The `lerobot-train` argv for `options` (`train_options`) on the LeRobot dataset at `dataset_root`."""
    options = {
        **options,
        "dataset.repo_id": repo_id,
        "dataset.root": str(dataset_root),
        "dataset.video_backend": "pyav",
        "output_dir": str(output_dir),
        "job_name": job_name,
        "wandb.enable": False,
    }
    return ["lerobot-train", *(_flag(k, v) for k, v in options.items())]


def lerobot_train_executable() -> str:
    """The `lerobot-train` of the LeRobot environment: beside this interpreter, else on PATH."""
    import sys

    beside = Path(sys.executable).parent / "lerobot-train"
    found = str(beside) if beside.exists() else shutil.which("lerobot-train")
    if found is None:
        raise DependencyNotInstalled("lerobot-train is not installed: run this in .venv-lerobot (./setup.sh makes it)")
    return found


def launch(command: list[str]) -> int:
    """Run `lerobot-train` (from the LeRobot environment); returns its exit code."""
    return subprocess.call([lerobot_train_executable(), *command[1:]])
