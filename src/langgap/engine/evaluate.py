"""The evaluator: plan a run from its spec, skip what the store already has, schedule the rest, store every episode."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterable, Iterator
from dataclasses import asdict, dataclass, field, replace
from datetime import UTC, datetime
from pathlib import Path

from langgap.catalog.catalog import Catalog, gate_snapshot, load_catalog
from langgap.catalog.task import Task
from langgap.engine.episode import gap_record
from langgap.engine.execute import scheduled, with_progress
from langgap.engine.filming import VideoSelection, replay_matches
from langgap.engine.plan import PlannedEpisode, build_plan
from langgap.engine.pools import WorkerPool, make_pool
from langgap.engine.runner import RunnerSetup
from langgap.engine.sharing import SharedRollout, policy_spec, share_rollouts
from langgap.engine.spec import PLAN_FIELDS, ExecutionOptions, RunSpec, SpecParameterError
from langgap.errors import LangGapError, one_line
from langgap.records import EpisodeKey, EpisodeRecord, Status
from langgap.store import PROGRESS, RunStore
from langgap.version import code_version
from langgap.vocabulary import Outcome


@dataclass
class RunSummary:
    """What one `evaluate` call did.

    Attributes:
        run: The run directory.
        planned: The episodes the spec plans.
        skipped: Those the store already held (a resume).
        ran: Those this call ran.
        successes: Of those, the successful ones.
        gaps: Of those, the ones infrastructure failed to run (stored as gaps, run again by a resume).
        policy_errors: Episodes that ended on a malformed action (outcome `policy_error`).
        policy_server: A shared policy's counters (Ray): calls, queries.
        filmed: Episodes with a clip among those `video` chose.
        shared: Episodes run inside shared rollouts (`share_rollouts`).
        rollouts: The shared rollouts they ran in.
        film_mismatches: Replays (per-outcome filming) that ended otherwise: no clip attached.
    """

    run: Path
    planned: int
    skipped: int
    ran: int = 0
    successes: int = 0
    gaps: int = 0
    policy_errors: int = 0
    policy_server: dict = field(default_factory=dict)
    filmed: int = 0
    shared: int = 0
    rollouts: int = 0
    film_mismatches: int = 0

    def rates(self, _latest: EpisodeRecord | None = None) -> str:
        """The running success rate (of judged episodes) and the gaps, for the progress bar."""
        return f"success={self.successes / max(1, self.ran - self.gaps):.0%}, gaps={self.gaps}"

    @property
    def complete(self) -> bool:
        """True when every planned episode is stored as judged (no gaps left)."""
        return self.gaps == 0


@dataclass(frozen=True)
class ResolvedRun:
    """A run's spec resolved once, where `evaluate` starts (`resolve_run`): the plan, the store's gate snapshot,
    the gaps' records and a worker in this process all read the one catalog and the one list of tasks.

    Attributes:
        spec: The spec (on a resume, with the tasks its stored run was created with).
        catalog: The spec's catalog, loaded.
        tasks: The spec's tasks, found in `catalog`, in the spec's order.
    """

    spec: RunSpec
    catalog: Catalog
    tasks: tuple[Task, ...]


def resolve_run(spec: RunSpec, run: Path, *, resume: bool = False) -> ResolvedRun:
    """`spec` resolved for a run into `run` (`resume`: the tasks the stored run holds, `_tasks_as_created`)."""
    if resume:
        spec = _tasks_as_created(spec, run)
    catalog = load_catalog(spec.catalog)
    return ResolvedRun(spec, catalog, tuple(catalog.get(t) for t in spec.tasks))


def plan_of(resolved: ResolvedRun) -> list[PlannedEpisode]:
    """Every episode of the run: each task × condition × init index of its spec."""
    spec = resolved.spec
    return build_plan(
        list(resolved.tasks),
        resolved.catalog,
        episodes=len(spec.inits),
        first_init=spec.inits[0],
        seed=spec.seed,
        repeats=spec.repeats,
        conditions=spec.conditions,
        style=spec.style,
    )


def still_to_run(plan: list[PlannedEpisode], done: set[EpisodeKey]) -> list[PlannedEpisode]:
    """The episodes of `plan` whose whole key (task, init state, seed, condition) is not among the judged ones
    stored (`done`): a resume runs them, gaps included, and a run grown by `--repeats` runs its new seeds."""
    return [p for p in plan if p.key not in done]


def _open_store(resolved: ResolvedRun, options: ExecutionOptions, run: Path, *, resume: bool, extend: bool) -> RunStore:
    """Create the run's store, or reopen it for a resume after checking that it holds the same run."""
    spec = resolved.spec
    if not (resume and RunStore.exists(run)):
        created = {"code_version": code_version(), "created_at": datetime.now(UTC).isoformat(timespec="seconds")}
        gate = gate_snapshot(spec.catalog, resolved.tasks)  # reports read these verdicts, never the live gate file
        return RunStore.create(
            run, {"spec": spec.to_dict(), "execution": asdict(options), "created": created, "gate": gate}
        )
    store = RunStore.open(run, write=True)
    try:
        stored = store.meta("spec") or {}
        differing = spec.differences(stored)
        growing = extend and not set(differing) - set(PLAN_FIELDS)
        if differing and not growing:
            hint = (
                " ({extend} grows a run's tasks, episodes or conditions)" if set(differing) <= set(PLAN_FIELDS) else ""
            )
            raise SpecParameterError(
                "run {path} was made with another spec: {differences}" + hint,
                path=run,
                differences=spec.describe_differences(stored, differing),
            )
        if differing:
            store.set_meta("spec", spec.to_dict())
            if (gate := store.meta("gate")) is not None:  # a run grown by --extend: verdicts of its new tasks
                store.set_meta("gate", gate_snapshot(spec.catalog, resolved.tasks, gate))
        store.set_meta("execution", asdict(options))
    except BaseException:
        store.close()
        raise
    return store


def _tasks_as_created(spec: RunSpec, run: Path) -> RunSpec:
    """`spec` with the tasks its selection resolved to when the stored run was created (the same selection
    on the same catalog): `feasible`, the default, follows the gate's verdicts, and a re-gate since must
    not change which tasks a resumed run holds."""
    if not RunStore.exists(run):
        return spec
    with RunStore.open(run) as store:
        stored = store.meta("spec") or {}
    if (stored.get("selection"), stored.get("catalog_hash")) != (spec.selection, spec.catalog_hash):
        return spec
    return replace(spec, tasks=tuple(stored["tasks"]))


def evaluate(
    spec: RunSpec,
    run: str | Path,
    options: ExecutionOptions | None = None,
    *,
    resume: bool = False,
    extend: bool = False,
) -> RunSummary:
    """Run (or resume) the evaluation `spec` into the run directory `run`; returns what was done.

    Everything that can be checked is checked before the store is touched: the spec (built by
    `RunSpec.create`), the execution options, the plan (init indices in range), and, when resuming,
    that the stored run has the same spec (`extend` lets it grow its tasks, inits or conditions).
    A run that hits `options.max_failure_streak` consecutive infrastructure failures with one cause
    raises `RunStopped`; every episode stored before stays, and a resume continues.

    Args:
        spec: What to run (`RunSpec.create`).
        run: The run directory: its episodes are stored in `episodes.sqlite` there, with their clips.
        options: How to run it (None: `ExecutionOptions()`, one worker process).
        resume: Continue the run stored in `run`: episodes it holds are skipped, the others (gaps included)
            run. Without it an existing run is refused.
        extend: With `resume`: the spec may grow the stored run's tasks, init states or conditions.

    Returns:
        What this call did: episodes planned, skipped, run, successes and gaps.

    Raises:
        SpecError: `resume` of a run stored with another spec.
        RunStopped: `options.max_failure_streak` infrastructure failures in a row with one cause.
        LangGapError: Options the backend cannot satisfy, a run that exists already (without `resume`) or
            that another process is writing, init indices out of range.
    """
    options = options or ExecutionOptions()
    run = Path(run)
    resolved = resolve_run(spec, run, resume=resume)
    spec = resolved.spec
    catalog = resolved.catalog  # loaded once: the plan, the store's gate snapshot and a worker here use it
    videos = options.video_selection
    plan = plan_of(resolved)
    firsts = videos.filmed_while_running([p.key for p in plan])
    plan = [replace(p, film=True) if p.key in firsts else p for p in plan]
    setup = RunnerSetup(
        catalog=spec.catalog,
        policy=spec.policy,
        policy_args=dict(spec.policy_args),
        style=spec.style,
        run_dir=str(run),
        stepping=spec.stepping,
        seed_scheme=spec.seed_scheme,
    )

    sharing = policy_spec(spec.policy, spec.policy_args) if options.share_rollouts else None

    def run_episodes(items: list[PlannedEpisode | SharedRollout], pool: WorkerPool) -> Iterator[EpisodeRecord]:
        def gap(planned: PlannedEpisode, error: str, attempts: int) -> EpisodeRecord:
            task = catalog.get(planned.key.task_id)
            return gap_record(
                planned, task, policy_name=spec.policy, error=error, attempts=attempts, physics=spec.physics
            )

        def make_gap(item: PlannedEpisode | SharedRollout, error: str, attempts: int):
            if isinstance(item, SharedRollout):
                return [gap(p, error, attempts) for p in item.members]
            return gap(item, error, attempts)

        return _episodes(scheduled(items, pool, options, make_gap))

    # The pool comes first: options it cannot satisfy (no Ray, too few GPUs) fail before a run
    # directory exists. Workers only start when the scheduler asks for them.
    pool = make_pool(setup, options, catalog)
    with contextlib.ExitStack() as stack:
        stack.callback(pool.close)
        store = stack.enter_context(_open_store(resolved, options, run, resume=resume, extend=extend))
        todo = still_to_run(plan, store.done_keys())
        summary = RunSummary(run, planned=len(plan), skipped=len(plan) - len(todo))
        items = todo if sharing is None else share_rollouts(todo, catalog, sharing, spec.style)
        shared = [item for item in items if isinstance(item, SharedRollout)]
        summary.shared, summary.rollouts = sum(len(item.members) for item in shared), len(shared)
        records = with_progress(
            _counted(run_episodes(items, pool), summary),
            len(todo),
            unit="ep",
            enabled=options.progress,
            describe=summary.rates,
        )
        store.set_meta(PROGRESS, {"planned": len(plan), "stopped": None})
        try:
            for record in records:
                store.write(record)
        except BaseException as exc:  # whatever ends the call early, a report of the run says it
            store.set_meta(PROGRESS, {"planned": len(plan), "stopped": _stop_reason(exc)})
            raise
    summary.policy_server = dict(getattr(pool, "server_stats", {}))  # set by closing a shared-policy pool
    if videos:

        def replay(todo: list[PlannedEpisode]) -> Iterator[EpisodeRecord]:
            pool = make_pool(setup, options, catalog)
            try:
                yield from run_episodes(todo, pool)
            finally:
                pool.close()

        _film(plan, videos, run, summary, replay, progress=options.progress)
    return summary


def _film(
    plan: list[PlannedEpisode],
    videos: VideoSelection,
    run: Path,
    summary: RunSummary,
    replay: Callable[[list[PlannedEpisode]], Iterator[EpisodeRecord]],
    *,
    progress: bool,
) -> None:
    """Give every episode `videos` chooses a clip: replay the chosen judged episodes that have none with the
    cameras on, and attach each clip whose replay ended as the stored episode did (else delete it). With
    `progress`, the replays have a bar of their own: they come after the run's bar has reached its end."""
    with RunStore.open(run, write=True) as store:
        stored = {r.key: r for r in store.records()}
        chosen = videos.choose([p.key for p in plan], stored.values())
        by_key = {p.key: p for p in plan}
        todo = [replace(by_key[k], film=True) for k in chosen if not stored[k].video]
        summary.filmed = len(chosen) - len(todo)
        if not todo:
            return
        replays = replay(todo)
        try:
            for record in with_progress(replays, len(todo), unit="clip", enabled=progress, label="filming"):
                if record.video is None:
                    continue
                if replay_matches(stored[record.key], record):
                    store.attach_video(record.key, record.video)
                    summary.filmed += 1
                else:
                    (run / record.video).unlink(missing_ok=True)
                    summary.film_mismatches += 1
        finally:
            replays.close()


def _stop_reason(exc: BaseException) -> str:
    """Why a call ended before its plan did, as the run's report states it."""
    if isinstance(exc, KeyboardInterrupt):
        return "interrupted"
    return str(exc) if isinstance(exc, LangGapError) else one_line(exc)


def _episodes(results: Iterable[EpisodeRecord | list[EpisodeRecord]]) -> Iterator[EpisodeRecord]:
    """The records of work items' results: a planned episode's record, each of a shared rollout's."""
    for result in results:
        if isinstance(result, list):
            yield from result
        else:
            yield result


def _counted(records: Iterable[EpisodeRecord], summary: RunSummary) -> Iterator[EpisodeRecord]:
    """`records`, counted into `summary` as they pass."""
    for record in records:
        summary.ran += 1
        summary.successes += record.success
        summary.gaps += record.status == Status.GAP
        summary.policy_errors += record.outcome == Outcome.POLICY_ERROR
        yield record
