"""The report's sections, each registered once, in order, under its name: its heading, the tables the table
formats show of it and the data the JSON report holds of it. Every format picks the sections it shows by name:
the full report and the diagnosis (`--summary`) are two lists of names (`FULL_REPORT`, `DIAGNOSIS`), the JSON
report a third (`JSON_REPORT`), the CSV a fourth (`CSV_REPORT`).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from langgap.report.data import Spec, to_data
from langgap.report.published import Published
from langgap.report.stats import Rate
from langgap.report.summary import RunResults, SideBySide, Summary
from langgap.report.tables import (
    OUTCOME_NAME,
    Table,
    Title,
    beyond_table,
    comparison_table,
    condition_table,
    confusion_tables,
    dimension_table,
    mde_table,
    mismatch_table,
    outcome_table,
    protocol_table,
    published_appendix_table,
    published_diagnostic_table,
    side_by_side_table,
    source_table,
    split_table,
    spread_table,
    suite_table,
    switch_table,
    task_table,
    video_table,
    wording_table,
)
from langgap.vocabulary import Outcome, TaskKind

Tables = Table | list[Table] | None  # None: the section does not apply to these runs
Rows = Callable[[RunResults], Iterable]


@dataclass(frozen=True)
class Section:
    """One named part of the report. Its tables are made from the whole summary (`tables`) or from one run
    (`run_tables`, shown run by run); its data (`data`) is the JSON report's entries for it. A section without
    tables is in the JSON report only; one without data has its numbers in another section's."""

    name: str
    heading: str = ""  # its tables' title: `{run}` the run's label, other fields as its tables fill them
    paper: str = ""  # the paper's table it reproduces, named after the heading
    tables: Callable[[Summary, Published | None, Title], Tables] | None = None
    run_tables: Callable[[RunResults, Title], Tables] | None = None
    data: Callable[[Summary], dict] | None = None

    def title(self, **fields: str) -> str:
        """The heading with its fields filled, then which of the paper's tables it reproduces, if one."""
        heading = self.heading.format(**fields)
        return f"{heading} (the paper's {self.paper})" if self.paper else heading


def rate_row(rate: Rate, **first) -> dict:
    """A rate's JSON row: `first`'s entries, the rate's group as `id`, then the rate's data."""
    data = to_data(rate)
    return {**first, "id": data.pop("group"), **data}


def _getter(source: str | Rows) -> Rows:
    return (lambda run: getattr(run, source)) if isinstance(source, str) else source


def run_rates(**sources: str | Rows) -> Callable[[Summary], dict]:
    """Section data: under each key, every run's rates from its `RunResults` attribute or function (`rate_row`)."""
    return lambda summary: {
        key: [rate_row(r, run=run.name) for run in summary.runs for r in _getter(source)(run)]
        for key, source in sources.items()
    }


def run_rows(**sources: str | Rows) -> Callable[[Summary], dict]:
    """Section data: under each key, every run's rows from its `RunResults` attribute or function, each led by the
    run's name."""
    return lambda summary: {
        key: [{"run": run.name, **to_data(row)} for run in summary.runs for row in _getter(source)(run)]
        for key, source in sources.items()
    }


def side_by_side_rows(side: SideBySide | None) -> list[dict]:
    """One row per (row, catalog, group) the runs have: the JSON report's `side_by_side` section."""
    if side is None:
        return []
    return [
        rate_row(rate, row=number, policy=run.card["policy"], catalog=catalog, run=run.name)
        for number, row in enumerate(side.rows)
        for catalog, run in row.items()
        for group in side.groups[catalog]
        if (rate := side.rate(run, group)) is not None
    ]


# A run in the JSON report: where it is, its size, its spec and protocol card, and what its ceilings rest on.
RUN_DATA: Spec = (
    ("run", "name"),
    "path",
    "episodes",
    "gaps",
    "privilege",
    "spec",
    "card",
    ("capped_tasks", "capped"),
    ("other_stack_tasks", "other_stack"),
    ("gate", "gate_source"),
)

SECTIONS: dict[str, Section] = {
    section.name: section
    for section in (
        Section("answers", data=run_rows(answers=lambda run: [run.answer])),
        Section(
            "card",
            "Protocol card",
            tables=protocol_table,
            data=lambda summary: {"runs": [to_data(run, RUN_DATA) for run in summary.runs]},
        ),
        Section(
            "side-by-side",
            "Side by side — one policy on several catalogs (success %, 95% CI; columns: catalog: tasks)",
            tables=side_by_side_table,
            data=lambda summary: {"side_by_side": side_by_side_rows(summary.side_by_side)},
        ),
        Section(
            "sources",
            "Success by data source, suite and dimension — {run}",
            "Table II",
            run_tables=source_table,
            data=run_rates(by_source="by_source", per_dimension="by_dimension", per_suite="by_suite"),
        ),
        Section(
            "outcomes",
            f"What the policy did instead — {{run}} ({OUTCOME_NAME[Outcome.DID_SOURCE_TASK]} = default-task rate)",
            run_tables=outcome_table,
            data=run_rows(outcomes="outcomes"),
        ),
        Section("videos", "Filmed episodes — {run}", run_tables=video_table, data=run_rows(videos="clips")),
        Section(
            "splits",
            "Success on training vs held-out tasks — {run}",
            run_tables=split_table,
            data=run_rates(per_split="by_split"),
        ),
        Section(
            "mde",
            "Minimum detectable effect — {run} (80 % power, α = 0.05, against a run of the same size)",
            run_tables=mde_table,
        ),
        Section(
            "spread",
            "Between-seed spread — {run} (same init states, other seeds)",
            run_tables=spread_table,
            data=run_rows(spread="spread"),
        ),
        Section(
            "conditions",
            "Language conditions, paired episode by episode (McNemar) — {run}",
            run_tables=condition_table,
            data=run_rows(conditions="conditions"),
        ),
        Section(
            "switches",
            f"Instruction switched at step K — {{run}} ({Outcome.PERSISTED}: after the switch it did what the first "
            "instruction asked; other: another scene task)",
            run_tables=switch_table,
            data=run_rows(switches="switches"),
        ),
        Section(
            "wording",
            "Same goal, other words, paired episode by episode (McNemar) — {run}",
            run_tables=wording_table,
            data=run_rows(wording="wording"),
        ),
        Section(
            "published-sources",
            "Success by data source and dimension — {method} as published",
            "Table II",
            tables=published_diagnostic_table,
        ),
        Section(
            "suites",
            f"Success per suite, {TaskKind.ORIGINAL} vs {TaskKind.EXTENDED} tasks — success %, 95% CI",
            "Table VI",
            tables=suite_table,
        ),
        Section(
            "dimensions",
            f"Success on {TaskKind.EXTENDED} tasks by dimension — success %, 95% CI, (tasks)",
            "Table VII",
            tables=dimension_table,
        ),
        Section(
            "beyond",
            f"Success on {TaskKind.EXTENDED} tasks by the dimensions beyond the paper's — success %, 95% CI, (tasks)",
            tables=beyond_table,
        ),
        Section(
            "comparisons",
            "Runs compared on matched episodes (McNemar)",
            tables=comparison_table,
            data=lambda summary: {"comparisons": to_data(summary.comparisons)},
        ),
        Section(
            "mismatches",
            "Runs not compared: their protocols differ from the first run's (--allow-mismatch pairs them anyway)",
            tables=mismatch_table,
            data=lambda summary: {"protocol_mismatches": summary.mismatches, "comparisons_refused": summary.refused},
        ),
        Section(
            "published-appendix",
            "Success per group of tasks — {method} as published, beside your runs on the group's tasks they ran",
            "appendix",
            tables=published_appendix_table,
        ),
        Section(
            "tasks",
            "Success per task — {run}",
            run_tables=task_table,
            data=run_rates(per_task=lambda run: [t.rate for t in run.tasks]),
        ),
        Section(
            "confusion",
            "Confusion (intended × achieved) — {run}, scene {scene}",
            run_tables=confusion_tables,
            data=lambda summary: {"confusion": {run.name: run.confusion for run in summary.runs}},
        ),
    )
}


@dataclass(frozen=True)
class Layout:
    """A report of tables: its sections by name, and whether it has the runs' header: each run's place, size and
    task selection opening the Markdown, and the notes on the task selection, the oracle's columns and ⚠ (which
    its tables show)."""

    sections: tuple[str, ...]
    header: bool


# Sections of one run's tables listed next to each other are shown run by run (`report_tables`).
FULL_REPORT = Layout(
    (
        "card",
        "side-by-side",
        *("sources", "outcomes", "videos", "splits", "mde", "spread", "conditions", "switches", "wording"),
        *("published-sources", "suites", "dimensions", "beyond", "comparisons", "mismatches", "published-appendix"),
        *("tasks", "confusion"),
    ),
    header=True,
)
DIAGNOSIS = Layout(
    ("card", "side-by-side", "dimensions", "beyond", "mismatches", "outcomes", "conditions", "switches", "wording"),
    header=False,
)
JSON_REPORT = (
    *("card", "confusion", "comparisons", "mismatches", "side-by-side", "answers"),
    *("sources", "splits", "tasks", "outcomes", "conditions", "switches", "wording", "spread", "videos"),
)
CSV_REPORT = ("sources", "splits", "tasks")  # the rate rows


def _listed(made: Tables) -> list[Table]:
    return [] if made is None else [made] if isinstance(made, Table) else made


def report_tables(summary: Summary, published: Published | None, names: Iterable[str]) -> list[Table]:
    """The tables of the sections `names`, in order (the paper's published rows with them when `published` is
    given). Sections of one run's tables listed next to each other are shown run by run: all of the first
    run's, then all of the next run's."""
    tables = []
    sections = [SECTIONS[name] for name in names]
    for per_run, group in itertools.groupby(sections, key=lambda section: section.run_tables is not None):
        if per_run:
            block = list(group)
            tables += [t for run in summary.runs for s in block for t in _listed(s.run_tables(run, s.title))]
        else:
            tables += [t for s in group if s.tables for t in _listed(s.tables(summary, published, s.title))]
    return tables


def report_data(summary: Summary, names: Iterable[str] = JSON_REPORT) -> dict:
    """The data of the sections `names`, in order: the JSON report's object for `JSON_REPORT`."""
    return {key: value for name in names for key, value in SECTIONS[name].data(summary).items()}
