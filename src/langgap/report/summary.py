"""Every number a report shows, computed once from the stored episodes into one `Summary`.

Tables and every output format read the summary; nothing downstream counts episodes again. Rates
use the episodes run with the task's own instruction (condition `given`); gaps never count as
failures, and every row carries the number it left out.
"""

from __future__ import annotations

import functools
import statistics
from collections import Counter, defaultdict
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

from langgap.catalog.switch_verdicts import SwitchVerdicts, accepted
from langgap.catalog.verdicts import GateResult
from langgap.engine.plan import repeat_of
from langgap.engine.spec import spec_differences
from langgap.errors import LangGapError
from langgap.records import JUDGED_OUTCOMES, EpisodeRecord, Privilege, achieved
from langgap.report.answer import Answer, Switched
from langgap.report.card import PROTOCOL_ITEMS, protocol_card
from langgap.report.data import MERGED, Spec
from langgap.report.labels import (
    EXTENDED_DIMENSIONS,
    KNOWN_DIMENSIONS,
    SUITE_ORDER,
    split_order,
)
from langgap.report.load import Run
from langgap.report.stats import PairedTest, Rate
from langgap.stack import stack_differences, stacks_differ
from langgap.vocabulary import SAME_GOAL_DIMENSIONS, SWITCH, Condition, Outcome, TaskKind, switch_step


def oracle_ceiling(records: Iterable[EpisodeRecord], gates: Mapping[str, GateResult]) -> tuple[int, int]:
    """(successes, episodes) of the scripted oracle on the tasks and init states of the judged `records`,
    from the recorded verdicts `gates` (tasks without one are left out; (0, 0) when none has one)."""
    inits: dict[str, set[int]] = defaultdict(set)
    for r in records:
        if r.judged and r.task_id in gates:
            inits[r.task_id].add(r.init_index)
    counts = [gates[task].oracle_on(sorted(indices)) for task, indices in inits.items()]
    return sum(s for s, _ in counts), sum(n for _, n in counts)


def dimension_order(present: Iterable[str]) -> list[str]:
    """The dimensions in `present`: those reports know in `KNOWN_DIMENSIONS` order, then any other, sorted."""
    present = set(present)
    return [d for d in KNOWN_DIMENSIONS if d in present] + sorted(present - set(KNOWN_DIMENSIONS))


def extended_dimensions(records: Iterable[EpisodeRecord]) -> list[str]:
    """The dimensions of `records`' extended tasks (`dimension_order`)."""
    return dimension_order(r.dimension for r in records if r.kind == TaskKind.EXTENDED)


def rate(group: str, records: Iterable[EpisodeRecord], gates: Mapping[str, GateResult] | None = None) -> Rate:
    """The success rate of `records` over their judged episodes, beside the oracle's on the same ones."""
    records = list(records)
    judged = [r for r in records if r.judged]
    oracle_successes, oracle_episodes = oracle_ceiling(judged, gates or {})
    return Rate(
        group=group,
        episodes=len(judged),
        successes=sum(r.success for r in judged),
        gaps=len(records) - len(judged),
        tasks=len({r.task_id for r in records}),
        oracle_successes=oracle_successes,
        oracle_episodes=oracle_episodes,
    )


def rates_by(
    records: Iterable[EpisodeRecord],
    key: Callable[[EpisodeRecord], str | None],
    order=(),
    gates: Mapping[str, GateResult] | None = None,
) -> list[Rate]:
    """One `Rate` per value of `key` (records whose key is None are left out), `order` first, then sorted."""
    groups: dict[str, list[EpisodeRecord]] = defaultdict(list)
    for record in records:
        if (name := key(record)) is not None:
            groups[name].append(record)
    names = [n for n in order if n in groups] + sorted(n for n in groups if n not in order)
    return [rate(n, groups[n], gates) for n in names]


@dataclass(frozen=True)
class TaskRow:
    """One task's rate with what the per-task table shows beside it."""

    rate: Rate
    dimension: str
    instruction: str
    suite: str = ""
    split: str = ""
    outcomes: dict[str, int] = field(default_factory=dict)  # judged episodes per outcome

    @property
    def instead(self) -> tuple[str, int] | None:
        """The most frequent outcome other than success and its episode count (None: every episode succeeded)."""
        failures = [(n, o) for o, n in self.outcomes.items() if o != Outcome.SUCCESS and n]
        if not failures:
            return None
        count, outcome = max(failures, key=lambda item: (item[0], -JUDGED_OUTCOMES.index(item[1])))
        return outcome, count


# The order in which clips are shown: the failures that explain most first, successes last.
CLIP_ORDER = (Outcome.PERSISTED, Outcome.DID_SOURCE_TASK, Outcome.WRONG_ORDER, Outcome.DID_OTHER_TASK,
              Outcome.NO_GOAL_REACHED, Outcome.POLICY_ERROR, Outcome.SUCCESS)  # fmt: skip


@dataclass(frozen=True)
class Clip:
    """One filmed episode: what was asked, what happened, and the video file."""

    task_id: str
    condition: str
    init_index: int
    seed: int
    outcome: str
    instruction: str  # every instruction it was sent, in order (`timeline_text`)
    path: Path


def timeline_text(timeline: list[tuple[int, str]]) -> str:
    """An episode's instructions as one line: the first, then each change with its step (`→ at step K: ...`)."""
    return " → ".join(text if step == 0 else f"at step {step}: {text}" for step, text in timeline)


def clips(run: Run) -> list[Clip]:
    """The run's filmed judged episodes, in `CLIP_ORDER`, then by task, condition and init state."""
    filmed = [r for r in run.records if r.video and r.judged]
    filmed.sort(key=lambda r: (CLIP_ORDER.index(Outcome(r.outcome)), r.task_id, r.condition, r.init_index, r.seed))
    return [
        Clip(
            r.task_id, r.condition, r.init_index, r.seed, str(r.outcome), timeline_text(r.timeline), run.path / r.video
        )
        for r in filmed
    ]


@dataclass(frozen=True)
class SpreadRow:
    """One group's success rate in each repeat of a run (same init states, other seeds)."""

    group: str
    rates: list[Rate]  # one per repeat

    @property
    def mean(self) -> float:
        return statistics.fmean(r.rate for r in self.rates)

    @property
    def std(self) -> float:
        """The sample standard deviation across repeats (0 with one repeat)."""
        return statistics.stdev(r.rate for r in self.rates) if len(self.rates) > 1 else 0.0

    # The JSON report's row (`langgap.report.data.to_data`): each repeat's rate, their mean and spread.
    DATA: ClassVar[Spec] = ("group", ("rates", lambda row: [r.rate for r in row.rates]), "mean", "std")


def spread(records: list[EpisodeRecord], run_seed: int) -> list[SpreadRow]:
    """Per source and dimension, the rate in each repeat; empty for a run with one repeat."""
    repeats = sorted({repeat_of(r.seed, r.init_index, run_seed) for r in records})
    if len(repeats) < 2:
        return []
    groups = [(kind, lambda r, kind=kind: r.kind == kind) for kind in TaskKind]
    groups += [
        (d, lambda r, d=d: r.kind == TaskKind.EXTENDED and r.dimension == d) for d in extended_dimensions(records)
    ]
    rows = []
    for name, member in groups:
        chosen = [r for r in records if member(r)]
        if chosen:
            by_repeat = [[r for r in chosen if repeat_of(r.seed, r.init_index, run_seed) == k] for k in repeats]
            rows.append(SpreadRow(name, [rate(name, rs) for rs in by_repeat]))
    return rows


@dataclass(frozen=True)
class OutcomeRow:
    """What the policy did instead, for one group of episodes: the share of each outcome."""

    group: str  # a dimension, `extended` (all extended tasks) or `original`
    episodes: int
    gaps: int
    shares: dict[str, float]  # outcome -> share of the judged episodes

    DATA: ClassVar[Spec] = ("group", "episodes", "gaps", (MERGED, "shares"))  # one entry per outcome


def outcome_row(group: str, records: list[EpisodeRecord]) -> OutcomeRow:
    judged = [r for r in records if r.judged]
    counts = Counter(r.outcome for r in judged)
    shares = {str(o): counts[o] / len(judged) if judged else 0.0 for o in JUDGED_OUTCOMES}
    return OutcomeRow(group, len(judged), len(records) - len(judged), shares)


# A switch episode's outcome in four: its own task, the first instruction's, another scene task's, or none.
SWITCH_CLASSES = {
    Outcome.SUCCESS: (Outcome.SUCCESS,),
    Outcome.PERSISTED: (Outcome.PERSISTED,),
    "other": (Outcome.DID_SOURCE_TASK, Outcome.DID_OTHER_TASK, Outcome.WRONG_ORDER),
    "none": (Outcome.NO_GOAL_REACHED, Outcome.POLICY_ERROR),
}


@dataclass(frozen=True)
class SwitchRow:
    """The `switch:K` episodes of one group (a dimension, `extended` or `original`): each class's share as
    a `Rate` (its successes are the episodes in that class), for its interval."""

    k: int
    group: str
    classes: dict[str, Rate]  # `SWITCH_CLASSES` name -> its share
    tasks: int = 0  # the group's tasks
    unproven: tuple[str, ...] = ()  # its tasks the switch gate has not accepted at K (marked ⚠)

    @property
    def episodes(self) -> int:
        """The group's judged episodes (every class's denominator)."""
        return next(iter(self.classes.values())).episodes

    @property
    def gaps(self) -> int:
        """The group's gaps (left out of every class's share)."""
        return next(iter(self.classes.values())).gaps

    # The JSON report's row (`langgap.report.data.to_data`): the counts, each class's share, then their intervals.
    DATA: ClassVar[Spec] = (
        "k",
        "group",
        "episodes",
        "gaps",
        "tasks",
        "unproven",
        (MERGED, lambda row: {name: r.rate for name, r in row.classes.items()}),
        (MERGED, lambda row: {f"{name}_ci": r.ci for name, r in row.classes.items()}),
    )


def switch_rows(records: list[EpisodeRecord], verdicts: SwitchVerdicts | None = None) -> list[SwitchRow]:
    """Per K of the run's `switch:K` conditions, per dimension, then all extended and original tasks, each
    naming its tasks without an accepted switch verdict at K in `verdicts` (the run's snapshot)."""
    rows = []
    for k in sorted({k for r in records if (k := switch_step(r.condition)) is not None}):
        switched = [r for r in records if switch_step(r.condition) == k]
        extended = [r for r in switched if r.kind == TaskKind.EXTENDED]
        groups = [(d, [r for r in extended if r.dimension == d]) for d in extended_dimensions(extended)]
        groups += [
            (TaskKind.EXTENDED, extended),
            (TaskKind.ORIGINAL, [r for r in switched if r.kind == TaskKind.ORIGINAL]),
        ]
        for group, members in groups:
            if not members:
                continue
            judged = [r for r in members if r.judged]
            classes = {
                name: Rate(
                    group,
                    len(judged),
                    sum(r.outcome in outcomes for r in judged),
                    len(members) - len(judged),
                    len({r.task_id for r in members}),
                )
                for name, outcomes in SWITCH_CLASSES.items()
            }
            inits: dict[str, set[int]] = defaultdict(set)
            for r in members:
                inits[r.task_id].add(r.init_index)
            condition = f"{SWITCH}{k}"
            unproven = tuple(t for t in sorted(inits) if not accepted(verdicts or {}, t, condition, inits[t]))
            rows.append(SwitchRow(k, group, classes, len(inits), unproven))
    return rows


def paired(
    name: str, a: dict[tuple, EpisodeRecord], b: dict[tuple, EpisodeRecord], *, retest: bool = False
) -> PairedTest | None:
    """McNemar over the keys judged in both `a` and `b` (None when there are none); `retest`: they are the
    episodes of one run spec run twice (`PairedTest.retest`)."""
    keys = [k for k in a if k in b and a[k].judged and b[k].judged]
    if not keys:
        return None
    return PairedTest(
        name=name,
        pairs=len(keys),
        successes_a=sum(a[k].success for k in keys),
        successes_b=sum(b[k].success for k in keys),
        only_a=sum(a[k].success and not b[k].success for k in keys),
        only_b=sum(b[k].success and not a[k].success for k in keys),
        changed=sum(achieved(a[k]) != achieved(b[k]) for k in keys),
        retest=retest,
    )


def condition_tests(records: list[EpisodeRecord]) -> list[PairedTest]:
    """Each language condition against `given`, episode by episode: a policy that reads language changes."""
    by_condition: dict[str, dict[tuple, EpisodeRecord]] = defaultdict(dict)
    for r in records:
        by_condition[r.condition][(r.task_id, r.init_index, r.seed)] = r
    given = by_condition[Condition.GIVEN]
    others = sorted(c for c in by_condition if c != Condition.GIVEN)
    tests = (paired(f"{Condition.GIVEN} vs {c}", given, by_condition[c]) for c in others)
    return [t for t in tests if t is not None]


# Dimensions whose tasks keep their source's goal and change only its words: paired against the source.
REWORDED_DIMENSIONS = ("paraphrase", "attribute_reference")


def wording_tests(records: list[EpisodeRecord]) -> list[PairedTest]:
    """Each rewording (a paraphrase template, attribute reference) against its sources' original sentences,
    episode by episode (same init state, seed and condition): the difference the words alone make."""
    originals = {(r.task_id, r.init_index, r.seed, r.condition): r for r in records if r.kind == TaskKind.ORIGINAL}
    variants: dict[str, dict[tuple, EpisodeRecord]] = defaultdict(dict)
    for r in records:
        if r.kind == TaskKind.EXTENDED and r.dimension in REWORDED_DIMENSIONS:
            name = f"{r.dimension} ~{r.task_id.rsplit('~', 1)[-1]}"
            variants[name][(r.source, r.init_index, r.seed, r.condition)] = r
    tests = (paired(f"{TaskKind.ORIGINAL} vs {name}", originals, variants[name]) for name in sorted(variants))
    return [t for t in tests if t is not None]


def against_sources(records: list[EpisodeRecord]) -> PairedTest | None:
    """Every extended episode against its source task's episode on the same init state, seed and condition
    (a source's episode stands beside each of its extended tasks): the drop the extended tasks make."""
    originals = {(r.task_id, r.init_index, r.seed, r.condition): r for r in records if r.kind == TaskKind.ORIGINAL}
    extended = {r.key: r for r in records if r.kind == TaskKind.EXTENDED}
    sources = {
        key: source
        for key, r in extended.items()
        if (source := originals.get((r.source, r.init_index, r.seed, r.condition))) is not None
    }
    return paired(f"{TaskKind.ORIGINAL}s vs {TaskKind.EXTENDED}", sources, extended)


def default_task(records: list[EpisodeRecord]) -> Rate:
    """The default-task rate of extended episodes: the share that did the scene's original task instead
    (as a `Rate`, for its interval)."""
    judged = [r for r in records if r.judged]
    return Rate(
        group=Outcome.DID_SOURCE_TASK,
        episodes=len(judged),
        successes=sum(r.outcome == Outcome.DID_SOURCE_TASK for r in judged),
        gaps=len(records) - len(judged),
        tasks=len({r.task_id for r in records}),
    )


def confusion(records: list[EpisodeRecord]) -> dict[str, dict[str, dict[str, int]]]:
    """Per scene: intended task -> achieved task -> judged episode count."""
    matrices: dict[str, dict[str, Counter]] = defaultdict(lambda: defaultdict(Counter))
    for r in records:
        if r.judged:
            matrices[r.scene][r.task_id][achieved(r)] += 1
    return {scene: {task: dict(row) for task, row in rows.items()} for scene, rows in matrices.items()}


def capped_because(task_rate: Rate, gate: GateResult | None) -> str | None:
    """Why a task is marked ⚠ (None: it is not), led by its verdict's word: proven infeasible, its starts do not
    come to rest, or an oracle below `langgap.vocabulary.CEILING_TARGET` on the run's init states
    (`GateResult.capped_because`)."""
    return None if gate is None else gate.capped_because(task_rate.oracle_successes, task_rate.oracle_episodes)


def verdicts_on_other_stacks(gates: Mapping[str, GateResult], episodes: Mapping[str, EpisodeRecord]) -> dict:
    """Task -> how the physics stack its verdict was made on differs from that of its episode `episodes` gives
    (`langgap.stack.stack_differences`), for the tasks whose verdict's stack differs: their Oracle % and ⚠
    rest on other physics than the policy's episodes."""
    differences = {
        task: stack_differences(gates[task].physics, r.physics) for task, r in episodes.items() if task in gates
    }
    return {task: found for task, found in differences.items() if found}


# How tables mark a run whose policy had a privilege (explained by `tables.PRIVILEGE_NOTES`).
PRIVILEGE_MARK = {Privilege.GOAL: "†", Privilege.STATE: "‡"}


@dataclass
class RunResults:
    """Everything reports show about one run."""

    name: str
    path: Path
    spec: dict
    privilege: Privilege
    episodes: int  # stored episodes, all conditions
    gaps: int
    by_source: list[Rate]  # original, extended, total
    by_dimension: list[Rate]  # extended tasks
    by_suite: list[Rate]  # `suite/kind`
    by_split: list[Rate]
    tasks: list[TaskRow]
    outcomes: list[OutcomeRow]  # per dimension, all extended, original
    confusion: dict[str, dict[str, dict[str, int]]]
    conditions: list[PairedTest]
    wording: list[PairedTest]  # rewordings against their sources' original sentences (`wording_tests`)
    card: dict[str, str]  # the protocol card (`CARD_ITEMS`)
    spread: list[SpreadRow]  # between-seed spread (runs with --repeats)
    clips: list[Clip]  # filmed episodes (`--video`)
    capped: dict[str, str]  # task -> why it is marked ⚠ (`capped_because`)
    other_stack: dict[str, list[str]]  # task -> how its verdict's physics stack differs from its episodes'
    gate_source: str  # where the verdicts behind Oracle % and ⚠ come from (`Run.gate_source`)
    against_originals: PairedTest | None  # extended episodes against their sources' (`against_sources`)
    default_task: Rate  # extended episodes that did the scene's original task instead (`default_task`)
    against_blind: PairedTest | None = None  # extended episodes against a compared `blind` run's (`summarize`)
    switches: list[SwitchRow] = field(default_factory=list)  # `switch:K` episodes per K and dimension
    # The extended episodes the answer rests on (`answer_rests_on`) and how many extended tasks reword their
    # source's goal (a policy that ignores its instruction does those as well as their sources).
    answered: Rate | None = None
    reworded: int = 0
    progress: str | None = None  # how much of its plan the run holds, when not all of it (`Run.progress`)

    @property
    def same_goal_only(self) -> bool:
        """Whether every extended task asks for its source's goal in other words."""
        return 0 < self.reworded == self.source(TaskKind.EXTENDED).tasks

    @property
    def mixed(self) -> bool:
        """Whether the run has both rewordings of a source's goal and tasks asking for another goal: its answer
        rests on the latter."""
        return 0 < self.reworded < self.source(TaskKind.EXTENDED).tasks

    @property
    def label(self) -> str:
        """The name tables show: marked † if the policy was told the goal (a scripted reference), ‡ if it
        read simulator state (`tables.PRIVILEGE_NOTES`)."""
        mark = PRIVILEGE_MARK.get(self.privilege)
        return f"{self.name} {mark}" if mark else self.name

    def source(self, group: str) -> Rate:
        return next(r for r in self.by_source if r.group == group)

    @property
    def answer(self) -> Answer:
        """The run's opening sentence and what it rests on."""
        original = self.source(TaskKind.ORIGINAL)
        return Answer(
            self.label,
            original,
            self.answered or self.source(TaskKind.EXTENDED),
            self.default_task,
            self.against_originals,
            self.against_blind,
            self.gaps,
            self.same_goal_only,
            self.reworded if self.mixed else 0,
            tuple(
                Switched(row.k, row.classes[Outcome.SUCCESS], row.classes[Outcome.PERSISTED])
                for row in self.switches
                if row.group == TaskKind.EXTENDED
            ),
        )


def results(run: Run) -> RunResults:
    """Aggregate one run."""
    given = [r for r in run.records if r.condition == Condition.GIVEN]
    extended = [r for r in given if r.kind == TaskKind.EXTENDED]
    originals = [r for r in given if r.kind == TaskKind.ORIGINAL]
    reworded = {r.task_id for r in extended if r.dimension in SAME_GOAL_DIMENSIONS}
    mixed = 0 < len(reworded) < len({r.task_id for r in extended})
    answered = [r for r in extended if answer_rests_on(r, mixed=mixed)]
    order = {d: i for i, d in enumerate((TaskKind.ORIGINAL, *KNOWN_DIMENSIONS))}
    info = {r.task_id: r for r in given}
    per_outcome: dict[str, Counter] = defaultdict(Counter)
    for r in given:
        if r.judged:
            per_outcome[r.task_id][str(r.outcome)] += 1
    gates = run.gates
    tasks = [
        TaskRow(t, (i := info[t.group]).dimension, i.instruction, i.suite, i.split, dict(per_outcome[t.group]))
        for t in rates_by(given, lambda r: r.task_id, gates=gates)
    ]
    tasks.sort(key=lambda row: (order.get(row.dimension, len(order)), row.rate.group))
    outcome_groups = [(d, [r for r in extended if r.dimension == d]) for d in extended_dimensions(extended)]
    outcome_groups += [(TaskKind.EXTENDED, extended), (TaskKind.ORIGINAL, originals)]
    return RunResults(
        name=run.name,
        path=run.path,
        spec=run.spec,
        privilege=run.privilege,
        episodes=len(run.records),
        gaps=sum(not r.judged for r in run.records),
        by_source=[
            rate(TaskKind.ORIGINAL, originals, gates),
            rate(TaskKind.EXTENDED, extended, gates),
            rate("total", given, gates),
        ],
        by_dimension=rates_by(extended, lambda r: r.dimension, KNOWN_DIMENSIONS, gates),
        by_suite=rates_by(
            given, lambda r: f"{r.suite}/{r.kind}", [f"{s}/{k}" for s in SUITE_ORDER for k in TaskKind], gates
        ),
        by_split=rates_by(given, lambda r: r.split, split_order({r.split for r in given}), gates),
        tasks=tasks,
        outcomes=[outcome_row(g, rs) for g, rs in outcome_groups if rs],
        confusion=confusion(given),
        conditions=condition_tests(run.records),
        wording=wording_tests(given),
        card=protocol_card(run),
        spread=spread(given, int(run.spec.get("seed", 0))),
        clips=clips(run),
        capped={t.rate.group: why for t in tasks if (why := capped_because(t.rate, gates.get(t.rate.group)))},
        other_stack=verdicts_on_other_stacks(gates, info),
        gate_source=run.gate_source,
        against_originals=against_sources(originals + answered),
        default_task=default_task(answered),
        switches=switch_rows(run.records, run.switch_gates),
        answered=rate(TaskKind.EXTENDED, answered, gates) if mixed else None,
        reworded=len(reworded),
        progress=run.progress,
    )


def answer_rests_on(record: EpisodeRecord, *, mixed: bool) -> bool:
    """Whether a run's answer rests on `record`: an extended episode under the given instruction, and in a run
    that `mixed` rewordings of a source's goal with tasks asking for another goal, one of the latter."""
    extended = record.kind == TaskKind.EXTENDED and record.condition == Condition.GIVEN
    return extended and not (mixed and record.dimension in SAME_GOAL_DIMENSIONS)


def shown_dimensions(runs: list[RunResults]) -> list[str]:
    """The paper's dimensions (always shown), then those beyond them that some run has episodes of:
    `langgap-beyond`'s, then other catalogs' (libero-pro's `task`, ...)."""
    return [*EXTENDED_DIMENSIONS, *(d for d in present_dimensions(runs) if d not in EXTENDED_DIMENSIONS)]


def present_dimensions(runs: list[RunResults]) -> list[str]:
    """The dimensions some run has episodes of (`dimension_order`)."""
    return dimension_order(r.group for run in runs for r in run.by_dimension if r.episodes)


def policy_identity(run: RunResults) -> tuple[str, ...]:
    """What makes two runs runs of one policy: its name, arguments and configuration hash (protocol card)."""
    return tuple(run.card[item] for item in ("policy", "policy arguments", "policy config hash"))


@dataclass(frozen=True)
class SideBySide:
    """Runs of one policy on several catalogs, side by side: one column group per catalog (its originals,
    each of its dimensions, all its extended tasks), one row per policy (a second run of a policy on a
    catalog it already has in a row starts another row)."""

    catalogs: list[str]  # in the order the runs were given
    groups: dict[str, list[str]]  # catalog -> `original`, its dimensions, `extended`
    rows: list[dict[str, RunResults]]  # catalog -> the row's run on it

    @staticmethod
    def rate(run: RunResults, group: str) -> Rate | None:
        """The run's rate of a column group's column (None: the run has no such tasks)."""
        if group in tuple(TaskKind):
            return run.source(group)
        return next((r for r in run.by_dimension if r.group == group), None)


def side_by_side(runs: list[RunResults]) -> SideBySide | None:
    """The runs side by side by catalog, when some policy was run on two or more catalogs (None otherwise:
    runs of different policies on different catalogs are compared as any runs are)."""
    by_policy: dict[tuple[str, ...], list[RunResults]] = defaultdict(list)
    for run in runs:
        by_policy[policy_identity(run)].append(run)
    if not any(len({run.card["catalog"] for run in group}) > 1 for group in by_policy.values()):
        return None
    rows: list[dict[str, RunResults]] = []
    for group in by_policy.values():
        mine: list[dict[str, RunResults]] = []  # this policy's rows: a run goes to the first without its catalog
        for run in group:
            catalog = run.card["catalog"]
            row = next((row for row in mine if catalog not in row), None)
            if row is None:
                mine.append(row := {})
            row[catalog] = run
        rows += mine
    catalogs = list(dict.fromkeys(run.card["catalog"] for run in runs))
    groups = {
        catalog: [
            TaskKind.ORIGINAL,
            *present_dimensions([r for r in runs if r.card["catalog"] == catalog]),
            TaskKind.EXTENDED,
        ]
        for catalog in catalogs
    }
    return SideBySide(catalogs, groups, rows)


@dataclass
class Summary:
    """The runs of one report (the first is the reference for comparisons) and their comparisons."""

    runs: list[RunResults]
    comparisons: list[PairedTest]  # the first run against each other run, on matched episodes
    mismatches: dict[str, list[str]]  # other run -> protocol items in which it differs from the first
    refused: bool = False  # paired tests left out because protocols differ (and no `allow_mismatch`)
    side_by_side: SideBySide | None = None  # one policy's runs on several catalogs (`side_by_side`)

    @property
    def privileges(self) -> set[Privilege]:
        """The privileges the runs' policies had (`Privilege.NONE` included when one had none)."""
        return {run.privilege for run in self.runs}


def protocol_differences(a: RunResults, b: RunResults) -> list[str]:
    """The protocol items in which two runs differ (runs are paired episode by episode only when none); their
    physics as `langgap.stack.stack_differences` compares stacks (an entry one run predates is not a difference)."""

    def differs(item: str) -> bool:
        if item == "physics":
            return stacks_differ(a.spec.get("physics", {}), b.spec.get("physics", {}))
        return a.card[item] != b.card[item]

    return [item for item in PROTOCOL_ITEMS if differs(item)]


def same_spec(a: RunResults, b: RunResults) -> bool:
    """Whether two runs are one run spec run twice — the same policy and arguments, catalog, tasks, init states,
    seeds, conditions, style and physics (`langgap.engine.spec.spec_differences`) and the same policy
    configuration (its hash): their paired outcomes are then a test-retest."""
    return not spec_differences(a.spec, b.spec) and a.card["policy config hash"] == b.card["policy config hash"]


BLIND_POLICY = "blind"  # the reference that does the scene's original task whatever it is asked


def keyed(run: Run, member: Callable[[EpisodeRecord], bool] = lambda r: True) -> dict[tuple, EpisodeRecord]:
    """A run's episodes (those `member` keeps) by key, for pairing with another run's."""
    return {r.key: r for r in run.records if member(r)}


def summarize(runs: list[Run], *, allow_mismatch: bool = False) -> Summary:
    """Aggregate runs once, for every table and format. Runs whose protocols differ from the first
    run's are not paired episode by episode unless `allow_mismatch` is given. Each run is paired with the
    first compared `blind` run whose protocol (its catalog included) equals its own, or with `allow_mismatch`
    the first `blind` run. Runs of one policy on several catalogs are also put side by side (`side_by_side`)."""
    for run in runs:
        if not run.records:
            raise LangGapError(f"nothing to report for {run.path}: {run.progress}")
    results_ = [results(run) for run in runs]
    first = results_[0]
    mismatches = {other.name: protocol_differences(first, other) for other in results_[1:]}
    mismatches = {name: items for name, items in mismatches.items() if items}
    refused = bool(mismatches) and not allow_mismatch
    comparisons = []
    if not refused:
        tests = (
            paired(f"{runs[0].name} vs {run.name}", keyed(runs[0]), keyed(run), retest=same_spec(first, other))
            for run, other in zip(runs[1:], results_[1:], strict=True)
        )
        comparisons = [t for t in tests if t is not None]
    blinds = [
        (run, result) for run, result in zip(runs, results_, strict=True) if run.spec.get("policy") == BLIND_POLICY
    ]

    for run, result in zip(runs, results_, strict=True):
        extended = functools.partial(answer_rests_on, mixed=result.mixed)

        others = [(blind, blind_result) for blind, blind_result in blinds if blind is not run]
        # The blind run with the same protocol (on the same catalog, when runs of several catalogs are given).
        matched = (blind for blind, blind_result in others if not protocol_differences(blind_result, result))
        blind = next(matched, others[0][0] if others and allow_mismatch else None)
        if blind is not None:
            result.against_blind = paired(f"blind vs {TaskKind.EXTENDED}", keyed(blind, extended), keyed(run, extended))
    return Summary(results_, comparisons, mismatches, refused, side_by_side(results_))
