"""How much of a catalog the feasibility gate has proven: its verdicts counted per suite and dimension.

A task is *gated* when a verdict is recorded for it; each gated task is counted under its verdict's word
(`langgap.vocabulary.Verdict`): doable (the gate kept it: the oracle met the gate's rate, or a searched
demonstration did it), unproven (rejected without a proof: nobody has yet shown it doable or impossible),
infeasible (rejected with a proof that no policy can do it, `langgap.gate.proofs`) or unsettled (rejected
because its starts do not come to rest).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

from langgap.catalog.task import DIMENSIONS, Task
from langgap.stack import SUITES
from langgap.vocabulary import Verdict

TOTAL = "total"
EVERY = "all"


@dataclass(frozen=True)
class GateCount:
    """The gate's verdicts on one group of tasks (a suite and dimension, or a total)."""

    suite: str
    dimension: str
    tasks: int
    gated: int
    verdicts: dict[Verdict, int]  # gated tasks per verdict (every verdict, 0 included)
    episodes: int  # the oracle's, over the gated tasks
    successes: int


def _count(suite: str, dimension: str, tasks: list[Task]) -> GateCount:
    gated = [t.gate for t in tasks if t.gate is not None]
    found = Counter(g.verdict for g in gated)
    return GateCount(
        suite=suite,
        dimension=dimension,
        tasks=len(tasks),
        gated=len(gated),
        verdicts={v: found[v] for v in Verdict},
        episodes=sum(g.episodes for g in gated),
        successes=sum(g.successes for g in gated),
    )


def gate_counts(tasks: list[Task]) -> list[GateCount]:
    """One count per suite and dimension that has tasks (suites in LIBERO's order, dimensions in the
    catalog's), then, when the tasks span suites, one per dimension over them (suite `total`), then
    the grand total (suite `total`, dimension `all`)."""
    counts = []
    dimensions = [d for d in DIMENSIONS if any(t.dimension == d for t in tasks)]
    for suite in SUITES:
        for dimension in dimensions:
            group = [t for t in tasks if t.suite == suite and t.dimension == dimension]
            if group:
                counts.append(_count(suite, dimension, group))
    if len({t.suite for t in tasks}) > 1:
        counts += [_count(TOTAL, d, [t for t in tasks if t.dimension == d]) for d in dimensions]
    counts.append(_count(TOTAL, EVERY, tasks))
    return counts


HEADER = ("suite", "dimension", "tasks", "gated", *Verdict, "oracle")


def _cells(count: GateCount) -> tuple[str, ...]:
    oracle = f"{count.successes}/{count.episodes}" if count.episodes else "-"
    numbers = (count.tasks, count.gated, *(count.verdicts[v] for v in Verdict))
    return (count.suite, count.dimension, *map(str, numbers), oracle)


def coverage_table(counts: list[GateCount], *, markdown: bool = False) -> str:
    """The counts as a printed table, or a Markdown one."""
    rows = [HEADER, *map(_cells, counts)]
    if markdown:
        lines = ["| " + " | ".join(row) + " |" for row in rows]
        lines.insert(1, "|" + "---|" * 2 + "---:|" * (len(HEADER) - 2))
        return "\n".join(lines)
    widths = [max(len(row[i]) for row in rows) for i in range(len(HEADER))]

    def line(row: tuple[str, ...]) -> str:
        cells = zip(row, widths, strict=True)
        return "  ".join(cell.ljust(w) if i < 2 else cell.rjust(w) for i, (cell, w) in enumerate(cells))  # names left

    return "\n".join(map(line, rows))


def on_other_stacks(tasks: list[Task]) -> tuple[int, int]:
    """(verdicts made on another physics stack than the installed one, verdicts) over the tasks."""
    gated = [t.gate for t in tasks if t.gate is not None]
    return sum(bool(gate.other_stack) for gate in gated), len(gated)


def stacks_text(tasks: list[Task]) -> str | None:
    """How many of the tasks' verdicts were made on the installed physics stack and how many on another, with
    what differs and in how many verdicts (`GateResult.other_stack`); None when no task is gated."""
    gated = [t.gate for t in tasks if t.gate is not None]
    if not gated:
        return None
    differing = Counter(difference for gate in gated for difference in gate.other_stack)
    other, _ = on_other_stacks(tasks)
    text = f"verdicts made on the installed physics stack: {len(gated) - other} of {len(gated)}"
    if other:
        named = "; ".join(f"{difference}: {n}" for difference, n in sorted(differing.items()))
        text += f"; on another: {other} ({named}; re-gate: langgap validate --record)"
    return text
