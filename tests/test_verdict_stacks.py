"""Every gate verdict keeps the physics stack it was made on, and where verdicts are read it is said when that
is not the installed stack (`tasks gate`, `tasks show`) or not the stack of a run's episodes (`report`)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import yaml

from langgap.stack import physics_stack
from tests.support.harness import run_cli

OLD = "spatial/s0/black-bowl-2-on-plate"  # its verdict made on robosuite 1.4.0 before the fresh-env start
UNRECORDED = "spatial/s0/open-cabinet-top-drawer"  # its verdict written before verdicts kept their stack
OLDER_STACK = physics_stack() | {"robosuite": "1.4.0", "start": "cleared-warmstart"}


def _gated_copy(short_catalog: str, tmp_path: Path) -> Path:
    """A copy of the short catalog, every task accepted: one verdict on the installed stack, one on an older one,
    one with no stack recorded."""
    catalog = tmp_path / "catalog" / "short.yaml"
    catalog.parent.mkdir()
    shutil.copyfile(short_catalog, catalog)
    verdicts = {}
    for task in (t["id"] for t in yaml.safe_load(catalog.read_text())["tasks"]):
        verdicts[task] = {"episodes": 1, "successes": 1, "feasible": True, "inits": 1, "failed_inits": []}
        if task != UNRECORDED:
            verdicts[task]["physics"] = OLDER_STACK if task == OLD else physics_stack()
    catalog.with_name("short.gate.json").write_text(json.dumps({"about": {}, "tasks": verdicts}))
    return catalog


def test_tasks_gate_and_show_say_which_verdicts_were_made_on_another_stack(short_catalog, tmp_path):
    catalog = _gated_copy(short_catalog, tmp_path)
    for flags in ((), ("--markdown",)):
        result = run_cli("tasks", "gate", "--catalog", str(catalog), *flags)
        assert result.returncode == 0, result.stderr
        assert result.stdout.strip().splitlines()[-1] == (
            "verdicts made on the installed physics stack: 1 of 3; on another: 2 (robosuite 1.4.0 (not 1.4.1): 1; "
            "stack not recorded: 1; start cleared-warmstart (not fresh-env): 1; re-gate: langgap validate --record)"
        )
    shown = {}
    for task in (OLD, UNRECORDED, "spatial/s0/black-bowl-1-on-plate"):
        result = run_cli("tasks", "show", task, "--catalog", str(catalog))
        assert result.returncode == 0, result.stderr
        shown[task] = [line for line in result.stdout.splitlines() if "physics stack" in line]
    assert shown == {
        OLD: [
            "gate         made on another physics stack than the installed one: robosuite 1.4.0 (not 1.4.1), "
            "start cleared-warmstart (not fresh-env)"
        ],
        UNRECORDED: ["gate         made on another physics stack than the installed one: stack not recorded"],
        "spatial/s0/black-bowl-1-on-plate": [],
    }


def test_report_marks_a_ceiling_made_on_another_stack_than_the_runs_episodes(short_catalog, tmp_path):
    catalog = _gated_copy(short_catalog, tmp_path)
    run = tmp_path / "run"
    result = run_cli("eval", "--policy", "noop", "--catalog", str(catalog), "--episodes", "1", "--run", str(run),
                     "--no-progress", "--quiet")  # fmt: skip
    assert result.returncode == 0, result.stderr
    catalog.with_name("short.gate.json").unlink()  # the report reads the verdicts stored with the run
    report = run_cli("report", str(run), "--no-published", "--format", "md")
    assert report.returncode == 0, report.stderr
    cells = {cell.strip() for line in report.stdout.splitlines() for cell in line.split("|")}
    assert {cell for cell in cells if "≠" in cell and " marks " not in cell} == {f"{OLD} ≠", f"{UNRECORDED} ≠"}
    assert "≠ marks a task whose feasibility verdict (its Oracle % and ⚠) was made on another physics stack" in (
        report.stdout
    )
    stored = json.loads(run_cli("report", str(run), "--no-published", "--format", "json").stdout)
    assert sorted(stored["runs"][0]["other_stack_tasks"]) == [OLD, UNRECORDED]
