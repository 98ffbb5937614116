"""The evaluator core: plan a run, skip what the store already has, schedule the rest, store every episode."""

from __future__ import annotations

import sys
from collections.abc import Iterable, Iterator
from dataclasses import asdict, dataclass, field
from datetime import UTC, datetime
from pathlib import Path

from langgap import stack
from langgap.catalog.catalog import DEFAULT_CATALOG, load_catalog
from langgap.catalog.task import DEFAULT_STYLE
from langgap.engine.local import DEFAULT_MAX_ATTEMPTS, DEFAULT_TIMEOUT_S, LocalBackend, run_in_process
from langgap.engine.plan import build_plan
from langgap.engine.runner import RunnerSetup
from langgap.errors import LangGapError
from langgap.policies import policy_kwargs
from langgap.records import EpisodeRecord
from langgap.store import RunStore
from langgap.version import code_version

# A resumed run must agree on these, or its episodes would not be comparable.
IDENTITY_KEYS = ("policy", "policy_args", "catalog", "style", "seed", "physics")
PAPER_EPISODES = 20


@dataclass(frozen=True)
class EvalConfig:
    """One evaluation run (what `langgap eval` is asked to do)."""

    policy: str
    policy_args: dict[str, str] = field(default_factory=dict)
    catalog: str = DEFAULT_CATALOG
    tasks: str | None = None
    episodes: int = PAPER_EPISODES
    seed: int = 0
    conditions: tuple[str, ...] = ("given",)
    style: str = DEFAULT_STYLE
    workers: int = 1
    videos: int = 0  # record this many episodes (the first of the plan) as mp4
    timeout_s: float = DEFAULT_TIMEOUT_S
    max_attempts: int = DEFAULT_MAX_ATTEMPTS
    backend: str = "local"  # local | ray; not part of a run's identity: every backend gives the same episodes
    ray_address: str | None = None
    shared_policy: bool = False  # ray: one policy actor batching the queries of all environment actors
    max_batch: int = 8
    max_wait_ms: float = 5.0
    policy_gpus: float = 0.0


@dataclass
class RunSummary:
    run: Path
    planned: int
    skipped: int
    ran: int
    successes: int
    gaps: int


def _stored_config(config: EvalConfig) -> dict:
    data = asdict(config)
    data["conditions"] = list(config.conditions)
    data.update(
        physics=stack.physics_stack(),
        code_version=code_version(),
        created_at=datetime.now(UTC).isoformat(timespec="seconds"),
    )
    return data


def evaluate(config: EvalConfig, run: str | Path, *, resume: bool = False, progress: bool = True) -> RunSummary:
    """Run (or resume) an evaluation into the run directory `run`.

    Everything that can be checked is checked before the store is touched: the policy and its
    arguments, the task selection, the plan (init indices in range), and, when resuming, that the
    stored run was made with the same configuration.
    """
    policy_kwargs(config.policy, config.policy_args)
    _backend(config)  # an unknown backend or a missing Ray fails before anything is stored
    catalog = load_catalog(config.catalog)
    tasks = catalog.select(config.tasks)
    plan = build_plan(
        tasks, catalog, episodes=config.episodes, seed=config.seed, conditions=config.conditions, style=config.style
    )
    stored = _stored_config(config)
    store = (
        RunStore.open(run, write=True) if resume and RunStore.exists(run) else RunStore.create(run, {"config": stored})
    )
    with store:
        previous = store.meta("config") or {}
        differing = [k for k in IDENTITY_KEYS if previous.get(k) != stored.get(k)]
        if differing:
            raise LangGapError(f"run {run} was made with another configuration ({', '.join(differing)})")
        done = store.done_keys()
        todo = [p for p in plan if p.key not in done]
        setup = RunnerSetup(
            catalog=config.catalog,
            policy=config.policy,
            policy_args=dict(config.policy_args),
            style=config.style,
            video_dir=str(Path(run) / "videos") if config.videos else None,
            video_keys=frozenset(p.key for p in plan[: config.videos] if p.key not in done),
        )
        records = _backend(config).run(todo, setup)
        summary = RunSummary(Path(run), planned=len(plan), skipped=len(plan) - len(todo), ran=0, successes=0, gaps=0)
        for record in _with_progress(records, len(todo), summary, enabled=progress):
            store.write(record)
    return summary


class _InProcess:
    def __init__(self, max_attempts: int):
        self.max_attempts = max_attempts

    def run(self, plan, setup):
        return run_in_process(plan, setup, max_attempts=self.max_attempts)


def _backend(config: EvalConfig):
    if config.backend == "ray":
        from langgap.engine.ray_backend import RayBackend

        return RayBackend(
            config.workers, address=config.ray_address, timeout_s=config.timeout_s, max_attempts=config.max_attempts
        )
    if config.backend != "local":
        raise LangGapError(f"unknown backend {config.backend!r} (local or ray)")
    if config.shared_policy:
        raise LangGapError("--shared-policy needs --backend ray")
    if config.workers <= 0:
        return _InProcess(config.max_attempts)
    return LocalBackend(config.workers, timeout_s=config.timeout_s, max_attempts=config.max_attempts)


def _with_progress(
    records: Iterable[EpisodeRecord], total: int, summary: RunSummary, *, enabled: bool
) -> Iterator[EpisodeRecord]:
    """Count results into `summary` and show a progress bar (ETA, running success rate) on stderr."""
    bar = None
    if enabled and total:
        from tqdm import tqdm

        bar = tqdm(
            total=total,
            unit="ep",
            file=sys.stderr,
            dynamic_ncols=True,
            mininterval=0.5 if sys.stderr.isatty() else 30.0,
        )
    try:
        for record in records:
            yield record
            summary.ran += 1
            summary.successes += record.success
            summary.gaps += record.status == "gap"
            if bar is not None:
                valid = summary.ran - summary.gaps
                bar.set_postfix(success=f"{summary.successes / max(1, valid):.0%}", gaps=summary.gaps, refresh=False)
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()
