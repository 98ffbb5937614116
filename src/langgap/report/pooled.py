"""Replicate runs pooled: one configuration run several times (a policy trained with several seeds, say), its
episodes counted together, beside each replicate's own count.

A pool's rate has a Wilson interval over its pooled episodes; that interval is about episodes only and does not
cover the spread between replicates, which is why each replicate's successes are shown beside it, and why two
pools are also compared over their replicates (an exact permutation test on the replicates' rates: the
replicates, not the episodes, are the samples).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from langgap.errors import LangGapError, ParameterError
from langgap.report.data import Spec
from langgap.report.labels import SPLIT_LABEL, label, split_order
from langgap.report.load import load_runs
from langgap.report.stats import Rate, permutation_floor, permutation_p
from langgap.report.summary import RunResults, protocol_differences, results
from langgap.report.tables import Table, pct, rate_cell
from langgap.vocabulary import Outcome

# The pooled table's last column: the extended episodes that did the scene's original task instead.
DEFAULT_TASK = str(Outcome.DID_SOURCE_TASK)
GROUP_LABEL = {**SPLIT_LABEL, DEFAULT_TASK: "Extended episodes that did the original task"}


def pooled_rate(rates: list[Rate]) -> Rate:
    """The rates' episodes counted together (their tasks are the same tasks: the largest count is kept)."""
    return Rate(
        group=rates[0].group,
        episodes=sum(r.episodes for r in rates),
        successes=sum(r.successes for r in rates),
        gaps=sum(r.gaps for r in rates),
        tasks=max(r.tasks for r in rates),
        oracle_successes=sum(r.oracle_successes for r in rates),
        oracle_episodes=sum(r.oracle_episodes for r in rates),
    )


@dataclass(frozen=True)
class PooledCell:
    """One group of episodes (a split, or the default task) of a pool: pooled, and per replicate in order."""

    group: str
    pooled: Rate
    replicates: tuple[Rate, ...]

    DATA: ClassVar[Spec] = ("group", "pooled", "replicates")

    @property
    def counts(self) -> str:
        """Each replicate's successes: `9, 4, 6 of 10` when their episodes agree, `9/10, 4/9` otherwise."""
        sizes = {r.episodes for r in self.replicates}
        if len(sizes) == 1:
            return ", ".join(str(r.successes) for r in self.replicates) + f" of {sizes.pop()}"
        return ", ".join(f"{r.successes}/{r.episodes}" for r in self.replicates)


@dataclass(frozen=True)
class PooledRow:
    """One pool: its label, its runs in the order given, and a cell per group."""

    label: str
    runs: tuple[Path, ...]
    cells: tuple[PooledCell, ...]

    def cell(self, group: str) -> PooledCell | None:
        return next((c for c in self.cells if c.group == group), None)


def _order(groups: set[str]) -> list[str]:
    """The splits in table order (`split_order`), the default task last."""
    return [*split_order(groups - {DEFAULT_TASK}), *([DEFAULT_TASK] if DEFAULT_TASK in groups else [])]


def _groups(result: RunResults) -> dict[str, Rate]:
    """A run's rates that pools show: per split (original, training, held-out), then the default task."""
    return {**{r.group: r for r in result.by_split}, DEFAULT_TASK: result.default_task}


def pool(
    pools: dict[str, list[str | Path]], *, allow_mismatch: bool = False, split: str | None = None
) -> list[PooledRow]:
    """Each pool's runs (replicates of one configuration) counted together, in the order of `pools`; their groups
    are a stored split's when `split` names one (`langgap.report.load.load_runs`).

    Raises:
        LangGapError: A pool is empty or names a run twice, its runs are of different policies, or (unless
            `allow_mismatch`) some run's protocol differs from the first run's.
        StoreError: A path holds no run store.
    """
    rows = []
    first: RunResults | None = None
    for name, paths in pools.items():
        resolved = [Path(p).resolve() for p in paths]
        if not paths:
            raise LangGapError(f"pool {name!r} names no run")
        if len(set(resolved)) < len(resolved):
            raise LangGapError(f"pool {name!r} names a run twice: its episodes would be counted twice")
        replicates = [results(run) for run in load_runs(paths, split=split)]
        policies = sorted({str(r.spec.get("policy", "?")) for r in replicates})
        if len(policies) > 1:
            raise LangGapError(f"pool {name!r} mixes policies ({', '.join(policies)}): a pool is one configuration")
        first = first or replicates[0]
        for replicate in replicates:
            differences = protocol_differences(first, replicate)
            if differences and not allow_mismatch:
                raise ParameterError(
                    "{path} differs from {first} in {fields}: pooled episodes must come from one protocol "
                    "({allow_mismatch} pools them anyway)",
                    path=replicate.path,
                    first=first.path,
                    fields=", ".join(differences),
                )
        per_run = [_groups(r) for r in replicates]
        present = {g for groups in per_run for g, rate in groups.items() if rate.episodes or rate.gaps}
        cells = []
        for group in _order(present):
            rates = [groups.get(group, Rate(group, 0, 0, 0, 0)) for groups in per_run]
            cells.append(PooledCell(group, pooled_rate(rates), tuple(rates)))
        rows.append(PooledRow(name, tuple(Path(p) for p in paths), tuple(cells)))
    return rows


@dataclass(frozen=True)
class ReplicateTest:
    """Two pools compared on one group over their replicates: each replicate's rate, the difference of the
    means (second minus first), the exact permutation p-value (None: too many splits to enumerate) and the
    smallest p-value these numbers of replicates can give."""

    first: str
    second: str
    group: str
    first_rates: tuple[float, ...]
    second_rates: tuple[float, ...]
    difference: float
    p: float | None
    floor: float


def replicate_tests(rows: list[PooledRow]) -> list[ReplicateTest]:
    """Every pair of pools with at least two replicates each, on every group both have episodes in, but the
    groups where every replicate of both pools has the same rate (nothing to test)."""
    tests = []
    for first, second in itertools.combinations([row for row in rows if len(row.runs) >= 2], 2):
        for group in _order({c.group for c in first.cells} & {c.group for c in second.cells}):
            a = tuple(r.rate for r in first.cell(group).replicates if r.episodes)
            b = tuple(r.rate for r in second.cell(group).replicates if r.episodes)
            if len(a) < 2 or len(b) < 2 or len({*a, *b}) == 1:
                continue
            difference = sum(b) / len(b) - sum(a) / len(a)
            tests.append(
                ReplicateTest(
                    first.label,
                    second.label,
                    group,
                    a,
                    b,
                    difference,
                    permutation_p(a, b),
                    permutation_floor(len(a), len(b)),
                )
            )
    return tests


def replicate_tests_table(tests: list[ReplicateTest]) -> Table:
    """A row per pair of pools and group: each replicate's rate, the difference of means (second minus first, which
    each cell names: a bare sign reads either way), p and its floor."""
    rows = [
        [
            f"{t.first} vs {t.second}",
            label(GROUP_LABEL, t.group),
            ", ".join(map(pct, t.first_rates)),
            ", ".join(map(pct, t.second_rates)),
            f"{100 * t.difference:+.1f} ({t.second} minus {t.first})",
            "–" if t.p is None else f"{t.p:.3g}",
            f"{t.floor:.3g}",
        ]
        for t in tests
    ]
    headers = ["Pools", "Group", "First pool's runs %", "Second pool's runs %",
               "Difference of means (points, second minus first)", "p (exact permutation over runs)",
               "Smallest p possible"]  # fmt: skip
    return Table("Between pools over their runs (each run one sample; two-sided exact permutation test)", headers, rows)


def pooled_table(rows: list[PooledRow]) -> Table:
    """A row per pool: each group's pooled rate and Wilson interval, then each replicate's successes."""
    groups = _order({c.group for row in rows for c in row.cells})
    table_rows = []
    for row in rows:
        cells = [row.cell(g) for g in groups]
        table_rows.append(
            [row.label, str(len(row.runs))] + [f"{rate_cell(c.pooled)}; {c.counts}" if c else "–" for c in cells]
        )
    headers = ["Pool", "Runs", *(f"{label(GROUP_LABEL, g)} %" for g in groups)]
    return Table("Pooled over replicate runs (rate % [95% CI over the pooled episodes]; each run's successes)",
                 headers, table_rows)  # fmt: skip
