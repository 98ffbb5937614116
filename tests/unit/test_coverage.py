"""What the gate has proven, counted per suite and dimension from the recorded verdicts."""

from __future__ import annotations

import dataclasses
import json

from langgap.catalog.catalog import load_catalog, registry_path
from langgap.catalog.verdicts import GateResult
from langgap.cli.main import main
from langgap.gate.coverage import gate_counts, on_other_stacks
from langgap.vocabulary import Verdict


def test_verdicts_are_counted_as_doable_unproven_infeasible_by_proof_unsettled_or_not_gated():
    tasks = load_catalog("langgap99").select("spatial/s0/*,object/s0/*")
    verdicts = [
        GateResult(5, 5, True),
        GateResult(5, 0, False, proof="out of reach: the target is 2.1 m from the shoulder"),
        GateResult(5, 3, False),
        GateResult(5, 5, False, reason="scene settles"),  # the oracle did it; its starts do not come to rest
        None,
    ]
    words = [Verdict.DOABLE, Verdict.INFEASIBLE, Verdict.UNPROVEN, Verdict.UNSETTLED]
    tasks = [dataclasses.replace(t, gate=verdicts[i % 5]) for i, t in enumerate(tasks)]
    counts = gate_counts(tasks)
    total = counts[-1]
    assert (total.suite, total.dimension, total.tasks) == ("total", "all", len(tasks))
    assert total.gated == sum(t.gate is not None for t in tasks)
    for verdict, word in zip(verdicts, words, strict=False):
        assert total.verdicts[word] == sum(t.gate == verdict for t in tasks) > 0
    assert sum(total.verdicts.values()) == total.gated
    assert (total.successes, total.episodes) == (
        sum(t.gate.successes for t in tasks if t.gate),
        sum(t.gate.episodes for t in tasks if t.gate),
    )
    per_suite = [c for c in counts if c.suite != "total"]
    assert {c.suite for c in per_suite} == {"libero_spatial", "libero_object"}
    by_dimension = [c for c in counts if c.suite == "total" and c.dimension != "all"]
    for part in (per_suite, by_dimension):
        for field in ("tasks", "gated", "episodes"):
            assert sum(getattr(c, field) for c in part) == getattr(total, field)
        for word in Verdict:
            assert sum(c.verdicts[word] for c in part) == total.verdicts[word]


def test_tasks_gate_prints_the_recorded_verdicts(capsys):
    recorded = json.loads(registry_path("langgap99").with_suffix(".gate.json").read_text())["tasks"]
    accepted = sum(v["feasible"] for v in recorded.values())
    episodes = sum(v["episodes"] for v in recorded.values())
    successes = sum(v["successes"] for v in recorded.values())
    assert accepted == len(recorded)  # every langgap99 task is doable
    assert main(["tasks", "gate", "--markdown"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0] == "| suite | dimension | tasks | gated | doable | unproven | infeasible | unsettled | oracle |"
    assert lines[-1].startswith("verdicts made on the installed physics stack: ") and lines[-2] == ""
    assert lines[-3] == f"| total | all | 99 | {len(recorded)} | {accepted} | 0 | 0 | 0 | {successes}/{episodes} |"


def test_doctor_says_how_many_shipped_verdicts_were_made_on_another_stack():
    from langgap.diagnostics.doctor import CHECKS

    (check,) = [c for c in CHECKS if c.__name__ == "_verdict_stacks"]
    found = check()
    other, gated = on_other_stacks(list(load_catalog("langgap99")))
    assert found.ok and gated == 99  # information, never a failure
    assert f"langgap99 {other} of {gated}" in found.detail
