"""Switch verdicts beside a registry (`<registry>.switch-gate.json`): merged per task and K, snapshotted by runs."""

from __future__ import annotations

import json

import pytest

from langgap.catalog.switch_verdicts import (
    accepted,
    read_switch_verdicts,
    record_switch_verdicts,
    snapshot_switch_gates,
    snapshot_switch_verdicts,
    switch_verdicts_path,
)
from langgap.catalog.verdicts import GateResult
from langgap.errors import CatalogError


def _verdict(successes: int) -> GateResult:
    return GateResult(episodes=2, successes=successes, feasible=successes == 2, inits=2)


def test_recording_merges_per_task_and_k_and_leaves_the_plain_verdicts_alone(tmp_path):
    registry = tmp_path / "c.yaml"
    plain = registry.with_name("c.gate.json")
    plain.write_text('{"about": {}, "tasks": {}}')
    record_switch_verdicts(registry, {"a": {"switch:20": _verdict(2)}}, {"inits": 2})
    record_switch_verdicts(registry, {"a": {"switch:60": _verdict(1)}, "b": {"switch:20": _verdict(0)}}, {})
    found = read_switch_verdicts(registry)
    assert {t: sorted(by_k) for t, by_k in found.items()} == {"a": ["switch:20", "switch:60"], "b": ["switch:20"]}
    assert accepted(found, "a", "switch:20") and not accepted(found, "a", "switch:60")
    assert not accepted(found, "b", "switch:20") and not accepted(found, "a", "switch:5")  # none: not accepted
    assert accepted(found, "a", "switch:20", [0, 1]) and not accepted(found, "a", "switch:20", [0, 2])  # inits 0-1
    record_switch_verdicts(registry, {"a": {"switch:60": _verdict(2)}}, {})  # re-recorded: replaced
    assert accepted(read_switch_verdicts(registry), "a", "switch:60")
    assert plain.read_text() == '{"about": {}, "tasks": {}}'
    assert switch_verdicts_path(registry).name == "c.switch-gate.json"


def test_a_run_s_snapshot_keeps_the_switch_verdicts_it_was_created_with(tmp_path):
    registry = tmp_path / "c.yaml"
    assert snapshot_switch_verdicts(registry, ["a"]) == {"file": "c.switch-gate.json", "sha256": [], "tasks": {}}
    record_switch_verdicts(registry, {"a": {"switch:20": _verdict(2)}}, {})
    snapshot = json.loads(json.dumps(snapshot_switch_verdicts(registry, ["a"])))  # as stored: JSON
    record_switch_verdicts(registry, {"a": {"switch:20": _verdict(0)}}, {})  # a re-gate
    assert accepted(snapshot_switch_gates(snapshot), "a", "switch:20")


@pytest.mark.parametrize("content", ["not json", '{"tasks": {"a": ["switch:20"]}}', '{"tasks": {"a": {"k": {}}}}'])
def test_a_malformed_switch_verdict_file_is_a_catalog_error(tmp_path, content):
    registry = tmp_path / "c.yaml"
    switch_verdicts_path(registry).write_text(content)
    with pytest.raises(CatalogError, match="cannot read switch verdicts"):
        read_switch_verdicts(registry)
