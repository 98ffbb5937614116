"""`langgap report --split NAME[:K]`: a run's episodes grouped by a stored split — its training tasks (or its
nested subset of K), its held-out tasks, the rest — in every table and pool, instead of the tasks' own split."""

from __future__ import annotations

import dataclasses

from langgap.report import pooled_text, render
from langgap.report.load import split_groups
from tests.support.harness import run_cli
from tests.support.reports import SOURCE, episode, write_run

SPLIT = "full-spatial-s0-compositional"
FIRST = "spatial/s0/cookie-box-on-ramekin"  # the split's subset of 1 training task
HELD_OUT = "spatial/s0/cookie-box-on-cabinet-top"
ORIGINAL = "spatial/s0/black-bowl-1-on-plate"  # in the split's training pool, not in its subset of 1


def _records(successes: dict[str, int]) -> list:
    """Two episodes of each task, the first `successes[task]` of them successful."""
    return [
        dataclasses.replace(episode(SOURCE, k, success=k < wins), task_id=task)
        for task, wins in successes.items()
        for k in range(2)
    ]


def test_each_episode_takes_the_part_of_the_split_its_task_is_in():
    records = _records({FIRST: 1, HELD_OUT: 0, ORIGINAL: 2})
    whole = {r.task_id: r.split for r in split_groups(records, "full", SPLIT)}
    assert whole == {FIRST: f"trained ({SPLIT})", HELD_OUT: f"held out ({SPLIT})", ORIGINAL: f"trained ({SPLIT})"}
    first = {r.task_id: r.split for r in split_groups(records, "full", f"{SPLIT}:1")}
    assert first == {FIRST: f"trained ({SPLIT}:1)", HELD_OUT: f"held out ({SPLIT})", ORIGINAL: f"outside {SPLIT}"}
    assert [r.success for r in split_groups(records, "full", SPLIT)] == [r.success for r in records]


def test_the_pools_and_the_report_group_by_the_split_in_its_order(tmp_path):
    one = write_run(tmp_path / "one", "small-bc", _records({FIRST: 2, HELD_OUT: 0, ORIGINAL: 1}), catalog="full")
    two = write_run(tmp_path / "two", "small-bc", _records({FIRST: 1, HELD_OUT: 0, ORIGINAL: 0}), catalog="full")
    table = pooled_text({"k1": [one, two]}, split=f"{SPLIT}:1").splitlines()
    header = next(line for line in table if line.startswith("| Pool"))
    parts = [f"trained ({SPLIT}:1)", f"held out ({SPLIT})", f"outside {SPLIT}"]
    assert [header.index(p) for p in parts] == sorted(header.index(p) for p in parts)
    row = next(line for line in table if line.startswith("| k1"))
    assert "| 75.0 [30.1, 95.4]; 2, 1 of 2 |" in row and "| 0.0 [0.0, 49.0]; 0, 0 of 2 |" in row
    assert "Extended, training split" not in header  # the tasks' own split is not shown beside it
    report = render([one], split=SPLIT)
    assert f"| trained ({SPLIT}) |" in report and f"| held out ({SPLIT}) |" in report


def test_a_split_of_another_catalog_is_one_error_line(tmp_path):
    run = write_run(tmp_path / "run", "small-bc", _records({FIRST: 1}), catalog="full")
    result = run_cli("report", str(run), "--split", "langgap99-instruction")
    assert result.returncode != 0
    assert result.stderr.strip() == "error: split langgap99-instruction is of catalog langgap99; this run is of full"
