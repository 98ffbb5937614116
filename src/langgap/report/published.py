"""The LangGap paper's published results, shown beside a user's runs as reference rows.

They are the paper's figures as printed (success % per suite and per dimension for six models;
Table II's episode counts for π0.5), stored as data in `published/langgap_paper.yaml`, never
re-run; every table that shows them says so.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import yaml

from langgap.catalog.catalog import load_catalog
from langgap.report.stats import Rate

_DATA = Path(__file__).with_name("published") / "langgap_paper.yaml"


@dataclass(frozen=True)
class PublishedRow:
    """One model's row of a published table: success % by column key (`libero_goal/extended`, `change_object`)."""

    method: str
    values: dict[str, float]


@dataclass(frozen=True)
class AppendixGroup:
    """A row of the paper's per-task appendix: a task or group of tasks and its published count."""

    dimension: str
    label: str
    task_ids: frozenset[str]  # the group's tasks in the langgap99 catalog
    published: Rate


@dataclass(frozen=True)
class Published:
    """The published tables a report can show beside its runs."""

    source: str
    suites: list[PublishedRow]  # Table VI
    dimensions: list[PublishedRow]  # Table VII
    diagnostic_method: str  # Table II's model
    diagnostic: list[Rate]  # Table II: by data source, then by dimension (the published counts)
    appendix_method: str
    appendix: list[AppendixGroup]  # the appendix's per-task detail

    def label(self, method: str, table: str) -> str:
        return f"{method} (published: {self.source}, {table})"


def _rows(table: dict) -> list[PublishedRow]:
    return [
        PublishedRow(method, dict(zip(table["columns"], values, strict=True)))
        for method, values in table["rows"].items()
    ]


@functools.cache
def load_published() -> Published:
    """The paper's published results (read once)."""
    data = yaml.safe_load(_DATA.read_text(encoding="utf-8"))
    tables = data["tables"]
    table_ii = tables["table_ii"]
    diagnostic = [
        Rate(group, episodes=episodes, successes=successes, gaps=0, tasks=tasks)
        for section in ("by_source", "by_dimension")
        for group, (tasks, episodes, successes) in table_ii[section].items()
    ]
    catalog = load_catalog("langgap99")
    appendix = [
        AppendixGroup(
            g["dimension"],
            g["label"],
            frozenset(t.id for t in catalog.select(g["tasks"])),
            Rate(g["label"], episodes=g["episodes"], successes=g["successes"], gaps=0, tasks=g["episodes"] // 20),
        )
        for g in tables["appendix"]["groups"]
    ]
    return Published(
        source=data["source"],
        suites=_rows(tables["table_vi"]),
        dimensions=_rows(tables["table_vii"]),
        diagnostic_method=table_ii["method"],
        diagnostic=diagnostic,
        appendix_method=tables["appendix"]["method"],
        appendix=appendix,
    )
