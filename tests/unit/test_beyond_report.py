"""Reports of the dimensions beyond the paper's: Table VII's form, what the policy did instead, and
paraphrases paired against their original sentences (synthetic run stores, no simulator)."""

from __future__ import annotations

from langgap.report.load import load_runs
from langgap.report.sections import DIAGNOSIS, report_data, report_tables
from langgap.report.summary import summarize
from langgap.vocabulary import Outcome
from tests.support.reports import SOURCE, beyond_episode, episode, memoriser, write_run

ORDERED = "spatial/s0/first-open-drawer-then-bowl-on-plate"
NEGATED = "spatial/s0/bowl-on-plate~not-where"
PASSIVE = "spatial/s0/bowl-on-plate~passive"


def run_records() -> list:
    records = [episode(SOURCE, k, success=k != 3, reached={SOURCE: 5} if k != 3 else {}) for k in range(4)]
    # ordered: in order on inits 0-1, the source's sub-goal first on 2-3 (right goals, wrong order)
    records += [beyond_episode(ORDERED, "ordering", k, success=True, reached={SOURCE: 9}) for k in (0, 1)]
    records += [beyond_episode(ORDERED, "ordering", k, reached={SOURCE: 5}, wrong_order=True) for k in (2, 3)]
    # negated: the bowl on the plate anyway (the source task), every time
    records += [beyond_episode(NEGATED, "negation", k, reached={SOURCE: 7}) for k in range(4)]
    # paraphrased: fails where the original sentence succeeded on init 0, succeeds where it failed on init 3
    records += [beyond_episode(PASSIVE, "paraphrase", k, success=k != 0, reached={SOURCE: 5}) for k in range(4)]
    return records


def test_new_dimensions_get_table_vii_form_and_what_the_policy_did_instead(tmp_path):
    summary = summarize(load_runs([write_run(tmp_path / "vla", "vla", run_records())]))
    (run,) = summary.runs
    (table,) = report_tables(summary, None, ["beyond"])
    assert table.headers == ["Method", "Ordering", "Negation", "Paraphrase"]
    assert table.rows[0][1].startswith("50.0") and table.rows[0][2].startswith("0.0")
    (instead,) = report_tables(summary, None, ["outcomes"])
    assert "Wrong order %" in instead.headers
    rows = {row[0]: dict(zip(instead.headers, row, strict=True)) for row in instead.rows}
    assert rows["Ordering"]["Wrong order %"] == "50.0" and rows["Ordering"]["Success %"] == "50.0"
    assert rows["Negation"]["Did source task %"] == "100.0"
    assert {o.group: o.shares[Outcome.WRONG_ORDER] for o in run.outcomes}["ordering"] == 0.5
    assert table in report_tables(summary, None, DIAGNOSIS.sections)


def test_a_paraphrase_is_paired_with_its_original_sentence_on_the_same_episodes(tmp_path):
    summary = summarize(load_runs([write_run(tmp_path / "vla", "vla", run_records())]))
    (test,) = summary.runs[0].wording
    assert test.name == "original vs paraphrase ~passive" and test.pairs == 4
    assert (test.successes_a, test.successes_b, test.only_a, test.only_b) == (3, 3, 1, 1)
    (table,) = report_tables(summary, None, ["wording"])
    assert table.rows[0][-1] == "+0.0" and table.headers[-1] == "Difference (points)"
    assert report_data(summary)["wording"][0]["pairs"] == 4


def test_runs_of_the_paper_catalog_show_no_new_columns(tmp_path):
    summary = summarize(load_runs([write_run(tmp_path / "blind", "blind", memoriser())]))
    assert report_tables(summary, None, ["beyond", "wording"]) == []
    (instead,) = report_tables(summary, None, ["outcomes"])
    assert "Wrong order %" not in instead.headers
