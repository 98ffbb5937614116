"""The feasibility gate: rows, checks, recorded verdicts, the CLI."""

from __future__ import annotations

import json

import pytest

from langgap.bddl import Predicate
from langgap.catalog.catalog import load_catalog_file
from langgap.engine.spec import ExecutionOptions
from langgap.gate.rows import goals_exclude
from langgap.gate.validation import validate
from langgap.goals import conjunction
from langgap.stack import physics_stack
from langgap.version import code_version
from tests.support.catalogs import cut_down_catalog
from tests.support.harness import run_cli

IN_PROCESS = ExecutionOptions(workers=0, progress=False)
RAMEKIN = "spatial/s0/ramekin-on-plate"
PROBE_TASKS = ("spatial/s0/black-bowl-1-on-plate", RAMEKIN)
# a copy of the ramekin's task whose goal holds at t0
PLATE_ON_ITS_SPOT = {"id": "spatial/s0/plate-on-plate-spot", "goal": ["(On plate_1 main_table_plate_region)"]}


@pytest.fixture(scope="module")
def probe_registry(tmp_path_factory):
    """spatial/s0 with its original, one extended task, and a task whose goal holds at t0 (the plate on its own
    spot); 12-step limit, so the gate runs in seconds."""
    already = PLATE_ON_ITS_SPOT | {"dimension": "change_object"}
    return cut_down_catalog(
        tmp_path_factory.mktemp("gate") / "probe.yaml", PROBE_TASKS, steps=12, copies=[(RAMEKIN, already)]
    )


def test_gate_with_the_oracle_passes_doable_tasks_and_rejects_a_goal_true_at_t0(tmp_path):
    path = cut_down_catalog(tmp_path / "probe.yaml", PROBE_TASKS, copies=[(RAMEKIN, PLATE_ON_ITS_SPOT)])
    selection = "spatial/s0/ramekin-on-plate,spatial/s0/plate-on-plate-spot"
    rows = {r.id: r for r in validate(str(path), selection, inits=2, options=IN_PROCESS).rows}
    doable = rows["spatial/s0/ramekin-on-plate"]
    assert doable.feasible and doable.successes == 2 and doable.rate == 1.0, doable.reason
    # Where the goals exclude each other, the source task's goal must be false after the oracle's success.
    assert doable.checks["source goal false at end"]
    rejected = rows["spatial/s0/plate-on-plate-spot"]
    assert not rejected.feasible and not rejected.checks["goal false at t0"]


def test_gate_rows_and_checks(probe_registry):
    found = validate(str(probe_registry), "all", inits=2, options=IN_PROCESS, policy="noop", blind=True)
    rows = {r.id: r for r in found.rows}
    assert set(rows) == {
        "spatial/s0/black-bowl-1-on-plate",
        "spatial/s0/ramekin-on-plate",
        "spatial/s0/plate-on-plate-spot",
    }
    for row in rows.values():
        assert row.episodes == 2 and row.gaps == 0 and not row.feasible and row.checks["env builds"]
        assert row.checks["scene settles"] and row.settle_drift_mm < 2
    assert rows["spatial/s0/ramekin-on-plate"].reason == "oracle 0/2"
    at_t0 = rows["spatial/s0/plate-on-plate-spot"]
    assert at_t0.goal_true_at_t0 == 2 and not at_t0.checks["goal false at t0"] and "goal false at t0" in at_t0.reason
    ramekin = rows["spatial/s0/ramekin-on-plate"]  # the noop policy fails it on both init states
    assert ramekin.failed_inits == [0, 1] and ramekin.verdict(2).failed_inits == (0, 1) and not at_t0.failed_inits
    # The claims on the real episodes: one scene, identical t0 states; the plate's goal holds at t0 in
    # every episode of the scene (it is a scene goal), so that claim fails — a release blocker.
    same_state, nothing_at_t0, originals, never = found.claims
    assert same_state.holds and same_state.checked == 2
    assert not nothing_at_t0.holds and nothing_at_t0.checked == 6 and not found.passed
    assert originals.holds and originals.checked == 2
    # blind "does" the plate task at once (its goal already holds): the claim names both episodes.
    assert never.checked == 4 and never.violations == [f"spatial/s0/plate-on-plate-spot init {k}" for k in (0, 1)]


def test_goals_exclude():
    def on(text: str):
        return conjunction([Predicate.parse(text)])

    assert goals_exclude(on("(On a plate)"), on("(On a stove)"))
    assert not goals_exclude(on("(On a plate)"), on("(On b plate)"))
    assert not goals_exclude(on("(Open drawer)"), on("(On a plate)"))


def test_cli_validate_writes_report_and_records_verdicts(probe_registry, tmp_path):
    out = tmp_path / "report.json"
    result = run_cli(
        "validate",
        "spatial/s0/ramekin-on-plate",
        "--catalog",
        str(probe_registry),
        "--inits",
        "1",
        "--policy",
        "noop",
        "--workers",
        "0",
        "--out",
        str(out),
        "--record",
        "--no-progress",
    )
    assert result.returncode == 1, result.stderr  # exit 1: a task is rejected
    # the provers read the task's simulator and find no proof: rejected, yet unproven (not infeasible)
    unproven = "unproven: the oracle does not do it (0/1); no proof that a policy cannot"
    assert f"spatial/s0/ramekin-on-plate: {unproven}" in result.stdout
    report = json.loads(out.read_text())
    rows = report["tasks"]
    assert [r["id"] for r in rows] == ["spatial/s0/ramekin-on-plate"]
    assert [c["holds"] for c in report["claims"]] == [True, False]  # the plate's goal holds at t0
    assert {"episodes", "successes", "rate", "mean_steps", "max_steps", "feasible", "reason"} <= set(rows[0])
    catalog = load_catalog_file(probe_registry)
    gate = catalog.get("spatial/s0/ramekin-on-plate").gate
    assert gate is not None and gate.made_by == f"noop, langgap {code_version()}, exact stepping"
    assert gate.physics == physics_stack() and gate.other_stack == []  # the stack it was made on, per verdict
    assert catalog.get("spatial/s0/black-bowl-1-on-plate").gate is None
    assert gate.proof == "" and not gate.feasible
    shown = run_cli("tasks", "show", "spatial/s0/ramekin-on-plate", "--catalog", str(probe_registry))
    assert f"made by: {gate.made_by}" in shown.stdout and "made on another physics stack" not in shown.stdout
    assert f"evidence:    {unproven}" in shown.stdout and "infeasible" not in shown.stdout


def test_claims_only_resets_every_task_without_a_policy(probe_registry, tmp_path):
    out = tmp_path / "claims.json"
    args = ("validate", "--catalog", str(probe_registry), "--inits", "2", "--claims-only", "--out", str(out))
    result = run_cli(*args)
    assert result.returncode == 1, result.stderr  # the plate's goal holds at t0
    same_state, nothing_at_t0 = json.loads(out.read_text())["claims"]
    assert same_state["holds"] and same_state["checked"] == 2  # one scene, two init states, three tasks each
    assert not nothing_at_t0["holds"] and nothing_at_t0["checked"] == 6
    assert nothing_at_t0["violations"][0].endswith("init 0: spatial/s0/plate-on-plate-spot")
    refused = run_cli(*args, "--record")
    assert refused.returncode == 2 and refused.stderr.startswith("error: --claims-only runs no policy")


@pytest.mark.parametrize("flags", [["--policy", "oracle"], ["--run", "r"], ["--resume"], ["--search-budget", "0"]])
def test_claims_only_refuses_the_flags_of_a_gate_that_runs_a_policy(probe_registry, flags):
    result = run_cli("validate", "--catalog", str(probe_registry), "--claims-only", *flags)
    assert result.returncode == 2 and result.stderr.strip().splitlines() == [
        "error: --claims-only runs no policy: it stores no episodes, records no verdicts and searches nothing "
        f"(drop {flags[0]})"
    ]


def test_claims_only_runs_its_probes_on_the_execution_flags(probe_registry):
    # Each task's start probe is a work item: a timeout far too short kills its worker, and the
    # fail-fast rule stops the command at the first failure.
    args = ("validate", "--catalog", str(probe_registry), "--inits", "1", "--claims-only", "--no-progress")
    result = run_cli(*args, "--workers", "1", "--timeout", "0.01", "--max-failure-streak", "1")
    assert result.returncode == 4 and result.stderr.strip().splitlines()[-1].startswith(
        "error: stopped after 1 start probes in a row failed with: start probe timed out after 0s"
    ), result.stderr


def test_resume_without_a_run_is_refused(probe_registry):
    result = run_cli("validate", "--catalog", str(probe_registry), "--resume")
    assert result.returncode == 2 and result.stderr.strip() == (
        "error: --resume needs --run (the directory of the validation to continue)"
    )


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (["--search-budget", "-1"], "error: --search-budget must be >= 0, got -1"),
        (["--search-budget", "3", "--policy", "noop"], "error: --search-budget varies the oracle's plan"),
    ],
)
def test_a_search_budget_that_cannot_take_effect_is_refused(probe_registry, flags, message):
    result = run_cli("validate", "spatial/s0/ramekin-on-plate", "--catalog", str(probe_registry), *flags)
    assert result.returncode == 2 and result.stderr.startswith(message), result.stderr
