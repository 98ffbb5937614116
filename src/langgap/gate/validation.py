"""The feasibility gate: the scripted oracle must prove a task physically doable before it ships.

`validate` runs the oracle (rendering off) on the first K fixed init states of each task through the
ordinary evaluation harness, then checks per task:

* success rate — below `FEASIBLE_RATE` the task is rejected (unproven: the oracle does not do it; only
  a proof from `langgap.gate.proofs`, recorded with `--record`, makes it infeasible);
* the goal is false at t0 (after settling) in every episode;
* for an extended task whose goal excludes its source's goal (the same object placed elsewhere), the
  source goal is false at the end of every successful episode;
* the environment builds and its scene settles (no infrastructure gap; objects at rest after the
  settle steps, on the first init states of each scene).

Then the benchmark's own claims, over every validated init state (`langgap.gate.claims`): the tasks of
a scene start from the identical state (equal t0 hashes per init state), no scene task's goal holds
at t0, and — with `blind=True`, which also runs the `blind` policy — the scene's original task done
whatever the instruction says succeeds exactly where the oracle does on originals and never on an
extended task whose goal differs. A claim that fails is a release blocker.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from langgap.catalog.catalog import load_catalog
from langgap.engine.evaluate import evaluate
from langgap.engine.pools import backend_session
from langgap.engine.spec import ExecutionOptions, RunSpec
from langgap.errors import ParameterError
from langgap.gate.claims import Claim, benchmark_claims
from langgap.gate.demonstrations import stored_demonstrations
from langgap.gate.probes import settle_drifts
from langgap.gate.recording import beside_registry, demonstrations_dir, prove_rejected
from langgap.gate.recording import record as record_verdicts
from langgap.gate.rows import FULL_INITS, TaskValidation, task_row
from langgap.gate.search import BUDGET, demonstrate
from langgap.records import EpisodeRecord
from langgap.stack import DEFAULT_STEPPING
from langgap.store import RunStore


@dataclass
class Validation:
    """What `validate` found: one row per task, and the benchmark's claims."""

    rows: list[TaskValidation]
    claims: list[Claim]
    inherited: list[str] = field(default_factory=list)  # selected tasks that take another task's verdict
    proofs: dict[str, str] = field(default_factory=dict)  # recorded proofs of impossibility: task id -> its text
    recorded: Path | None = None  # the verdict file written

    @property
    def passed(self) -> bool:
        return all(r.feasible for r in self.rows) and all(c.holds for c in self.claims)


def check_resume(resume: bool, run: str | Path | None) -> None:
    """Refuse `resume` without `run`, the directory of the validation to continue (a `ParameterError`)."""
    if resume and run is None:
        raise ParameterError("{resume} needs {run} (the directory of the validation to continue)")


def validate(
    catalog_name: str,
    selection: str | None = "all",
    *,
    inits: int = FULL_INITS,
    options: ExecutionOptions | None = None,
    run: str | Path | None = None,
    resume: bool = False,
    policy: str = "oracle",
    blind: bool = False,
    stepping: str = DEFAULT_STEPPING,
    search_budget: int | None = 0,
    demonstrations: str | Path | None = None,
    record: bool = False,
) -> Validation:
    """Run the gate on the selected tasks and check the benchmark's claims on its episodes.

    Every part (the episodes, the searches, the settle probes) is work for the engine's scheduler, run
    as `options` say (backend, workers, retries, timeouts, progress), all on one connection to the backend
    (one local Ray instance). A task with `gate_from` takes that task's verdict (its trial would repeat that
    one's exactly) and is not run: it is listed in `inherited`.

    Args:
        catalog_name: A shipped catalog's name, or the path of a registry file.
        selection: The tasks (a selection, as `Catalog.select` reads it; None: the default selection).
        inits: The init states each task runs on: 0..`inits`-1.
        options: How the work runs (None: `ExecutionOptions()`).
        run: The run directory that keeps the episodes (None: a temporary one).
        resume: Continue the interrupted validation kept in `run`.
        policy: The scripted policy that proves tasks.
        blind: Also run the `blind` policy on the same episodes (kept in `run`-blind when `run` is given) and
            check its claims.
        stepping: How the simulator steps (`langgap.vocabulary.Stepping`).
        search_budget: Candidate episodes searched for a demonstration on each init state the oracle fails
            (`langgap.gate.search`); those found are replayed and counted (0: no search; None: `BUDGET` for
            the oracle, else 0).
        demonstrations: The directory the searched demonstrations are stored in (None: beside the registry with
            `record`, else the run's, or a temporary one).
        record: Record the verdicts beside the catalog's registry, with the proofs of impossibility found for
            the tasks the oracle did below the gate's rate.

    Returns:
        A row per task, the claims, the tasks that take another's verdict; with `record`, the proofs and the
        verdict file written.

    Raises:
        ParameterError: `resume` without `run`, a negative `search_budget`, or a search for a policy other
            than the oracle.
    """
    check_resume(resume, run)
    if search_budget is not None and search_budget < 0:
        raise ParameterError("{search_budget} must be >= 0, got {budget}", budget=search_budget)
    if search_budget and policy != "oracle":
        raise ParameterError("{search_budget} varies the oracle's plan; {policy} {name} has none to vary", name=policy)
    if search_budget is None:
        search_budget = BUDGET if policy == "oracle" else 0
    if record and demonstrations is None:
        demonstrations = demonstrations_dir(catalog_name)
    catalog = load_catalog(catalog_name)
    selected = catalog.select(selection)
    tasks = [t for t in selected if t.gate_from is None]
    inherited = [t.id for t in selected if t.gate_from is not None]
    if not tasks:
        return Validation([], [], inherited)
    options = options or ExecutionOptions()

    def episodes(policy_name: str, directory: Path) -> list[EpisodeRecord]:
        ids = ",".join(t.id for t in tasks)
        spec = RunSpec.create(policy_name, catalog=catalog_name, tasks=ids, episodes=inits, stepping=stepping)
        evaluate(spec, directory, options, resume=resume, extend=resume)
        with RunStore.open(directory) as store:
            return store.records()

    with backend_session(options), tempfile.TemporaryDirectory(prefix="langgap-validate-") as scratch:
        directory = Path(run) if run is not None else Path(scratch) / "run"
        records = episodes(policy, directory)
        blind_records = episodes("blind", directory.with_name(directory.name + "-blind")) if blind else None
        demonstrated: dict[str, list[int]] = {}
        where = Path(demonstrations) if demonstrations is not None else directory / "demonstrations"
        if search_budget > 0 and policy == "oracle":
            failures: dict[str, list[tuple[int, int]]] = {}
            for r in records:
                if r.judged and not r.success:
                    failures.setdefault(r.task_id, []).append((r.init_index, r.seed))
            demonstrated = demonstrate(
                catalog_name, failures, where, stepping=stepping, budget=search_budget, options=options
            )
        drift_by_scene = settle_drifts(catalog_name, tasks, options)
    by_task: dict[str, list[EpisodeRecord]] = {}
    for episode in records:  # not `record`: that is the parameter saying whether to record the verdicts
        by_task.setdefault(episode.task_id, []).append(episode)
    rows = []
    for task in tasks:
        drift = drift_by_scene[(task.suite, task.scene_task)]
        row = task_row(task, catalog, by_task.get(task.id, []), drift, demonstrated.get(task.id, []))
        for init_index, path in stored_demonstrations(where / task.id).items():
            if init_index not in row.demonstrated_inits:
                path.unlink()  # an earlier gate's: this verdict does not rest on it
        if row.demonstrated_inits:
            row.demonstration = beside_registry(where / task.id, catalog_name)
        rows.append(row)
    claims = benchmark_claims(catalog, records, blind_records)
    if not record:
        return Validation(rows, claims, inherited)
    proofs = prove_rejected(catalog_name, rows, inits)
    path = record_verdicts(catalog_name, rows, inits=inits, policy=policy, stepping=stepping, proofs=proofs)
    return Validation(rows, claims, inherited, proofs, path)
