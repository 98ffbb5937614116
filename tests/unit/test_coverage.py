"""What the gate has proven, counted per suite and dimension from the recorded verdicts."""

from __future__ import annotations

import dataclasses
import json

from langgap.catalog.catalog import load_catalog, registry_path
from langgap.catalog.coverage import gate_counts, on_other_stacks
from langgap.catalog.task import GateResult
from langgap.cli.main import main


def test_verdicts_are_counted_as_accepted_infeasible_by_proof_unproven_or_not_gated():
    tasks = load_catalog("langgap99").select("spatial/s0/*,object/s0/*")
    verdicts = [
        GateResult(5, 5, True),
        GateResult(5, 0, False, proof="out of reach: the target is 2.1 m from the shoulder"),
        GateResult(5, 3, False),
        None,
    ]
    tasks = [dataclasses.replace(t, gate=verdicts[i % 4]) for i, t in enumerate(tasks)]
    counts = gate_counts(tasks)
    total = counts[-1]
    assert (total.suite, total.dimension, total.tasks) == ("total", "all", len(tasks))
    assert total.gated == sum(t.gate is not None for t in tasks)
    assert total.accepted == sum(t.gate is not None and t.gate.feasible for t in tasks)
    assert total.infeasible == sum(t.gate == verdicts[1] for t in tasks) > 0  # by a proof only
    assert total.unproven == total.rejected - total.infeasible == sum(t.gate == verdicts[2] for t in tasks) > 0
    assert (total.successes, total.episodes) == (
        sum(t.gate.successes for t in tasks if t.gate),
        sum(t.gate.episodes for t in tasks if t.gate),
    )
    per_suite = [c for c in counts if c.suite != "total"]
    assert {c.suite for c in per_suite} == {"libero_spatial", "libero_object"}
    for field in ("tasks", "gated", "accepted", "infeasible", "unproven", "episodes"):
        assert sum(getattr(c, field) for c in per_suite) == getattr(total, field)
        by_dimension = [c for c in counts if c.suite == "total" and c.dimension != "all"]
        assert sum(getattr(c, field) for c in by_dimension) == getattr(total, field)


def test_tasks_gate_prints_the_recorded_verdicts(capsys):
    recorded = json.loads(registry_path("langgap99").with_suffix(".gate.json").read_text())["tasks"]
    accepted = sum(v["feasible"] for v in recorded.values())
    proven = sum(not v["feasible"] and bool(v.get("proof")) for v in recorded.values())
    episodes = sum(v["episodes"] for v in recorded.values())
    successes = sum(v["successes"] for v in recorded.values())
    assert main(["tasks", "gate", "--markdown"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0] == (
        "| suite | dimension | tasks | gated | accepted | rejected | infeasible (proof) | unproven | oracle |"
    )
    rejected = len(recorded) - accepted
    assert lines[-1].startswith("verdicts made on the installed physics stack: ") and lines[-2] == ""
    assert lines[-3] == (
        f"| total | all | 99 | {len(recorded)} | {accepted} | {rejected} | {proven} | {rejected - proven} "
        f"| {successes}/{episodes} |"
    )


def test_doctor_says_how_many_shipped_verdicts_were_made_on_another_stack():
    from langgap.doctor import CHECKS

    (check,) = [c for c in CHECKS if c.__name__ == "_verdict_stacks"]
    found = check()
    other, gated = on_other_stacks(list(load_catalog("langgap99")))
    assert found.ok and gated == 99  # information, never a failure
    assert f"langgap99 {other} of {gated}" in found.detail
