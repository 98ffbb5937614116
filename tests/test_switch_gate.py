"""The switch feasibility gate: per task and K, the oracle must follow a `switch:K` on 95 % of the init states
(else the task is unproven at that K), recorded beside the registry, counted, and marked in reports."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from langgap.catalog.switch_verdicts import read_switch_verdicts, switch_verdicts_path
from tests.support.catalogs import cut_down_catalog
from tests.support.harness import run_cli

EXTENDED = "spatial/s0/black-bowl-2-on-plate"  # starts under its source's "black bowl 1 on the plate"


@pytest.fixture(scope="module")
def two_task_catalog(tmp_path_factory) -> Path:
    """The extended task and its source, at the full step limit (220): the oracle does the task after a switch
    at step 5, not after one at step 200 (it has put bowl 1 on the plate by then; 20 steps are too few)."""
    return cut_down_catalog(
        tmp_path_factory.mktemp("catalog") / "two.yaml", {EXTENDED, "spatial/s0/black-bowl-1-on-plate"}
    )


def _copy(catalog: Path, tmp_path: Path) -> Path:
    """A copy of the catalog of the test's own (verdict files go beside the registry)."""
    copy = tmp_path / "catalog" / catalog.name
    copy.parent.mkdir()
    shutil.copyfile(catalog, copy)
    return copy


def _switch_table(report: str) -> list[str]:
    lines = report.splitlines()
    start = next(i for i, line in enumerate(lines) if "Instruction switched at step K" in line)
    return lines[start : start + 8]


def test_the_switch_gate_records_counts_and_marks_verdicts_per_task_and_k(two_task_catalog, tmp_path):
    registry = _copy(two_task_catalog, tmp_path)
    catalog = str(registry)
    gate = ("validate", EXTENDED, "--catalog", catalog, "--inits", "1", "--workers", "0", "--no-progress")
    result = run_cli(*gate, "--condition", "switch:5", "--condition", "switch:200", "--record")
    assert result.returncode == 1, result.stderr  # a task unproven at one K: the gate does not pass
    assert "switch gate: 1 doable, 1 unproven" in result.stdout
    verdicts = read_switch_verdicts(registry)
    assert set(verdicts) == {EXTENDED} and set(verdicts[EXTENDED]) == {"switch:5", "switch:200"}
    assert verdicts[EXTENDED]["switch:5"].feasible and verdicts[EXTENDED]["switch:5"].successes == 1
    late = verdicts[EXTENDED]["switch:200"]
    assert not late.feasible and late.failed_inits == (0,) and not late.proof  # unproven, never infeasible
    assert late.reason == "oracle 0/1 under switch:200"
    from langgap.stack import physics_stack

    assert late.physics == physics_stack("exact")  # each verdict records the stack it was made on
    assert not registry.with_name("two.gate.json").exists()  # apart from the plain verdicts
    shown = run_cli("tasks", "show", "--catalog", catalog, EXTENDED)
    assert "switch gate  switch:5: oracle 1/1 on init states 0–0: doable\n" in shown.stdout
    assert "switch gate  switch:200: oracle 0/1 on init states 0–0: unproven\n" in shown.stdout
    shown_json = json.loads(run_cli("tasks", "show", "--catalog", catalog, EXTENDED, "--json").stdout)
    assert shown_json["switch_gate"]["switch:200"]["feasible"] is False

    counted = run_cli("tasks", "gate", "--catalog", catalog, "--condition", "switch:5", "--condition", "switch:200")
    assert counted.returncode == 0, counted.stderr
    at_5, at_200 = counted.stdout.split("\nswitch:200:\n")
    # total row: tasks, gated, doable, unproven, infeasible, unsettled
    assert at_5.splitlines()[-2].split()[2:8] == ["2", "1", "1", "0", "0", "0"]
    assert at_200.splitlines()[-2].split()[2:8] == ["2", "1", "0", "1", "0", "0"]
    assert "1 of 2 task(s) not gated at switch:5" in at_5

    # A run of the task under both K: its report marks K=200 (not gated there) and not K=5.
    run = tmp_path / "run"
    evaluated = run_cli(
        *("eval", "--policy", "noop", "--catalog", catalog, "--tasks", EXTENDED, "--episodes", "1"),
        *("--condition", "switch:5", "--condition", "switch:200", "--run", str(run), "--workers", "0", "--quiet"),
    )
    assert evaluated.returncode == 0, evaluated.stderr
    report = run_cli("report", str(run), "--no-published")
    assert report.returncode == 0, report.stderr
    table = _switch_table(report.stdout)
    assert f"has not accepted {EXTENDED} at K=200" in table[0] and "at K=5" not in table[0]
    rows_5 = [line for line in table if line.lstrip("| ").startswith("5 ")]
    rows_200 = [line for line in table if line.lstrip("| ").startswith("200 ")]
    assert rows_5 and rows_200 and all("1 of 1" in r for r in rows_200) and not any("of 1" in r for r in rows_5)
    # The report reads the verdicts the run stored when it was created, not the live file.
    switch_verdicts_path(registry).unlink()
    assert run_cli("report", str(run), "--no-published").stdout == report.stdout


def test_the_switch_gate_takes_switch_conditions_only_and_no_plain_gate_flags(two_task_catalog, tmp_path):
    registry = _copy(two_task_catalog, tmp_path)
    base = ("validate", EXTENDED, "--catalog", str(registry), "--inits", "1", "--workers", "0")
    for extra, message in [
        (("--condition", "given"), "--condition takes switch:K only"),
        (("--condition", "switch:5", "--blind"), "--condition runs the switch gate, which has no --blind"),
        (("--condition", "switch:5", "--search-budget", "3"), "which has no --search-budget"),
    ]:
        result = run_cli(*base, *extra)
        assert result.returncode != 0 and result.stderr.strip().splitlines()[-1].startswith("error: ")
        assert message in result.stderr
    assert not switch_verdicts_path(registry).exists() and list(registry.parent.iterdir()) == [registry]


def test_a_switch_gate_file_that_is_not_one_is_one_error_line(two_task_catalog, tmp_path):
    catalog = _copy(two_task_catalog, tmp_path)
    switch_verdicts_path(catalog).write_text(json.dumps({"tasks": {EXTENDED: ["switch:5"]}}))
    result = run_cli("tasks", "gate", "--catalog", str(catalog), "--condition", "switch:5")
    assert result.returncode != 0
    assert result.stderr.strip().splitlines()[-1].startswith(f"error: cannot read switch verdicts {catalog.parent}")
