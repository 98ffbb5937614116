"""One of the paper's fine-tuning experiments end to end: collect → export → merge → `lerobot-train` → eval → report.

`plan` turns an experiment, a policy recipe and the user's settings into stages, each a command a user could type
(`langgap collect …`, `lerobot-train …`) with the output it writes and a check of whether that output is already
there and whole; `run` runs the stages that are not done, in order, and stops at the first that fails. Stages
that were interrupted continue where that is possible (`eval --resume`, `lerobot-train --resume`) and start again
otherwise (a collection or an export that was not finished is written anew). Everything lands under one output
directory:

    OUT/data/<group>/           a collection per training group (its LeRobot dataset in lerobot/)
    OUT/data/train/             the groups merged with LeRobot's aggregation (one group: its dataset is used)
    OUT/train/                  lerobot-train's output (checkpoints/last/pretrained_model is evaluated)
    OUT/eval/                   the run store of the trained, held-out and original tasks
    OUT/report.md, OUT/report/  `langgap report` of that run (Markdown, HTML)
    OUT/experiment.md           the result beside the paper's Table III row

Runs in the LeRobot environment (LeRobot's dataset API, `lerobot-train`, the `lerobot` policy).
"""

from __future__ import annotations

import json
import shlex
import shutil
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

from langgap.catalog.catalog import DEFAULT_CATALOG, load_catalog
from langgap.demos.compact import LEROBOT_DIR, demo_files, read_manifest, short_tasks
from langgap.demos.export import FPS
from langgap.errors import LangGapError
from langgap.training.lerobot_train import TINY_VLM, Experiment, Recipe, train_command, train_options
from langgap.vocabulary import TaskKind

REPO_ID = "local/langgap_experiment"
TINY_IMAGE_SIZE = 64
CHECKPOINT = Path("checkpoints") / "last" / "pretrained_model"
PAPER_COLUMNS = " Paper before fine-tuning | Paper after |"  # an experiment of the paper's: its row beside ours


@dataclass(frozen=True)
class Settings:
    """How an experiment is run here (what it *is* comes from the experiment and recipe files).

    Attributes:
        out: The output directory.
        tuning: The recipe's tuning (None: its default).
        tiny: Rehearse with the recipe's tiny random-weight model (built here) instead of the real policy.
        image_size: The dataset's image size (None: the recipe's; a tiny rehearsal uses 64).
        demos: Demonstrations per task of every group instead of the experiment's (a rehearsal).
        episodes: Evaluation episodes per task instead of the experiment's.
        eval_sets: Which evaluation sets run (default: every set the experiment names).
        seed: Collection seed (attempt j of a task uses env seed seed + j).
        noise: Execution noise of the demonstrations (`collect --noise`).
        originals: A local LeRobot dataset of LIBERO's original tasks (a `lerobot/libero` copy) used instead of
            collecting the experiment's `original` group.
        device: Where the policy trains and runs (`cuda`, `cpu`).
        workers: Worker processes of collection, rendering and evaluation.
        allow_short: Train on a collection in which some tasks kept fewer demonstrations than asked (the oracle
            with execution noise can fail every attempt at a task); otherwise such a collection stops the
            experiment. `experiment.md` says what was kept either way.
        overrides: `lerobot-train` options set last (`steps=2`).
    """

    out: Path
    tuning: str | None = None
    tiny: bool = False
    image_size: int | None = None
    demos: int | None = None
    episodes: int | None = None
    eval_sets: tuple[str, ...] | None = None
    seed: int = 0
    noise: float = 0.0
    originals: Path | None = None
    device: str = "cuda"
    workers: int = 1
    allow_short: bool = False
    overrides: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Stage:
    """One step of the experiment: the command that makes `output`, and whether `output` is already whole."""

    name: str
    command: list[str]
    output: Path
    done: Callable[[], bool]
    stdout: Path | None = None  # where the command's standard output is written (a report)
    clean: Callable[[], None] | None = None  # removes what an interrupted earlier attempt left, before the command
    accepted: tuple[int, ...] = (0,)  # the exit codes that mean the output was written
    hints: dict[int, str] = field(default_factory=dict)  # what an exit code that stops the experiment means

    def shown(self) -> str:
        """The command as a user would type it."""
        text = shlex.join(self.command)
        return f"{text} > {self.stdout}" if self.stdout else text


def _langgap(*args: str) -> list[str]:
    return ["langgap", *args]


def _collection_done(out: Path, tasks: tuple[str, ...], demos: int, settings: Settings) -> bool:
    """A whole collection of `tasks` with these settings is at `out`; another collection there is an error."""
    if not (out / "collection.json").exists():
        return False
    manifest = read_manifest(out)
    wanted = {"tasks": sorted(tasks), "demos": demos, "seed": settings.seed, "noise": settings.noise}
    found = {k: sorted(manifest["tasks"]) if k == "tasks" else manifest.get(k) for k in wanted}
    if found != wanted:
        raise LangGapError(f"{out} holds another collection ({found}, not {wanted}): remove it or choose another out")
    if not settings.allow_short and short_tasks(manifest):
        raise LangGapError(f"{out}: {_short(out, demos)}")  # the same answer every time it is run without the flag
    return True


def _short(out: Path, demos: int) -> str:
    """Why a collection with a task that kept fewer than `demos` demonstrations stops the experiment."""
    listed = out / "collection.json"
    return (
        f"some task kept fewer than {demos} demonstrations ({listed} lists each task's): --allow-short trains on "
        "what there is; a lower --noise keeps more"
    )


def _dataset_done(root: Path, episodes: Callable[[], int], image_size: int) -> bool:
    """A whole LeRobot dataset of `episodes()` episodes at `image_size`, with LangGap's fps label, is at `root`."""
    info_path = root / "meta" / "info.json"
    if not info_path.exists():
        return False
    info = json.loads(info_path.read_text(encoding="utf-8"))
    shape = info["features"]["observation.images.image"]["shape"]
    return info["total_episodes"] == episodes() and shape[0] == image_size and info["fps"] == FPS


def _remover(path: Path) -> Callable[[], None]:
    """Removes `path`: an export, merge or training that stopped part way is written anew (LeRobot's writers
    refuse a directory that exists)."""
    return lambda: shutil.rmtree(path, ignore_errors=True)


def _trained(train_dir: Path, steps: int) -> bool:
    state = train_dir / "checkpoints" / "last" / "training_state" / "training_step.json"
    return state.exists() and json.loads(state.read_text())["step"] >= steps


def _evaluated(run: Path, planned: int) -> bool:
    from langgap.store import RunStore

    if not RunStore.exists(run):
        return False
    with RunStore.open(run) as store:
        return len(store.done_keys()) >= planned


def plan(experiment: Experiment, recipe: Recipe, settings: Settings, catalog: str = DEFAULT_CATALOG) -> list[Stage]:
    """The stages of `experiment` trained as `recipe` says, run as `settings` say."""
    tasks = load_catalog(catalog)
    image_size = settings.image_size or (TINY_IMAGE_SIZE if settings.tiny else recipe.image_size)
    stages: list[Stage] = []
    datasets: list[Path] = []
    for index, group in enumerate(experiment.train):
        if settings.originals is not None and group.tasks == TaskKind.ORIGINAL:
            datasets.append(settings.originals)
        else:
            data = _group_dir(settings, index)
            demos = settings.demos or group.demos
            selected = tuple(t.id for t in tasks.select(group.tasks))
            stages += _data_stages(data, group.tasks, selected, demos, image_size, settings, catalog)
            datasets.append(data / LEROBOT_DIR)
    dataset = datasets[0]
    if len(datasets) > 1:
        dataset = settings.out / "data" / "train"
        merge = _langgap("merge-lerobot", str(dataset), *map(str, datasets))
        done = partial(_dataset_done, dataset, partial(_episodes, datasets), image_size)
        stages.append(Stage("merge", merge, dataset, done, clean=_remover(dataset)))
    stages += _train_stages(experiment, recipe, settings, dataset, image_size)
    stages += _eval_stages(experiment, settings, tasks, catalog)
    return stages


def _group_dir(settings: Settings, index: int) -> Path:
    """Where training group `index` is collected."""
    return settings.out / "data" / f"group{index}"


def _trained_on(experiment: Experiment, settings: Settings) -> list[str]:
    """What each training group's data holds: demonstrations kept of those asked, the tasks that kept fewer."""
    lines = []
    for index, group in enumerate(experiment.train):
        if settings.originals is not None and group.tasks == TaskKind.ORIGINAL:
            count = _episodes([settings.originals])
            lines.append(f"- `{group.tasks}`: {count} episodes of {settings.originals} (`--originals`)")
            continue
        data = _group_dir(settings, index)
        if not (data / "collection.json").exists():
            lines.append(f"- `{group.tasks}`: not collected ({data} holds no collection)")
            continue
        manifest = read_manifest(data)
        asked, tasks = manifest["demos"], manifest["tasks"]
        kept = sum(len(stats["kept"]) for stats in tasks.values())
        short = ", ".join(f"{task} {n}" for task, n in short_tasks(manifest).items())
        line = f"- `{group.tasks}`: {kept} of {asked * len(tasks)} demonstrations kept ({len(tasks)} tasks"
        lines.append(line + (f"; fewer than {asked}: {short})" if short else ")"))
    return lines


def _data_stages(
    data: Path, selection: str, tasks: tuple[str, ...], demos: int, image_size: int, settings: Settings, catalog: str
) -> list[Stage]:
    """Collect a training group's demonstrations and export them as a LeRobot dataset."""
    collect = _langgap(
        "collect", "--catalog", catalog, "--tasks", selection, "--demos", str(demos), "--out", str(data),
        "--seed", str(settings.seed), "--noise", str(settings.noise), "--format", "compact",
        "--workers", str(settings.workers),
    )  # fmt: skip
    export = _langgap("export-lerobot", str(data), "--image-size", str(image_size))
    export += ["--workers", str(settings.workers)]
    dataset = data / LEROBOT_DIR
    exported = partial(_dataset_done, dataset, lambda: len(demo_files(data)), image_size)
    # `langgap collect` exits 1 when it wrote the collection but some task kept fewer demonstrations than asked
    return [
        Stage(
            f"collect {selection}",
            collect,
            data,
            partial(_collection_done, data, tasks, demos, settings),
            accepted=(0, 1) if settings.allow_short else (0,),
            hints={1: _short(data, demos)},
        ),  # fmt: skip
        Stage(f"export {selection}", export, dataset, exported, clean=_remover(dataset)),
    ]


def _train_stages(
    experiment: Experiment, recipe: Recipe, settings: Settings, dataset: Path, image_size: int
) -> list[Stage]:
    """Build the tiny model of a rehearsal that needs one, then `lerobot-train` (continued where it stopped)."""
    stages = []
    train_dir = settings.out / "train"
    tiny_vlm = (settings.out / "tiny-smolvlm").resolve()
    tiny = {"tiny_vlm": str(tiny_vlm), "image_size": str(image_size)} if settings.tiny else None
    options = train_options(experiment, recipe, tuning=settings.tuning, tiny=tiny, overrides=settings.overrides)
    options["policy.device"] = settings.device
    if settings.tiny and TINY_VLM in recipe.tiny.values():
        build = _langgap("experiment", "tiny-smolvlm", str(tiny_vlm), "--image-size", str(image_size))
        stages.append(Stage("tiny model", build, tiny_vlm, lambda: (tiny_vlm / "config.json").exists()))
    last = train_dir / "checkpoints" / "last"
    clean = None
    if last.exists():  # an interrupted training continues from its last checkpoint
        command = ["lerobot-train", f"--config_path={last / 'pretrained_model' / 'train_config.json'}", "--resume=true"]
    else:
        command = train_command(
            options, dataset_root=str(dataset), repo_id=REPO_ID, output_dir=str(train_dir), job_name=experiment.name
        )
        clean = _remover(train_dir)  # lerobot-train refuses an output directory that exists
    stages.append(Stage("train", command, train_dir, partial(_trained, train_dir, int(options["steps"])), clean=clean))
    return stages


def _eval_stages(experiment: Experiment, settings: Settings, tasks, catalog: str) -> list[Stage]:
    """Evaluate the last checkpoint on the chosen sets (one run, resumed), then report the run."""
    sets = settings.eval_sets or tuple(experiment.eval)
    unknown = [s for s in sets if s not in experiment.eval]
    if unknown:
        known = ", ".join(experiment.eval)
        raise LangGapError(f"{experiment.name} has no eval set {', '.join(unknown)} (it has: {known})")
    selection = ",".join(experiment.eval[s] for s in sets)
    episodes = settings.episodes or experiment.episodes
    run_dir = settings.out / "eval"
    checkpoint = settings.out / "train" / CHECKPOINT
    evaluate = _langgap(
        "eval", "--catalog", catalog, "--policy", "lerobot", "--policy-arg", f"path={checkpoint}",
        "--policy-arg", f"device={settings.device}", "--tasks", selection, "--episodes", str(episodes),
        "--run", str(run_dir), "--resume", "--workers", str(settings.workers), "--quiet",
    )  # fmt: skip
    planned = len(tasks.select(selection)) * episodes
    report = _langgap("report", str(run_dir), "--html", str(settings.out / "report"))
    return [
        Stage("eval", evaluate, run_dir, partial(_evaluated, run_dir, planned)),
        Stage("report", report, settings.out / "report.md", lambda: False, stdout=settings.out / "report.md"),
    ]


def _episodes(datasets: list[Path]) -> int:
    return sum(json.loads((d / "meta" / "info.json").read_text())["total_episodes"] for d in datasets)


def _executable(command: list[str]) -> list[str]:
    """`command` as this environment runs it: `langgap` as this interpreter's module, `lerobot-train` beside it."""
    from langgap.training.lerobot_train import lerobot_train_executable

    if command[0] == "langgap":
        return [sys.executable, "-m", "langgap.cli.main", *command[1:]]
    return [lerobot_train_executable(), *command[1:]]


def run(stages: list[Stage], *, times: Path | None = None, say: Callable[[str], None] = print) -> None:
    """Run every stage that is not done, in order; a stage that fails stops the experiment with an error. With
    `times`, each stage run appends its wall time to that tab-separated file (stage, seconds, command)."""
    for index, stage in enumerate(stages, 1):
        if stage.done():
            say(f"[{index}/{len(stages)}] {stage.name}: done already ({stage.output})")
            continue
        say(f"[{index}/{len(stages)}] {stage.name}: {stage.shown()}")
        start = time.monotonic()
        if stage.clean is not None:
            stage.clean()
        if stage.stdout is not None:
            with open(stage.stdout, "w", encoding="utf-8") as sink:
                code = subprocess.call(_executable(stage.command), stdout=sink)
        else:
            code = subprocess.call(_executable(stage.command))
        if code not in stage.accepted:
            meaning = f": {stage.hints[code]}" if code in stage.hints else ""
            raise LangGapError(f"the {stage.name} stage failed (exit {code}){meaning}: {stage.shown()}")
        if times is not None:
            times.parent.mkdir(parents=True, exist_ok=True)
            with open(times, "a", encoding="utf-8") as sink:
                sink.write(f"{stage.name}\t{time.monotonic() - start:.1f}\t{stage.shown()}\n")


def summary(experiment: Experiment, recipe: Recipe, settings: Settings, catalog: str = DEFAULT_CATALOG) -> str:
    """The experiment's result beside the paper's Table III row, in Markdown: success per evaluation set with
    Wilson 95 % intervals, and what was trained."""
    from langgap.report.stats import wilson
    from langgap.store import RunStore

    tasks = load_catalog(catalog)
    with RunStore.open(settings.out / "eval") as store:
        records = [r for r in store.records() if r.judged]
    paper = experiment.paper
    tuning = recipe.tuning(settings.tuning)
    lines = [
        f"# {experiment.name}: {experiment.title}",
        "",
        f"Policy: {recipe.name}{' (tiny, random-weight rehearsal)' if settings.tiny else ''}, tuning "
        f"`{tuning.name}`: trains {tuning.trains}; frozen: {tuning.frozen}.",
        "",
        "Trained on:",
        *_trained_on(experiment, settings),
        "",
        "| Set | Tasks | Successes | Success % [95 % CI] |" + (PAPER_COLUMNS if paper else ""),
        "|---|---|---|---|" + ("---|---|" if paper else ""),
    ]
    for name, selection in experiment.eval.items():
        ids = {t.id for t in tasks.select(selection)}
        rows = [r for r in records if r.task_id in ids]
        if not rows:
            continue
        wins = sum(r.success for r in rows)
        low, high = wilson(wins, len(rows))
        rate = f"{100 * wins / len(rows):.1f} [{100 * low:.1f}, {100 * high:.1f}]"
        row = f"| {name} | {len(ids)} | {wins}/{len(rows)} | {rate} |"
        if paper:
            row += f" {paper['baseline']:.1f} | {paper['result']:.1f} |" if name == "trained" else " – | – |"
        lines.append(row)
    lines += ["", f"The paper's row: {paper}." if paper else "Not one of the paper's experiments: no row to compare."]
    return "\n".join(lines) + "\n"
