"""`collect`: N successful oracle demonstrations per task, from sampled starts, on the engine's workers.

Each task's collection is one work item (`CollectTask`) for the engine's scheduler, so it runs on any
backend (`--backend local|ray`) with the scheduler's retries and timeouts. Attempt `j` of every task
uses env seed `seed + j`; attempts run in order until `demos` succeed or `max_attempts` are spent, so
the result depends only on the arguments, not on the workers or the backend. Failed attempts are
dropped (and counted); the states of kept ones are replayed once for their privileged observations.
Nothing is rendered here.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import ClassVar

from langgap import stack
from langgap.catalog.catalog import Catalog
from langgap.demos.compact import FORMAT_VERSION, read_manifest, save_demo, write_manifest
from langgap.demos.record import add_privileged, record_attempt
from langgap.engine.execute import execute
from langgap.engine.runner import RunnerSetup
from langgap.engine.spec import ExecutionOptions
from langgap.engine.work import Job, JobHost
from langgap.errors import LangGapError
from langgap.policies import make_policy
from langgap.sim.env import EnvOptions, TaskEnv
from langgap.version import code_version


@dataclass(frozen=True)
class CollectConfig:
    """What to collect. `policy` is the scripted demonstrator (`oracle`); `noise` is the standard deviation of
    the execution noise on its motion commands (see `ExecutionNoise`)."""

    catalog: str
    tasks: tuple[str, ...]
    demos: int
    seed: int = 0
    noise: float = 0.0
    style: str = "libero"
    max_attempts: int = 0  # per task; 0 = 3 * demos + 10
    policy: str = "oracle"

    @property
    def attempts_cap(self) -> int:
        return self.max_attempts or 3 * self.demos + 10


@dataclass
class TaskCollection:
    """How collecting one task went."""

    task_id: str
    attempts: int = 0
    kept: list[int] = field(default_factory=list)  # seeds of the kept demonstrations
    failed: list[int] = field(default_factory=list)  # seeds of dropped attempts
    steps: int = 0  # simulated policy steps, kept and dropped
    wall_time_s: float = 0.0

    @property
    def success_rate(self) -> float:
        return len(self.kept) / self.attempts if self.attempts else 0.0


@dataclass(frozen=True)
class CollectTask(Job):
    """The work item of one task's collection: its demonstrations go to the runner's output directory."""

    kind: ClassVar[str] = "collection"

    config: CollectConfig
    task_id: str

    @property
    def size(self) -> int:
        return self.config.attempts_cap

    def perform(self, runner: JobHost) -> TaskCollection:
        return collect_task(self.config, runner.catalog, self.task_id, runner.output_dir)


def collect_task(config: CollectConfig, catalog: Catalog, task_id: str, out: Path) -> TaskCollection:
    """Collect one task's demonstrations into `out`."""
    task = catalog.get(task_id)
    policy = make_policy(config.policy)
    stats = TaskCollection(task_id)
    started = time.perf_counter()
    with TaskEnv(task, EnvOptions(privileged=True)) as env:
        for attempt in range(config.attempts_cap):
            if len(stats.kept) == config.demos:
                break
            seed = config.seed + attempt
            success, demo = record_attempt(
                env, policy, task, catalog, seed=seed, style=config.style, noise=config.noise
            )
            stats.attempts += 1
            stats.steps += demo.length
            if not success:
                stats.failed.append(seed)
                continue
            add_privileged(env, demo)
            save_demo(out, demo)
            stats.kept.append(seed)
    stats.wall_time_s = time.perf_counter() - started
    return stats


def collect(config: CollectConfig, out: str | Path, options: ExecutionOptions | None = None) -> dict:
    """Collect every task of `config` into `out` (a task per work item, run as `options` say) and write its
    manifest; returns the manifest."""
    out = Path(out)
    if (out / "collection.json").exists():
        raise LangGapError(f"{out} already holds a collection ({read_manifest(out)['demos']} demos per task)")
    options = options or ExecutionOptions()
    setup = RunnerSetup(catalog=config.catalog, run_dir=str(out))
    items = [CollectTask(config, task_id) for task_id in config.tasks]
    results: dict[str, TaskCollection] = {}
    for stats in execute(items, setup, options, unit="task", describe=_describe):
        results[stats.task_id] = stats
    out.mkdir(parents=True, exist_ok=True)  # only now: a backend that cannot start leaves no directory
    manifest = {
        "format": FORMAT_VERSION,
        **asdict(config),
        "tasks": {
            task_id: {**asdict(stats), "success_rate": stats.success_rate} for task_id, stats in sorted(results.items())
        },
        "physics": stack.physics_stack(),
        "code_version": code_version(),
    }
    write_manifest(out, manifest)
    return manifest


def _describe(stats: TaskCollection) -> str:
    return f"{stats.task_id}: {len(stats.kept)}/{stats.attempts}"
