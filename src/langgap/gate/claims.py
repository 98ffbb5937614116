"""The benchmark's own claims: the tasks of a scene start from one state, no scene goal holds at t0, and
(with the `blind` policy's episodes) an instruction-blind policy does the scene's original task only.

A claim that fails is a release blocker.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from langgap.catalog.catalog import Catalog
from langgap.records import EpisodeRecord
from langgap.vocabulary import TaskKind


@dataclass
class Claim:
    """One of the benchmark's own claims, checked over every validated episode."""

    name: str
    holds: bool
    checked: int  # what it was checked on (pairs of scene and init state, episodes)
    violations: list[str] = field(default_factory=list)  # the first few, for the report


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
            f"every {TaskKind.EXTENDED} task starts from its source's state (one t0 hash per source task and init "
            "state)",
            len(t0),
            [f"{scene} init {init}: {n} different t0 states" for scene, init, n in differing],
        ),
        _claim(
            "no scene task's goal holds at t0",
            len(starts),
            [f"{s.task_id} init {s.init_index}: {', '.join(s.goals_at_start)}" for s in starts if s.goals_at_start],
        ),
    ]


def benchmark_claims(
    catalog: Catalog, records: list[EpisodeRecord], blind: list[EpisodeRecord] | None = None
) -> list[Claim]:
    """Check the claims the benchmark rests on, on the gate's episodes (and `blind`'s, when given). Workers
    switch a simulator between the tasks of one scene, so the t0 claim here mostly compares a scene with
    itself; `langgap.gate.probes.scene_starts` builds every task's own."""
    judged = [r for r in records if r.judged]
    claims = start_claims(
        [Start(r.task_id, r.source, r.init_index, r.t0_hash, tuple(r.goals_at_start)) for r in judged]
    )
    if blind is None:
        return claims
    oracle = {r.key: r.success for r in judged}
    originals = [r for r in blind if r.judged and r.kind == TaskKind.ORIGINAL and r.key in oracle]
    differing = [
        r
        for r in blind
        if r.judged and r.kind == TaskKind.EXTENDED and catalog.get(r.task_id).goal != catalog.get(r.source).goal
    ]
    claims += [
        _claim(
            f"blind succeeds on an {TaskKind.ORIGINAL} task exactly where the oracle does",
            len(originals),
            [
                f"{r.task_id} init {r.init_index}: blind {r.success}, oracle {oracle[r.key]}"
                for r in originals
                if r.success != oracle[r.key]
            ],
        ),  # fmt: skip
        _claim(
            f"blind never succeeds on an {TaskKind.EXTENDED} task whose goal differs from its source's",
            len(differing),
            [f"{r.task_id} init {r.init_index}" for r in differing if r.success],
        ),
    ]
    return claims
