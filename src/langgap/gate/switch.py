"""The switch feasibility gate: per task and K, whether the oracle follows an instruction that switches to
the task's own at policy step K (`switch:K`, `langgap.engine.plan`).

A task accepted by the plain gate is doable from its start; a `switch:K` episode leaves the scene as K
steps of another task did (a bowl carried off, a drawer half open) and leaves fewer steps. The oracle,
which puts down what it holds and closes what the new goal needs closed, runs every task under each
switch on the first init states; it must reach `SWITCH_RATE` with no gap, else the task is *unproven*
at that K — never infeasible, since the oracle failing shows nothing about other policies.
Verdicts are recorded per task and K in `<registry>.switch-gate.json` (`langgap.catalog.switch_verdicts`).
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from langgap.catalog.catalog import load_catalog, registry_path
from langgap.catalog.switch_verdicts import SwitchVerdicts, record_switch_verdicts
from langgap.catalog.verdicts import GateResult, verdict_counts, verdict_of
from langgap.engine.evaluate import evaluate
from langgap.engine.spec import ExecutionOptions, RunSpec
from langgap.errors import ParameterError
from langgap.gate.recording import provenance
from langgap.gate.rows import gate_result
from langgap.records import EpisodeRecord
from langgap.stack import DEFAULT_STEPPING
from langgap.store import RunStore
from langgap.vocabulary import SWITCH, SWITCH_RATE, Verdict, switch_step


@dataclass
class SwitchGateRow:
    """The switch gate's verdict on one task at one K."""

    id: str
    condition: str  # switch:K
    episodes: int  # judged
    successes: int
    gaps: int
    failed_inits: list[int] = field(default_factory=list)

    @property
    def rate(self) -> float:
        return self.successes / self.episodes if self.episodes else 0.0

    @property
    def feasible(self) -> bool:
        return bool(self.episodes) and not self.gaps and self.rate >= SWITCH_RATE

    @property
    def word(self) -> Verdict:
        """The row's verdict as a word: doable or unproven at this K (`verdict_of`)."""
        return verdict_of(self.feasible, "", self.reason)

    @property
    def reason(self) -> str:
        """Why the task is not accepted at this K (empty: it is)."""
        if self.feasible:
            return ""
        parts = [f"oracle {self.successes}/{self.episodes} under {self.condition}"] if self.rate < SWITCH_RATE else []
        return "; ".join(parts + ([f"{self.gaps} episode(s) not judged"] if self.gaps else []))

    def verdict(self, inits: int, made_by: str, physics: dict) -> GateResult:
        """The verdict to record for a gate that ran init states 0..`inits`-1 as `made_by` says, on `physics`."""
        return gate_result(self, inits, made_by, physics)


def switch_conditions(conditions: list[str]) -> tuple[str, ...]:
    """The `switch:K` conditions the switch gate runs; anything else is a LangGapError."""
    other = [c for c in conditions if switch_step(c) is None]
    if other:
        raise ParameterError(
            "{conditions} takes {switch}K only (the plain gate needs no condition), got {got}",
            switch=SWITCH,
            got=", ".join(other),
        )
    return tuple(dict.fromkeys(conditions))


def switch_rows(records: list[EpisodeRecord]) -> list[SwitchGateRow]:
    """One row per task and condition of `records`, in the order they first appear."""
    grouped: dict[tuple[str, str], list[EpisodeRecord]] = {}
    for r in records:
        grouped.setdefault((r.task_id, r.condition), []).append(r)
    rows = []
    for (task_id, condition), group in grouped.items():
        judged = [r for r in group if r.judged]
        failed = sorted(r.init_index for r in judged if not r.success)
        wins = sum(r.success for r in judged)
        rows.append(SwitchGateRow(task_id, condition, len(judged), wins, len(group) - len(judged), failed))
    return rows


def validate_switch(
    catalog_name: str,
    selection: str | None,
    conditions: tuple[str, ...],
    *,
    inits: int,
    options: ExecutionOptions | None = None,
    run: str | Path | None = None,
    resume: bool = False,
    policy: str = "oracle",
    stepping: str = DEFAULT_STEPPING,
) -> list[SwitchGateRow]:
    """Run `policy` on the selected tasks under each `switch:K` of `conditions`, init states 0..`inits`-1
    (kept in `run` when given, resumable), and judge each task and K."""
    ids = ",".join(t.id for t in load_catalog(catalog_name).select(selection))
    spec = RunSpec.create(
        policy, catalog=catalog_name, tasks=ids, episodes=inits, conditions=conditions, stepping=stepping
    )
    with tempfile.TemporaryDirectory(prefix="langgap-switch-gate-") as scratch:
        directory = Path(run) if run is not None else Path(scratch) / "run"
        evaluate(spec, directory, options or ExecutionOptions(), resume=resume, extend=resume)
        with RunStore.open(directory) as store:
            records = store.records()
    # A resumed run may hold other conditions' episodes too (one grown with --extend): only the switches count.
    return switch_rows([r for r in records if r.condition in conditions])


def record_switch(
    catalog_name: str,
    rows: list[SwitchGateRow],
    *,
    inits: int,
    policy: str = "oracle",
    stepping: str = DEFAULT_STEPPING,
) -> Path:
    """Record the rows' verdicts in the catalog's switch verdict file (other tasks and K are kept)."""
    about, made_by = provenance(policy, inits, stepping, switch_rate=SWITCH_RATE)
    verdicts: SwitchVerdicts = {}
    for row in rows:
        verdicts.setdefault(row.id, {})[row.condition] = row.verdict(inits, made_by, about["physics"])
    return record_switch_verdicts(registry_path(catalog_name), verdicts, about)


def switch_table_text(rows: list[SwitchGateRow]) -> str:
    """A printed table: one line per task and K, then the totals."""
    width = max((len(r.id) for r in rows), default=4)
    lines = [f"{'task':<{width}}  {'condition':<10}  {'oracle':>9}  {'rate':>6}  verdict"]
    for r in rows:
        verdict = r.word if r.feasible else f"{r.word} ({r.reason})"
        oracle = f"{r.successes:>4}/{r.episodes:<4}"
        lines.append(f"{r.id:<{width}}  {r.condition:<10}  {oracle}  {100 * r.rate:>5.1f}%  {verdict}")
    lines.append(
        f"switch gate: {verdict_counts([r.word for r in rows])} (task and K pairs; the oracle must reach "
        f"{SWITCH_RATE:.0%})"
    )
    return "\n".join(lines)
