"""Switch feasibility verdicts of a catalog, beside its registry file as `<registry>.switch-gate.json`.

A `switch:K` episode starts under another task's instruction and switches to the task's own at policy
step K (`langgap.engine.plan`). That the task is doable from its start (the plain verdict,
`langgap.catalog.verdicts`) does not show it is doable from where K steps of another task leave the
scene, so `langgap validate --condition switch:K --record` records a verdict per task *and K*: the
oracle followed the switch on at least `langgap.vocabulary.SWITCH_RATE` of the init states, else *unproven* (never
infeasible: the oracle failing shows nothing about other policies). They are kept in their own file so
that re-recording the plain verdicts never touches them, and the other way round.

    {"about": {...}, "tasks": {"<task id>": {"switch:<K>": {<GateResult fields>}, ...}, ...}}
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from dataclasses import asdict
from pathlib import Path

from langgap.atomic import write_text_atomically
from langgap.catalog.verdicts import GateResult, exclusive, read_bytes, snapshot_file
from langgap.errors import CatalogError

# task id -> condition (`switch:K`) -> verdict
SwitchVerdicts = dict[str, dict[str, GateResult]]


def switch_verdicts_path(registry: str | Path) -> Path:
    registry = Path(registry)
    return registry.with_name(registry.name.removesuffix(".yaml") + ".switch-gate.json")


def read_switch_verdicts(registry: str | Path) -> SwitchVerdicts:
    """The recorded switch verdicts for the registry at `registry` (empty if none were recorded)."""
    path = switch_verdicts_path(registry)
    return _parse(path, read_bytes(path)) if path.is_file() else {}


def _parse(path: Path, content: bytes) -> SwitchVerdicts:
    try:
        data = json.loads(content.decode("utf-8"))
        return {task: _per_k(by_k) for task, by_k in data["tasks"].items()}
    except (ValueError, KeyError, TypeError, AttributeError) as exc:
        raise CatalogError(f"cannot read switch verdicts {path}: {exc}") from None


def _per_k(by_k: dict) -> dict[str, GateResult]:
    return {condition: GateResult(**fields) for condition, fields in by_k.items()}


def _dump(by_k: dict[str, GateResult]) -> dict:
    return {condition: asdict(verdict) for condition, verdict in sorted(by_k.items())}


def record_switch_verdicts(registry: str | Path, verdicts: SwitchVerdicts, about: dict) -> Path:
    """Merge `verdicts` into the registry's switch verdict file (atomically; a task's other K are kept)."""
    path = switch_verdicts_path(registry)
    with exclusive(path.parent):  # read, merge and write as one step: a concurrent recording is not lost
        merged = read_switch_verdicts(registry)
        for task_id, by_k in verdicts.items():
            merged[task_id] = merged.get(task_id, {}) | by_k
        data = {"about": about, "tasks": {task: _dump(merged[task]) for task in sorted(merged)}}
        write_text_atomically(path, json.dumps(data, indent=1, sort_keys=True) + "\n")
    return path


def snapshot_switch_verdicts(registry: str | Path, task_ids, previous: dict | None = None) -> dict:
    """The switch verdicts of `task_ids` as a run stores them (`verdicts.snapshot_verdicts`' rules)."""
    return snapshot_file(switch_verdicts_path(registry), task_ids, previous, _parse, _dump)


def snapshot_switch_gates(snapshot: dict) -> SwitchVerdicts:
    """The switch verdicts a run's snapshot (`snapshot_switch_verdicts`) holds."""
    return {task: _per_k(by_k) for task, by_k in snapshot["tasks"].items()}


def accepted(verdicts: SwitchVerdicts, task_id: str, condition: str, inits: Iterable[int] = ()) -> bool:
    """Whether the oracle's switch gate accepted `task_id` under `condition` (`switch:K`) on a gate that ran
    every init state of `inits` (a verdict made on init states 0–4 says nothing about init state 10)."""
    verdict = verdicts.get(task_id, {}).get(condition)
    return verdict is not None and verdict.feasible and all(i < verdict.inits for i in inits)
