"""The report's rendering functions on synthetic stores: group rows are headings in every format (no Markdown
marks on a page), the outcome bars are named after their runs, the paper's counts show no gaps it never
reported, and its appendix says how many of each group's tasks each side counts."""

from __future__ import annotations

import dataclasses
import re

import pytest

from langgap.report import load_runs, summarize
from langgap.report.formats import latex_table, markdown_table
from langgap.report.html import _table, fitted, outcome_chart
from langgap.report.published import load_published
from langgap.report.sections import SECTIONS
from langgap.report.tables import published_appendix_table, published_diagnostic_table, source_table
from tests.support.reports import SOURCE, memoriser, reader, write_run

STOVE = "spatial/s0/black-bowl-1-on-stove"  # one of the paper's 13 change-target tasks
BOWL_2 = "spatial/s0/black-bowl-2-on-plate"  # the paper's one-task group "spatial task0 bowl 2"


@pytest.fixture
def summary(tmp_path):
    blind = write_run(tmp_path / "blind", "blind", memoriser(sees_state=True, sees_goal=True))
    vla = write_run(tmp_path / "my-long-vla-name", "my-vla", reader())
    return summarize(load_runs([blind, vla]))


def _title(**fields) -> str:
    return "a title"


def test_group_rows_are_headings_not_markdown_marks_on_the_page(summary):
    table = source_table(summary.runs[0], _title)
    page = _table(table, "t0")
    assert "*" not in page
    for heading in ("By data source", "By suite", "By perturbation dimension"):
        assert f'<tr class="heading"><th scope="rowgroup" colspan="9">{heading}</th></tr>' in page
        assert f"| *{heading}* |" in markdown_table(table)  # Markdown shows them in italics
        assert f"\n{heading} &  &" in latex_table(table)
    assert page.count("<tr") == len(table.rows) + 1  # a heading is one row, as in the table


def test_the_outcome_bars_are_named_after_their_runs(summary):
    chart = outcome_chart(summary)
    names = re.findall(r'<text class="run-name"[^>]*><title>[^<]*</title>([^<]*)</text>', chart)
    assert names == ["blind †", "my-long…"] * 3  # under each bar of the groups both runs have
    assert "<title>my-long-vla-name (my-vla)</title>" in chart
    assert ">1<" not in chart and ">2<" not in chart and "1: blind" not in chart


def test_a_name_too_long_for_its_bar_is_cut_with_an_ellipsis():
    assert fitted("oracle †", 60) == "oracle †"
    assert fitted("pi05-finetuned (openpi)", 60) == "pi05-fin…"
    assert fitted("anything", 1) == "…"


def test_the_papers_table_ii_shows_no_gaps_it_never_reported(summary):
    table = published_diagnostic_table(summary, load_published(), _title)
    column = table.headers.index("Gaps")
    assert {row[column] for row in table.rows} == {"–"}


def test_the_published_appendix_says_how_many_of_a_groups_tasks_each_side_counts(tmp_path):
    def renamed(records, task_id):
        return [dataclasses.replace(r, task_id=task_id) for r in records if r.task_id == SOURCE]

    run = write_run(tmp_path / "two-tasks", "my-vla", renamed(reader(range(3)), STOVE) + renamed(reader(), BOWL_2))
    section = SECTIONS["published-appendix"]
    table = published_appendix_table(summarize(load_runs([run])), load_published(), section.title)
    rows = {row[1]: row[2:] for row in table.rows}
    assert rows["all change-target tasks"] == ["0/260 (0.0%) on 13 tasks", "3/3 (100.0%) on 1 of the 13 tasks"]
    assert rows["spatial task0 bowl 2"] == ["1/20 (5.0%) on 1 task", "4/4 (100.0%) on the same 1 task"]
    assert rows["open the top drawer"] == ["6/20 (30.0%) on 1 task", "–"]
    assert "beside your runs on the group's tasks they ran" in table.title
