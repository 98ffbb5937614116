"""`validate --record` keeps a proof of impossibility for a task the oracle fails; only a proof makes it infeasible."""

from __future__ import annotations

import dataclasses

import pytest

from langgap.catalog.catalog import registry_path
from langgap.catalog.verdicts import read_verdicts
from langgap.gate import proofs
from langgap.gate.recording import record
from langgap.gate.rows import TaskValidation
from langgap.stack import physics_stack

DRAWER = "spatial/s2/open-cabinet-bottom-drawer"
BOWL = "spatial/s2/black-bowl-1-on-plate"
PROOF = proofs.Proof("Out of reach, on init state 0: …", ("the base does not move",), {"reach, m": 0.855})


def _row(task_id: str, successes: int, episodes: int = 5) -> TaskValidation:
    rate = successes / episodes
    return TaskValidation(
        id=task_id,
        suite="libero_spatial",
        dimension="spatial_description",
        episodes=episodes,
        successes=successes,
        rate=rate,
        mean_steps=0.0,
        max_steps=0,
        gaps=0,
        goal_true_at_t0=0,
        source_true_at_end=0,
        settle_drift_mm=0.0,
        feasible=rate >= 0.9,
        reason="" if rate >= 0.9 else f"oracle {successes}/{episodes}",
        failed_inits=list(range(successes, episodes)),
    )


@pytest.fixture
def registry(tmp_path):
    path = tmp_path / "langgap99.yaml"
    path.write_text(registry_path("langgap99").read_text())
    return path


def _prover(monkeypatch, proven: set[str]) -> list[list[str]]:
    asked: list[list[str]] = []

    def prove_tasks(tasks, inits):
        asked.append([t.id for t in tasks])
        return {t.id: PROOF for t in tasks if t.id in proven}

    monkeypatch.setattr(proofs, "prove_tasks", prove_tasks)
    return asked


def test_a_proof_is_recorded_for_a_task_the_oracle_fails(registry, monkeypatch):
    asked = _prover(monkeypatch, {DRAWER})
    record(str(registry), [_row(DRAWER, 0), _row(BOWL, 5)], inits=5)
    assert asked == [[DRAWER]]  # the provers run only where the oracle is below the gate's rate
    verdicts = read_verdicts(registry)
    assert verdicts[DRAWER].proof == PROOF.text() and not verdicts[DRAWER].feasible
    assert verdicts[DRAWER].capped_because(0, 5) == "infeasible: a proof that no policy can do it"
    assert verdicts[BOWL].proof == "" and verdicts[BOWL].feasible


def test_without_a_proof_a_failed_task_is_unproven(registry, monkeypatch):
    _prover(monkeypatch, set())
    record(str(registry), [_row(DRAWER, 0)], inits=5)
    verdict = read_verdicts(registry)[DRAWER]
    assert verdict.proof == "" and verdict.evidence.startswith("unproven: the oracle does not do it (0/5)")
    assert "infeasible" not in verdict.evidence


def test_a_proof_the_episodes_refute_is_not_recorded(registry, monkeypatch):
    _prover(monkeypatch, {DRAWER})
    with pytest.warns(UserWarning, match="yet the gate did it 2 time"):
        record(str(registry), [_row(DRAWER, 2)], inits=5)
    assert read_verdicts(registry)[DRAWER].proof == ""


def test_each_recorded_verdict_keeps_the_stack_it_was_made_on(registry):
    record(str(registry), [_row(DRAWER, 0), _row(BOWL, 5)], inits=5, proofs={})
    record(str(registry), [_row(BOWL, 5)], inits=5, stepping="fast", proofs={})  # re-validated: only its verdict
    verdicts = read_verdicts(registry)
    assert verdicts[DRAWER].physics == physics_stack() and verdicts[BOWL].physics == physics_stack("fast")
    # The stepping is chosen per gate, not installed: both were made on the installed stack.
    assert verdicts[DRAWER].other_stack == verdicts[BOWL].other_stack == []
    older = dataclasses.replace(verdicts[DRAWER], physics=physics_stack() | {"robosuite": "1.4.0"})
    assert older.other_stack == ["robosuite 1.4.0 (not 1.4.1)"]
