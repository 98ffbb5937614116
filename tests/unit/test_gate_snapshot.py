"""The gate snapshot a run stores: its tasks' verdicts and the verdict file's hash, kept as taken."""

from __future__ import annotations

import hashlib
import json

from langgap.catalog.verdicts import snapshot_gates, snapshot_verdicts


def _record(registry, **rates) -> str:
    """Write verdicts (task -> oracle successes of 2) beside `registry`; returns the file's SHA-256."""
    tasks = {t: {"episodes": 2, "successes": s, "feasible": s == 2, "inits": 2} for t, s in rates.items()}
    path = registry.with_name("c.gate.json")
    path.write_text(json.dumps({"about": {}, "tasks": tasks}))
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_a_snapshot_keeps_its_verdicts_and_only_adds_the_tasks_it_lacks(tmp_path):
    registry = tmp_path / "c.yaml"
    assert snapshot_verdicts(registry, ["a"]) == {"file": "c.gate.json", "sha256": [], "tasks": {}}
    first = _record(registry, a=2, b=2)
    snapshot = snapshot_verdicts(registry, ["a"])
    assert snapshot["sha256"] == [first] and list(snapshot["tasks"]) == ["a"]
    second = _record(registry, a=0, b=1)  # a re-gate: `a` rejected now
    grown = snapshot_verdicts(registry, ["a", "b"], snapshot)  # the run grows by `b` (--extend)
    assert grown["sha256"] == [first, second]
    gates = snapshot_gates(json.loads(json.dumps(grown)))  # as stored: JSON
    assert (gates["a"].successes, gates["a"].feasible) == (2, True) and gates["b"].successes == 1
    assert snapshot_verdicts(registry, ["a", "b"], grown) == grown  # nothing to add: unchanged
