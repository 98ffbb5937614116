"""The feasibility gate: the scripted oracle must prove a task physically doable before it ships.

`validate` runs the oracle (rendering off) on the first K fixed init states of each task through the
ordinary evaluation harness, then checks per task:

* success rate — below `FEASIBLE_RATE` the task is rejected (unproven: the oracle does not do it; only
  a proof from `langgap.proofs`, recorded with `--record`, makes it infeasible);
* the goal is false at t0 (after settling) in every episode;
* for an extended task whose goal excludes its source's goal (the same object placed elsewhere), the
  source goal is false at the end of every successful episode;
* the environment builds and its scene settles (no infrastructure gap; objects at rest after the
  settle steps, on the first init states of each scene).

Then the benchmark's own claims, over every validated init state (`benchmark_claims`): the tasks of
a scene start from the identical state (equal t0 hashes per init state), no scene task's goal holds
at t0, and — with `blind=True`, which also runs the `blind` policy — the scene's original task done
whatever the instruction says succeeds exactly where the oracle does on originals and never on an
extended task whose goal differs. A claim that fails is a release blocker.
"""

from __future__ import annotations

import tempfile
import warnings
from collections import Counter
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from langgap.catalog.catalog import Catalog, load_catalog, registry_path
from langgap.catalog.task import GateResult, Task
from langgap.catalog.verdicts import record_verdicts
from langgap.demos.searched import stored_demonstrations
from langgap.engine.evaluate import evaluate
from langgap.engine.spec import ExecutionOptions, RunSpec
from langgap.goals import Goal, plain_atoms
from langgap.records import EpisodeRecord
from langgap.search import demonstrate
from langgap.stack import DEFAULT_STEPPING, physics_stack
from langgap.store import RunStore
from langgap.version import code_version

FEASIBLE_RATE = 0.90
TARGET_RATE = 0.95
FULL_INITS = 50
SETTLE_INITS = 2
SETTLE_IDLE_STEPS = 20
SETTLE_TOLERANCE_M = 0.002


def _shown_doable(successes: int, demonstrated: int, episodes: int) -> bool:
    """Whether the oracle's successes and the searched demonstrations reach the gate's rate."""
    return bool(episodes) and (successes + demonstrated) / episodes >= FEASIBLE_RATE


@dataclass
class TaskValidation:
    """One row of the validation report."""

    id: str
    suite: str
    dimension: str
    episodes: int
    successes: int
    rate: float
    mean_steps: float
    max_steps: int
    gaps: int
    goal_true_at_t0: int
    source_true_at_end: int
    settle_drift_mm: float
    feasible: bool
    reason: str = ""
    checks: dict[str, bool] = field(default_factory=dict)
    failed_inits: list[int] = field(default_factory=list)  # judged episodes the oracle failed
    demonstrated_inits: list[int] = field(default_factory=list)  # of those, shown doable by a searched episode
    demonstration: str = ""  # where those demonstrations lie, relative to the registry's directory

    @property
    def short(self) -> bool:
        """Whether the oracle's successes and the searched demonstrations together stay below the gate's rate."""
        return bool(self.episodes) and not _shown_doable(self.successes, len(self.demonstrated_inits), self.episodes)

    def verdict(self, inits: int, made_by: str = "", proof: str = "") -> GateResult:
        """The verdict to record, for a gate that ran init states 0..`inits`-1 as `made_by` says (with `proof`,
        the text of a proof that no policy can do the task, `langgap.proofs`)."""
        return GateResult(
            episodes=self.episodes,
            successes=self.successes,
            feasible=self.feasible,
            reason=self.reason,
            inits=inits,
            failed_inits=tuple(self.failed_inits),
            made_by=made_by,
            proof=proof,
            demonstration=self.demonstration if self.demonstrated_inits else "",
            demonstrated_inits=tuple(self.demonstrated_inits),
        )


@dataclass
class Claim:
    """One of the benchmark's own claims, checked over every validated episode."""

    name: str
    holds: bool
    checked: int  # what it was checked on (pairs of scene and init state, episodes)
    violations: list[str] = field(default_factory=list)  # the first few, for the report


@dataclass
class Validation:
    """What `validate` found: one row per task, and the benchmark's claims."""

    rows: list[TaskValidation]
    claims: list[Claim]

    @property
    def passed(self) -> bool:
        return all(r.feasible for r in self.rows) and all(c.holds for c in self.claims)


SHOWN_VIOLATIONS = 5


def _claim(name: str, checked: int, violations: list[str]) -> Claim:
    return Claim(name, not violations, checked, violations[:SHOWN_VIOLATIONS])


@dataclass(frozen=True)
class Start:
    """How one task's episode starts from one init state: the state's hash, and the scene goals that hold."""

    task_id: str
    scene: str  # the original task whose scene and init states the task uses (its source)
    init_index: int
    t0_hash: str
    goals_at_start: tuple[str, ...]


def start_claims(starts: list[Start]) -> list[Claim]:
    """The claims about starts: one t0 state per source task and init state (an original and its extended
    tasks; LIBERO's suites reuse a scene layout across originals with their own init states), and no
    scene goal true at t0."""
    t0: dict[tuple[str, int], set[str]] = {}
    for s in starts:
        t0.setdefault((s.scene, s.init_index), set()).add(s.t0_hash)
    differing = [(scene, init, len(hashes)) for (scene, init), hashes in t0.items() if len(hashes) > 1]
    return [
        _claim(
            "every extended task starts from its source's state (one t0 hash per source task and init state)",
            len(t0),
            [f"{scene} init {init}: {n} different t0 states" for scene, init, n in differing],
        ),
        _claim(
            "no scene task's goal holds at t0",
            len(starts),
            [f"{s.task_id} init {s.init_index}: {', '.join(s.goals_at_start)}" for s in starts if s.goals_at_start],
        ),
    ]


def scene_starts(catalog: Catalog, tasks: list[Task], inits: int) -> list[Start]:
    """Every task's start from init states 0..`inits`-1, built from its own BDDL file (no policy runs).

    Each task gets a simulator of its own, never a sibling's switched over (as the engine's workers do),
    since the claim is that each task's own BDDL file yields its source's state."""
    from langgap.engine.episode import scene_goals
    from langgap.engine.plan import episode_seed
    from langgap.sim.env import TaskEnv

    starts = []
    for task in tasks:
        goals = scene_goals(task, catalog)
        with TaskEnv(task) as env:
            for index in range(min(inits, len(env.init_states))):
                env.reset(index, seed=episode_seed(0, index))
                t0 = env.t0_hash or ""
                env.settle()
                holding = tuple(name for name, goal in goals.items() if env.goal_holds(goal))
                starts.append(Start(task.id, task.source, index, t0, holding))
    return starts


def benchmark_claims(
    catalog: Catalog, records: list[EpisodeRecord], blind: list[EpisodeRecord] | None = None
) -> list[Claim]:
    """Check the claims the benchmark rests on, on the gate's episodes (and `blind`'s, when given). Workers
    switch a simulator between the tasks of one scene, so the t0 claim here mostly compares a scene with
    itself; `scene_starts` builds every task's own."""
    judged = [r for r in records if r.judged]
    claims = start_claims(
        [Start(r.task_id, r.source, r.init_index, r.t0_hash, tuple(r.goals_at_start)) for r in judged]
    )
    if blind is None:
        return claims
    oracle = {r.key: r.success for r in judged}
    originals = [r for r in blind if r.judged and r.kind == "original" and r.key in oracle]
    differing = [
        r
        for r in blind
        if r.judged and r.kind == "extended" and catalog.get(r.task_id).goal != catalog.get(r.source).goal
    ]
    claims += [
        _claim(
            "blind succeeds on an original task exactly where the oracle does",
            len(originals),
            [
                f"{r.task_id} init {r.init_index}: blind {r.success}, oracle {oracle[r.key]}"
                for r in originals
                if r.success != oracle[r.key]
            ],
        ),  # fmt: skip
        _claim(
            "blind never succeeds on an extended task whose goal differs from its source's",
            len(differing),
            [f"{r.task_id} init {r.init_index}" for r in differing if r.success],
        ),
    ]
    return claims


def claims_text(claims: list[Claim]) -> str:
    """One line per claim (and its first violations)."""
    lines = []
    for claim in claims:
        verdict = "holds" if claim.holds else "FAILS (release blocker)"
        lines.append(f"claim: {claim.name}: {verdict} ({claim.checked} checked)")
        lines += [f"  {v}" for v in claim.violations]
    return "\n".join(lines)


def goals_exclude(a: Goal, b: Goal) -> bool:
    """True when both goals place the same object at different targets (so they cannot hold together)."""
    a_atoms, b_atoms = plain_atoms(a) or (), plain_atoms(b) or ()
    if len(a_atoms) != 1 or len(b_atoms) != 1:
        return False
    (p,), (q,) = a_atoms, b_atoms
    placements = ("On", "In")
    return p.name in placements and q.name in placements and p.args[0] == q.args[0] and p.args[1] != q.args[1]


def settle_drift(task: Task, inits: int = SETTLE_INITS) -> float:
    """Largest displacement (m) of any object over idle steps after the settle steps, on the first init states."""
    from langgap.sim.env import TaskEnv

    worst = 0.0
    with TaskEnv(task) as env:
        bodies = [env.sim.model.body_name2id(o.root_body) for o in env.robosuite_env.objects_dict.values()]
        for index in range(min(inits, len(env.init_states))):
            env.reset(index)
            env.settle()
            before = env.sim.data.body_xpos[bodies].copy()
            env.settle(SETTLE_IDLE_STEPS)
            after = env.sim.data.body_xpos[bodies]
            worst = max(worst, float(np.linalg.norm(after - before, axis=1).max()))
    return worst


def _row(
    task: Task, catalog: Catalog, records: list[EpisodeRecord], drift: float, demonstrated: list[int]
) -> TaskValidation:
    """The verdict on one task: the oracle's episodes, with the init states a searched demonstration showed
    doable (`demonstrated`) counting toward the rate the gate asks for."""
    done = [r for r in records if r.judged]
    wins = [r for r in done if r.success]
    source = catalog.get(task.source)
    exclusive = task.kind == "extended" and goals_exclude(task.goal, source.goal)
    t0 = sum(task.id in r.goals_at_start for r in done)
    source_at_end = sum(source.id in r.goals_at_end for r in wins) if exclusive else 0
    rate = len(wins) / len(done) if done else 0.0
    checks = {
        f"success >= {FEASIBLE_RATE:.0%}": _shown_doable(len(wins), len(demonstrated), len(done)),
        "goal false at t0": t0 == 0,
        "source goal false at end": source_at_end == 0,
        "env builds": len(done) > 0 and len(done) == len(records),
        "scene settles": drift <= SETTLE_TOLERANCE_M,
    }
    failed = [name for name, ok in checks.items() if not ok]
    reason = "; ".join(failed)
    if failed and checks[f"success >= {FEASIBLE_RATE:.0%}"] is False:
        reason = reason.replace(f"success >= {FEASIBLE_RATE:.0%}", f"oracle {len(wins)}/{len(done)}")
    steps = [r.steps for r in wins]
    return TaskValidation(
        id=task.id,
        suite=task.suite,
        dimension=task.dimension,
        episodes=len(done),
        successes=len(wins),
        rate=rate,
        mean_steps=float(np.mean(steps)) if steps else 0.0,
        max_steps=max(steps, default=0),
        gaps=len(records) - len(done),
        goal_true_at_t0=t0,
        source_true_at_end=source_at_end,
        settle_drift_mm=drift * 1000,
        feasible=not failed,
        reason=reason,
        checks=checks,
        failed_inits=sorted(r.init_index for r in done if not r.success),
        demonstrated_inits=sorted(demonstrated),
    )


def validate(
    catalog_name: str,
    selection: str | None = "all",
    *,
    inits: int = FULL_INITS,
    workers: int = 1,
    run: str | Path | None = None,
    resume: bool = False,
    policy: str = "oracle",
    progress: bool = True,
    blind: bool = False,
    stepping: str = DEFAULT_STEPPING,
    search_budget: int = 0,
    demonstrations: str | Path | None = None,
) -> Validation:
    """Run the gate on the selected tasks and check the benchmark's claims on its episodes; with
    `blind`, the `blind` policy runs the same episodes too (kept in `run`-blind when `run` is given).

    With a `search_budget`, each init state the oracle fails gets a search for a demonstration
    (`langgap.search`, that many candidate episodes); those found are stored under `demonstrations`
    (a directory; the run's, or a temporary one, when None), replayed from there and counted."""
    catalog = load_catalog(catalog_name)
    tasks = catalog.select(selection)
    options = ExecutionOptions(workers=workers, progress=progress)

    def episodes(policy_name: str, directory: Path) -> list[EpisodeRecord]:
        ids = ",".join(t.id for t in tasks)
        spec = RunSpec.create(policy_name, catalog=catalog_name, tasks=ids, episodes=inits, stepping=stepping)
        evaluate(spec, directory, options, resume=resume, extend=resume)
        with RunStore.open(directory) as store:
            return store.records()

    with tempfile.TemporaryDirectory(prefix="langgap-validate-") as scratch:
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
            demonstrated = demonstrate(catalog, failures, where, stepping=stepping, budget=search_budget)
    by_task: dict[str, list[EpisodeRecord]] = {}
    for record in records:
        by_task.setdefault(record.task_id, []).append(record)
    drift_by_scene: dict[tuple[str, str], float] = {}
    rows = []
    for task in tasks:
        scene = (task.suite, task.scene_task)
        if scene not in drift_by_scene:
            drift_by_scene[scene] = settle_drift(task)
        row = _row(task, catalog, by_task.get(task.id, []), drift_by_scene[scene], demonstrated.get(task.id, []))
        for init_index, path in stored_demonstrations(where / task.id).items():
            if init_index not in row.demonstrated_inits:
                path.unlink()  # an earlier gate's: this verdict does not rest on it
        if row.demonstrated_inits:
            row.demonstration = _beside_registry(where / task.id, catalog_name)
        rows.append(row)
    return Validation(rows, benchmark_claims(catalog, records, blind_records))


def _beside_registry(path: Path, catalog_name: str) -> str:
    """`path` relative to the catalog registry's directory when it lies there (as verdicts name their
    evidence), else as it is."""
    try:
        return path.resolve().relative_to(registry_path(catalog_name).parent.resolve()).as_posix()
    except ValueError:
        return str(path)


def demonstrations_dir(catalog_name: str) -> Path:
    """Where `validate --record` stores a catalog's searched demonstrations: beside its registry file."""
    registry = registry_path(catalog_name)
    return registry.parent / "demonstrations" / registry.stem


def prove_rejected(catalog_name: str, rows: list[TaskValidation], inits: int) -> dict[str, str]:
    """Proofs of impossibility (`langgap.proofs`) for the tasks the oracle did below the gate's rate, read
    from each task's simulator on init states 0..`inits`-1: task id -> the proof's text, for those that
    have one. A task with none stays unproven: the oracle failing it shows nothing about other policies."""
    from langgap.proofs import prove_tasks

    catalog = load_catalog(catalog_name)
    below = {r.id: r for r in rows if r.short}
    found = {}
    for task_id, proof in prove_tasks([catalog.get(i) for i in below], inits).items():
        if below[task_id].successes:  # an episode refutes it: the prover is wrong, not the episodes
            warnings.warn(f"{task_id}: a proof of impossibility, yet the gate did it {below[task_id].successes} "
                          f"time(s); not recorded: {proof.text()}", stacklevel=2)  # fmt: skip
        else:
            found[task_id] = proof.text()
    return found


def record(
    catalog_name: str,
    rows: list[TaskValidation],
    *,
    inits: int,
    policy: str = "oracle",
    stepping: str = DEFAULT_STEPPING,
    proofs: dict[str, str] | None = None,
) -> Path:
    """Record the rows' verdicts beside the catalog's registry file, with the proofs of impossibility
    `proofs` gives (None: those `prove_rejected` finds)."""
    about = {
        "policy": policy,
        "inits": inits,
        "feasible_rate": FEASIBLE_RATE,
        "physics": physics_stack(stepping),
        "code_version": code_version(),
    }
    made_by = f"{policy}, langgap {about['code_version']}, {stepping} stepping"
    if proofs is None:
        proofs = prove_rejected(catalog_name, rows, inits)
    verdicts = {r.id: r.verdict(inits, made_by, proofs.get(r.id, "")) for r in rows}
    return record_verdicts(registry_path(catalog_name), verdicts, about)


def report(found: Validation) -> dict:
    """The validation as JSON data: a row per task, and the claims."""
    return {"tasks": [asdict(r) for r in found.rows], "claims": [asdict(c) for c in found.claims]}


def table_text(rows: list[TaskValidation]) -> str:
    """A printed table: one line per task, then the totals."""
    width = max((len(r.id) for r in rows), default=4)
    lines = [f"{'task':<{width}}  {'oracle':>9}  {'rate':>6}  {'steps':>11}  verdict"]
    for r in rows:
        verdict = "ok" if r.feasible else f"REJECTED ({r.reason})"
        if r.feasible and r.rate < TARGET_RATE:
            verdict = f"ok, below the {TARGET_RATE:.0%} target"
        if r.demonstrated_inits:
            verdict += f"; searched demonstrations on init state(s) {', '.join(map(str, r.demonstrated_inits))}"
        lines.append(
            f"{r.id:<{width}}  {r.successes:>4}/{r.episodes:<4}  {100 * r.rate:>5.1f}%  "
            f"{r.mean_steps:>5.0f}/{r.max_steps:<5}  {verdict}"
        )
    episodes = sum(r.episodes for r in rows)
    successes = sum(r.successes for r in rows)
    below = [r.id for r in rows if r.rate < TARGET_RATE]
    lines.append(
        f"{len(rows)} tasks, {successes}/{episodes} oracle successes "
        f"({100 * successes / max(1, episodes):.1f}%); {sum(not r.feasible for r in rows)} rejected; "
        f"{len(below)} below {TARGET_RATE:.0%}"
    )
    return "\n".join(lines)


def gate_summary(rows: list[TaskValidation]) -> str:
    """Accepted / rejected counts, rejections grouped by the checks they failed."""
    rejected = [r for r in rows if not r.feasible]
    lines = [f"gate: {len(rows) - len(rejected)} accepted, {len(rejected)} rejected"]
    for reason, count in Counter(
        r.reason.split(";")[0].split(" ")[0] if r.reason.startswith("oracle") else r.reason for r in rejected
    ).most_common():
        lines.append(f"  rejected {count:>4}: {reason}")
    return "\n".join(lines)
