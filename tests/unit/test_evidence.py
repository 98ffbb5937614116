"""How a task is shown doable or impossible: the oracle's episodes, a searched demonstration, a proof, or nothing."""

from __future__ import annotations

import dataclasses
import json

import pytest

from langgap.catalog.catalog import load_catalog, registry_path
from langgap.catalog.verdicts import GateResult, record_verdicts
from langgap.cli.main import main

DRAWER = "spatial/s2/open-cabinet-bottom-drawer"
MADE_BY = "oracle, langgap 0.1.0+abc, exact stepping"
ORACLE = GateResult(50, 50, True, inits=50, failed_inits=[], made_by=MADE_BY)
UNPROVEN = GateResult(50, 17, False, reason="oracle 17/50", inits=50, made_by=MADE_BY)
PROVEN = GateResult(50, 0, False, reason="oracle 0/50", inits=50, proof="Out of reach, on init state 0: …")
SEARCHED = GateResult(
    50,
    46,
    True,
    inits=50,
    made_by=MADE_BY,
    demonstration="demonstrations/langgap99/spatial/s2/x",
    demonstrated_inits=(3, 7),
)


def test_each_verdict_says_what_shows_it():
    assert ORACLE.evidence == f"doable: oracle 50/50 init states (made by {MADE_BY})"
    assert UNPROVEN.evidence == "unproven: the oracle does not do it (17/50); no proof that a policy cannot"
    assert PROVEN.evidence == "infeasible: a proof that no policy can do it: Out of reach, on init state 0: …"
    assert SEARCHED.evidence == (
        f"doable: oracle 46/50 init states (made by {MADE_BY}); "
        "searched demonstration on init state(s) 3, 7: demonstrations/langgap99/spatial/s2/x"
    )
    # a demonstration shows nothing unless the verdict it belongs to is feasible
    assert dataclasses.replace(UNPROVEN, demonstration="demos/x.hdf5").evidence == UNPROVEN.evidence
    # rejected by another check than the oracle's rate: unproven, and not "the oracle does not do it (5/5)"
    rejected = GateResult(5, 5, False, reason="goal false at t0")
    assert rejected.evidence == (
        "unproven: the gate's checks fail (the oracle did it 5/5); no proof that a policy cannot; "
        "the gate's reason: goal false at t0"
    )
    for verdict in (ORACLE, UNPROVEN, SEARCHED, rejected):
        assert "infeasible" not in verdict.evidence and "impossib" not in verdict.evidence


def test_a_task_gives_its_evidence_and_its_feasibility_is_the_verdicts():
    task = load_catalog("langgap99").get(DRAWER)
    assert dataclasses.replace(task, gate=None).evidence == "not gated"
    for verdict in (ORACLE, UNPROVEN, PROVEN, SEARCHED):
        shown = dataclasses.replace(task, gate=verdict)
        assert shown.to_dict()["evidence"] == verdict.evidence
        assert shown.feasible is verdict.feasible  # a searched demonstration makes it feasible through the verdict
    assert SEARCHED.demonstrated and not ORACLE.demonstrated


def _registry(directory, verdicts: dict[str, GateResult]):
    """A copy of langgap99 in `directory` with `verdicts` recorded (catalogs are cached by path: one each)."""
    directory.mkdir()
    path = directory / "langgap99.yaml"
    path.write_text(registry_path("langgap99").read_text())
    record_verdicts(path, verdicts, {})
    return path


@pytest.mark.parametrize("verdict", [ORACLE, UNPROVEN, PROVEN, SEARCHED, None])
def test_tasks_show_prints_the_evidence(tmp_path, capsys, verdict):
    registry = _registry(tmp_path / "r", {} if verdict is None else {DRAWER: verdict})
    assert main(["tasks", "show", DRAWER, "--catalog", str(registry)]) == 0
    lines = [line for line in capsys.readouterr().out.splitlines() if line.startswith("evidence:")]
    expected = "not gated" if verdict is None else verdict.evidence
    assert lines == [f"evidence:    {expected}"]
    assert main(["tasks", "list", "--json", "--tasks", DRAWER, "--catalog", str(registry)]) == 0
    assert json.loads(capsys.readouterr().out)[0]["evidence"] == expected


def test_tasks_show_calls_a_rejected_task_unproven_unless_proven(tmp_path, capsys):
    main(["tasks", "show", DRAWER, "--catalog", str(_registry(tmp_path / "unproven", {DRAWER: UNPROVEN}))])
    out = capsys.readouterr().out
    assert "gate         oracle 17/50 on init states 0–49: unproven\n" in out
    assert "infeasible" not in out and "certif" not in out
    main(["tasks", "show", DRAWER, "--catalog", str(_registry(tmp_path / "proven", {DRAWER: PROVEN}))])
    assert "gate         oracle 0/50 on init states 0–49: infeasible\n" in capsys.readouterr().out
