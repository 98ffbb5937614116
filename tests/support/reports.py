"""Synthetic run stores for report tests: real SQLite, records made by hand."""

from __future__ import annotations

import dataclasses
from dataclasses import asdict
from pathlib import Path

from langgap.catalog.verdicts import GateResult
from langgap.records import EpisodeRecord, Status, classify
from langgap.store import RunStore
from langgap.vocabulary import Outcome

SCENE = "libero_spatial/s0"
SOURCE = "spatial/s0/bowl-on-plate"
TASKS = {  # task id -> (kind, dimension, split)
    SOURCE: ("original", "original", "original"),
    "spatial/s0/ramekin-on-plate": ("extended", "change_object", "train"),
    "spatial/s0/bowl-on-stove": ("extended", "change_target", "heldout"),
}


def episode(task_id: str, init_index: int, *, success=False, reached=None, condition="given", gap=False, **kw):
    """One stored episode of `task_id` (its outcome classified as the engine does)."""
    kind, dimension, split = TASKS[task_id]
    reached = reached or {}
    outcome = Outcome.GAP if gap else classify(task_id, kind, SOURCE, success, reached)
    return EpisodeRecord(
        task_id=task_id,
        init_index=init_index,
        seed=init_index,
        condition=condition,
        status=Status.GAP if gap else Status.DONE,
        success=success,
        outcome=outcome,
        failure_kind=None if success else ("infra" if gap else "policy"),
        error=None,
        steps=10,
        policy_calls=10,
        instruction=f"do {task_id}",
        instruction_sha256="0" * 64,
        t0_hash=str(init_index),
        reached=reached,
        suite="libero_spatial",
        max_steps=220,
        settle_steps=10,
        kind=kind,
        dimension=dimension,
        split=split,
        source=SOURCE,
        scene=SCENE,
        **kw,
    )


def beyond_episode(task_id: str, dimension: str, k: int, *, success=False, reached=None, wrong_order=False):
    """An episode of a `langgap-beyond` task of `SCENE` (ordering, negation, paraphrase, ...), classified as the
    engine does."""
    reached = reached or {}
    outcome = classify(task_id, "extended", SOURCE, success, reached, wrong_order=wrong_order)
    base = episode("spatial/s0/ramekin-on-plate", k, success=success, reached=reached)
    return dataclasses.replace(base, task_id=task_id, dimension=dimension, split="heldout", outcome=outcome)


def write_run(
    directory: Path, policy: str, records: list[EpisodeRecord], gates: dict[str, GateResult] | None = None, **spec
) -> Path:
    """A run store holding `records`, with a spec naming `policy` (and `spec`'s other fields); `gates`, the
    gate verdicts stored with it (None: a run stored before runs kept them)."""
    spec = {"policy": policy, "physics": {"mujoco": "3.2.3"}, "seed": 0, "style": "libero", **spec}
    meta = {"spec": spec}
    if gates is not None:
        verdicts = {t: asdict(g) for t, g in gates.items()}
        meta["gate"] = {"file": "test.gate.json", "sha256": ["0" * 64], "tasks": verdicts}
    with RunStore.create(directory, meta) as store:
        for record in records:
            store.write(record)
    return directory


def memoriser(init_indices=range(4), **kw) -> list[EpisodeRecord]:
    """A policy that does the scene's original task whatever it is asked (one gap on the stove task)."""
    records = [episode(SOURCE, k, success=True, reached={SOURCE: 5}, **kw) for k in init_indices]
    records += [episode("spatial/s0/ramekin-on-plate", k, reached={SOURCE: 7}, **kw) for k in init_indices]
    records += [episode("spatial/s0/bowl-on-stove", k, reached={SOURCE: 9}, **kw) for k in init_indices[:-1]]
    records.append(episode("spatial/s0/bowl-on-stove", init_indices[-1], gap=True, **kw))
    return records


def reader(init_indices=range(4), **kw) -> list[EpisodeRecord]:
    """A policy that does what it is asked, except the stove task at init 0 (where nothing happens)."""
    records = []
    for task in TASKS:
        for k in init_indices:
            ok = not (task == "spatial/s0/bowl-on-stove" and k == 0)
            records.append(episode(task, k, success=ok, reached={task: 5} if ok else {}, **kw))
    return records
