"""One policy's runs on several catalogs side by side, on synthetic stores (real runs: tests/test_side_by_side.py)."""

from __future__ import annotations

import json

from langgap.report import load_runs, render, summarize
from tests.support.reports import memoriser, reader, write_run


def _run(tmp_path, name, policy, catalog, records):
    return write_run(tmp_path / name, policy, records, catalog=catalog)


def test_a_policys_runs_on_two_catalogs_get_one_row_with_a_column_group_per_catalog(tmp_path):
    runs = [
        _run(tmp_path, "vla-99", "my-vla", "langgap99", reader()),
        _run(tmp_path, "vla-pro", "my-vla", "libero-pro", memoriser()),
        _run(tmp_path, "vla-99-again", "my-vla", "langgap99", memoriser()),  # a second run on langgap99: a 2nd row
        _run(tmp_path, "other-pro", "other", "libero-pro", reader()),  # another policy, on one catalog only
    ]
    side = summarize(load_runs(runs)).side_by_side
    assert side.catalogs == ["langgap99", "libero-pro"]
    assert side.groups["libero-pro"] == ["original", "change_object", "change_target", "extended"]
    assert [{c: run.path.name for c, run in row.items()} for row in side.rows] == [
        {"langgap99": "vla-99", "libero-pro": "vla-pro"},
        {"langgap99": "vla-99-again"},
        {"libero-pro": "other-pro"},
    ]
    text = render(runs, "md", published=False)
    table = text.split("### Side by side")[1].split("###")[0]
    assert "| Policy | langgap99: Original | langgap99: Change Object |" in table
    assert "| my-vla (vla-99, vla-pro) | 100.0 [51.0, 100.0] |" in table  # reader: 4 of 4 originals
    assert "| other (other-pro) | – | – | – | – | 100.0 [51.0, 100.0] |" in table
    rows = json.loads(render(runs, "json"))["side_by_side"]
    pro = {r["id"]: r for r in rows if r["row"] == 0 and r["catalog"] == "libero-pro"}
    assert (pro["extended"]["successes"], pro["extended"]["episodes"], pro["extended"]["gaps"]) == (0, 7, 1)
    assert pro["extended"]["run"] == "vla-pro (my-vla)" and pro["extended"]["policy"] == "my-vla"


def test_runs_of_different_policies_on_different_catalogs_are_not_side_by_side(tmp_path):
    runs = [
        _run(tmp_path, "vla-99", "my-vla", "langgap99", reader()),
        _run(tmp_path, "other-pro", "other", "libero-pro", reader()),
    ]
    assert summarize(load_runs(runs)).side_by_side is None
    text = render(runs, "md", published=False)
    assert "Side by side" not in text and "Runs not compared" in text
    assert json.loads(render(runs, "json"))["side_by_side"] == []


def test_each_run_is_paired_with_the_blind_run_on_its_own_catalog(tmp_path):
    scripted = {"sees_state": True, "sees_goal": True}
    runs = [
        _run(tmp_path, "blind-99", "blind", "langgap99", reader(**scripted)),  # first, but another catalog
        _run(tmp_path, "blind-pro", "blind", "libero-pro", memoriser(**scripted)),
        _run(tmp_path, "vla-pro", "my-vla", "libero-pro", reader()),
    ]
    answers = {a["run"]: a for a in json.loads(render(runs, "json"))["answers"]}
    against = answers["vla-pro (my-vla)"]["against_blind"]
    assert (against["pairs"], against["successes_a"], against["successes_b"]) == (7, 0, 6)  # blind-pro's episodes
    assert answers["blind-99 (blind)"]["against_blind"] is None  # blind-pro is on another catalog
