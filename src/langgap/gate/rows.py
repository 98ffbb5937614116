"""The gate's verdict on one task: its checks over the oracle's episodes, and the row it makes."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from langgap.catalog.catalog import Catalog
from langgap.catalog.task import Task
from langgap.catalog.verdicts import SETTLE_CHECK, GateResult, verdict_of
from langgap.goals import Goal, plain_atoms
from langgap.records import EpisodeRecord
from langgap.vocabulary import FEASIBLE_RATE, TaskKind, Verdict

FULL_INITS = 50
SETTLE_TOLERANCE_M = 0.002


def shown_doable(successes: int, demonstrated: int, episodes: int) -> bool:
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
    def word(self) -> Verdict:
        """The row's verdict as a word (`verdict_of`; never infeasible: proofs are sought when it is recorded)."""
        return verdict_of(self.feasible, "", self.reason)

    @property
    def short(self) -> bool:
        """Whether the oracle's successes and the searched demonstrations together stay below the gate's rate."""
        return bool(self.episodes) and not shown_doable(self.successes, len(self.demonstrated_inits), self.episodes)

    def verdict(self, inits: int, made_by: str = "", proof: str = "", physics: dict | None = None) -> GateResult:
        """The verdict to record, for a gate that ran init states 0..`inits`-1 as `made_by` says, on the physics
        stack `physics` (with `proof`, the text of a proof that no policy can do the task,
        `langgap.gate.proofs`)."""
        return gate_result(
            self,
            inits,
            made_by,
            physics,
            proof=proof,
            demonstration=self.demonstration if self.demonstrated_inits else "",
            demonstrated_inits=tuple(self.demonstrated_inits),
        )


class JudgedRow(Protocol):
    """What a gate's row per task holds about the oracle's episodes (`TaskValidation`, a switch gate's row)."""

    episodes: int
    successes: int
    failed_inits: list[int]

    @property
    def feasible(self) -> bool: ...

    @property
    def reason(self) -> str: ...


def gate_result(row: JudgedRow, inits: int, made_by: str, physics: dict | None, **evidence) -> GateResult:
    """The verdict on `row`'s task for a gate that ran init states 0..`inits`-1 as `made_by` says, on the physics
    stack `physics`; `evidence`, the verdict's other fields (a proof, searched demonstrations)."""
    return GateResult(
        episodes=row.episodes,
        successes=row.successes,
        feasible=row.feasible,
        reason=row.reason,
        inits=inits,
        failed_inits=tuple(row.failed_inits),
        made_by=made_by,
        physics=dict(physics or {}),
        **evidence,
    )


def goals_exclude(a: Goal, b: Goal) -> bool:
    """True when both goals place the same object at different targets (so they cannot hold together)."""
    a_atoms, b_atoms = plain_atoms(a) or (), plain_atoms(b) or ()
    if len(a_atoms) != 1 or len(b_atoms) != 1:
        return False
    (p,), (q,) = a_atoms, b_atoms
    placements = ("On", "In")
    return p.name in placements and q.name in placements and p.args[0] == q.args[0] and p.args[1] != q.args[1]


def task_row(
    task: Task, catalog: Catalog, records: list[EpisodeRecord], drift: float, demonstrated: list[int]
) -> TaskValidation:
    """The verdict on one task: the oracle's episodes, with the init states a searched demonstration showed
    doable (`demonstrated`) counting toward the rate the gate asks for."""
    done = [r for r in records if r.judged]
    wins = [r for r in done if r.success]
    source = catalog.get(task.source)
    exclusive = task.kind == TaskKind.EXTENDED and goals_exclude(task.goal, source.goal)
    t0 = sum(task.id in r.goals_at_start for r in done)
    source_at_end = sum(source.id in r.goals_at_end for r in wins) if exclusive else 0
    rate = len(wins) / len(done) if done else 0.0
    checks = {
        f"success >= {FEASIBLE_RATE:.0%}": shown_doable(len(wins), len(demonstrated), len(done)),
        "goal false at t0": t0 == 0,
        "source goal false at end": source_at_end == 0,
        "env builds": len(done) > 0 and len(done) == len(records),
        SETTLE_CHECK: drift <= SETTLE_TOLERANCE_M,
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
