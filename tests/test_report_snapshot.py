"""A run keeps the gate verdicts it relies on: a re-gate changes neither its report nor its resumed plan."""

from __future__ import annotations

import json
import shutil
import sqlite3
from pathlib import Path

import yaml

from langgap.store import RunStore
from tests.support.harness import run_cli

REGATED = "spatial/s0/black-bowl-2-on-plate"  # the task the re-gate rejects


def _gate(catalog: Path, rejected: tuple[str, ...] = ()) -> None:
    """Record the gate's verdicts beside `catalog`: the oracle did every task at init 0, but `rejected`."""
    tasks = [t["id"] for t in yaml.safe_load(catalog.read_text())["tasks"]]
    verdicts = {
        t: {"episodes": 1, "successes": int(t not in rejected), "feasible": t not in rejected, "inits": 1,
            "failed_inits": [0] if t in rejected else []}
        for t in tasks
    }  # fmt: skip
    catalog.with_name(catalog.stem + ".gate.json").write_text(json.dumps({"about": {}, "tasks": verdicts}))


def _created(short_catalog: str, tmp_path: Path) -> tuple[Path, Path]:
    """A copy of the short catalog with every task accepted, and a one-init-state run of it (default selection)."""
    catalog = tmp_path / "catalog" / "short.yaml"
    catalog.parent.mkdir()
    shutil.copyfile(short_catalog, catalog)
    _gate(catalog)
    run = tmp_path / "run"
    result = run_cli("eval", "--policy", "noop", "--catalog", str(catalog), "--episodes", "1", "--run", str(run),
                     "--no-progress", "--quiet")  # fmt: skip
    assert result.returncode == 0, result.stderr
    return catalog, run


def _report(run: Path) -> str:
    result = run_cli("report", str(run), "--no-published")
    assert result.returncode == 0, result.stderr
    return result.stdout


def test_a_regate_does_not_change_a_stored_runs_report(short_catalog, tmp_path):
    catalog, run = _created(short_catalog, tmp_path)
    before = _report(run)
    assert f"{REGATED} ⚠" not in before and "gate: snapshot taken when the run was created (sha256 " in before
    _gate(catalog, rejected=(REGATED,))  # `validate --record` rewrites the verdict file
    assert _report(run) == before
    # A run stored before snapshots were kept reads the live verdicts, and says so.
    db = sqlite3.connect(run / "episodes.sqlite")
    with db:
        db.execute("DELETE FROM meta WHERE key = 'gate'")
    db.close()
    old = _report(run)
    assert "the catalog's live verdict file (this run was stored before runs kept a snapshot" in old
    assert f"{REGATED} ⚠" in old


def test_a_resume_after_a_regate_keeps_the_tasks_the_run_was_created_with(short_catalog, tmp_path):
    catalog, run = _created(short_catalog, tmp_path)
    with RunStore.open(run) as store:
        tasks, gate = store.meta("spec")["tasks"], store.meta("gate")
    assert REGATED in tasks and len(tasks) == 3 and sorted(gate["tasks"]) == sorted(tasks)
    _gate(catalog, rejected=(REGATED,))  # `feasible` now resolves to two tasks
    result = run_cli("eval", "--policy", "noop", "--catalog", str(catalog), "--episodes", "1", "--run", str(run),
                     "--resume", "--no-progress", "--quiet")  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "3 planned, 3 already stored, 0 run" in result.stdout
    with RunStore.open(run) as store:
        assert store.meta("spec")["tasks"] == tasks and store.meta("gate") == gate


def test_a_run_grown_by_extend_adds_only_its_new_tasks_verdicts(short_catalog, tmp_path):
    catalog = tmp_path / "catalog" / "short.yaml"
    catalog.parent.mkdir()
    shutil.copyfile(short_catalog, catalog)
    _gate(catalog, rejected=(REGATED,))
    run = tmp_path / "run"
    base = ["eval", "--policy", "noop", "--catalog", str(catalog), "--episodes", "1", "--run", str(run), "--quiet"]
    assert run_cli(*base, "--tasks", REGATED, "--no-progress").returncode == 0
    _gate(catalog)  # re-gated: the stove task accepted now
    grown = run_cli(*base, "--tasks", "all", "--resume", "--extend", "--no-progress")
    assert grown.returncode == 0, grown.stderr
    with RunStore.open(run) as store:
        gate = store.meta("gate")
    assert len(gate["sha256"]) == 2 and len(gate["tasks"]) == 3
    assert gate["tasks"][REGATED]["feasible"] is False  # as it was when the task joined the run
    assert f"{REGATED} ⚠" in _report(run)
