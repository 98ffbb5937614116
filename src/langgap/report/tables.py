"""The paper's table layouts (and LangGap's diagnoses), built from a `Summary` as neutral tables: each the
tables of one section of the report (`langgap.report.sections`), titled by that section's heading."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from langgap.records import JUDGED_OUTCOMES, Privilege
from langgap.report.answer import percent
from langgap.report.card import CARD_ITEMS
from langgap.report.labels import DIMENSION_LABEL, EXTENDED_DIMENSIONS, SPLIT_LABEL, SUITE_LABEL, SUITE_ORDER, label
from langgap.report.published import Published
from langgap.report.stats import PairedTest, Rate
from langgap.report.summary import (
    PRIVILEGE_MARK,
    SWITCH_CLASSES,
    RunResults,
    SideBySide,
    Summary,
    TaskRow,
    shown_dimensions,
)
from langgap.vocabulary import (
    CEILING_TARGET,
    FEASIBLE_RATE,
    SWITCH,
    SWITCH_RATE,
    Condition,
    Dimension,
    Outcome,
    TaskKind,
    Verdict,
)

# A section's heading with its fields filled (`Section.title`): `run=` the run's label, and whatever else it names.
Title = Callable[..., str]

SOURCE_LABEL = {TaskKind.ORIGINAL: "Original (LIBERO)", TaskKind.EXTENDED: "Extended (LangGap)", "total": "Total"}
OUTCOME_LABEL = {
    Outcome.SUCCESS: "Success %",
    Outcome.PERSISTED: "Persisted %",
    Outcome.WRONG_ORDER: "Wrong order %",
    Outcome.DID_SOURCE_TASK: "Did source task %",
    Outcome.DID_OTHER_TASK: "Did other task %",
    Outcome.NO_GOAL_REACHED: "No goal %",
    Outcome.POLICY_ERROR: "Policy error %",
}
OUTCOME_NAME = {o: o.replace("_", " ") for o in Outcome}
OUTCOME_GROUP_LABEL = {**DIMENSION_LABEL, TaskKind.EXTENDED: "All extended"}
PRIVILEGE_NOTES = {
    Privilege.GOAL: "† told the goal (task id and goal; shown the simulator state too): a scripted reference, "
    "not a policy under test",
    Privilege.STATE: "‡ reads simulator state (object poses, contacts, joints), never told the goal: a learned "
    "policy under test, with more than a camera shows",
}
PUBLISHED_NOTE = "Rows marked published are the LangGap paper's figures as printed (20 episodes per task), not re-run."
CEILING_NOTE = (
    "Oracle % is the scripted oracle's success on the same tasks and init states (the feasibility verdicts "
    "stored with the run when it was created); Relative % is the rate as a share of it."
)
# The notes are plain text: the terminal shows them as they are, so they quote no command in Markdown's backticks.
SELECTION_NOTE = (
    f"Tasks: --tasks feasible (the default) runs the tasks the feasibility gate found {Verdict.DOABLE}; --tasks all "
    f"adds the others ({Verdict.UNPROVEN}, {Verdict.INFEASIBLE} or {Verdict.UNSETTLED})."
)
CAPPED_NOTE = (
    f"⚠ marks a task the oracle does on fewer than {percent(CEILING_TARGET)} of these init states, or one the gate "
    f"found {Verdict.INFEASIBLE} (its proof and assumptions: langgap tasks show ID) or {Verdict.UNSETTLED} (its "
    f"starts do not come to rest). The gate admits a task as {Verdict.DOABLE} when the oracle, with searched "
    f"demonstrations, does at least {percent(FEASIBLE_RATE)} of its init states, so a {Verdict.DOABLE} task can "
    f"carry ⚠ too; one the oracle does not do, with no proof that a policy cannot, is {Verdict.UNPROVEN}."
)

STACK_NOTE = (
    "≠ marks a task whose feasibility verdict (its Oracle % and ⚠) was made on another physics stack than these "
    "episodes: other package versions, start or image conventions, stepping or seed scheme "
    "(langgap report --format json: other_stack_tasks; langgap tasks show ID)."
)


def selection_text(run: RunResults) -> str:
    """The run's task selection, as its report's header states it."""
    selection = run.spec.get("selection")
    if selection in (None, "feasible"):
        chosen = "feasible (the default)"
    else:
        chosen = f"a list of {len(selection.split(','))}" if "," in selection else repr(selection)
    capped = "; ".join(f"{task} ({why})" for task, why in sorted(run.capped.items()))
    return f"tasks: {chosen}" + (f"; ⚠ {capped}" if capped else "") + f"; {run.gate_source}"


def notes(summary: Summary, published: Published | None, *, ceiling: bool = True) -> list[str]:
    """The notes printed with the tables (`ceiling`: with those that explain the task selection, the oracle
    columns and ⚠, the last only when a task is marked ⚠)."""
    shown = [
        (SELECTION_NOTE, ceiling),
        (CAPPED_NOTE, ceiling and any(run.capped for run in summary.runs)),
        (CEILING_NOTE, ceiling),
        (STACK_NOTE, ceiling and any(run.other_stack for run in summary.runs)),
        *((note, privilege in summary.privileges) for privilege, note in PRIVILEGE_NOTES.items()),
        (PUBLISHED_NOTE, published is not None),
    ]
    return [note for note, show in shown if show]


@dataclass
class Table:
    """A titled grid of strings; formats decide how it looks.

    `filters` names the categorical columns a page can filter on; `kind` tells a page what the grid
    is: a `table`, a `heatmap` (counts, shaded by their share of the row) or a `gallery` (filmed
    episodes, the last column the clip's file). `column_groups` spans the headers from left to right
    ((name, number of columns); an empty name: no group); a grouped header reads `name: column`, which
    formats that can span a group over its columns (LaTeX) shorten to `column`. `headings` are the indices
    of the rows that head the rows below them: their first cell names the group, the others are empty; each
    format marks them its own way (Markdown in italics, a page as a heading cell across the table).
    """

    title: str
    headers: list[str]
    rows: list[list[str]]
    filters: tuple[str, ...] = ()
    kind: str = "table"
    column_groups: tuple[tuple[str, int], ...] = ()
    headings: frozenset[int] = frozenset()


def pct(x: float) -> str:
    return f"{100 * x:.1f}"


def ci(r: Rate) -> str:
    low, high = r.ci
    return f"[{pct(low)}, {pct(high)}]"


def rate_cell(r: Rate | None) -> str:
    if r is None or r.episodes == 0:
        return "–"
    return f"{pct(r.rate)} {ci(r)}" + (f" ({r.gaps} gaps)" if r.gaps else "")


_RATE_HEADERS = ["Category", "Tasks", "Episodes", "Success", "Rate %", "95% CI", "Gaps", "Oracle %", "Relative %"]


def ceiling_cells(r: Rate) -> list[str]:
    """The oracle's rate on the same tasks and init states, and the rate relative to it."""
    oracle, relative = r.oracle_rate, r.relative
    return ["–" if oracle is None else pct(oracle), "–" if relative is None else pct(relative)]


def _rate_rows(rates: list[Rate], names: dict[str, str], *, counted_gaps: bool = True) -> list[list[str]]:
    """One row per rate (`counted_gaps` False: figures that never counted gaps, whose Gaps cell is `–`)."""
    return [
        [
            label(names, r.group),
            str(r.tasks),
            str(r.episodes),
            str(r.successes),
            pct(r.rate),
            ci(r),
            str(r.gaps) if counted_gaps else "–",
            *ceiling_cells(r),
        ]
        for r in rates
    ]


SUITE_KIND_LABEL = {f"{suite}/{kind}": f"{SUITE_LABEL[suite]}, {kind}" for suite in SUITE_ORDER for kind in TaskKind}


def source_table(run: RunResults, title: Title) -> Table:
    """Success by data source, by suite and by perturbation dimension, each beside the oracle's ceiling (the
    paper's Table II)."""
    groups = [
        ("By data source", _rate_rows(run.by_source, SOURCE_LABEL)),
        ("By suite", _rate_rows(run.by_suite, SUITE_KIND_LABEL)),
        ("By perturbation dimension", _rate_rows(run.by_dimension, DIMENSION_LABEL)),
    ]
    rows: list[list[str]] = []
    headings = set()
    for heading, group in groups:
        headings.add(len(rows))
        rows += [[heading, *[""] * (len(_RATE_HEADERS) - 1)], *group]
    return Table(title(run=run.label), _RATE_HEADERS, rows, headings=frozenset(headings))


def _published_cells(values: dict[str, float], keys: list[str]) -> list[str]:
    return [f"{values[k]:.1f}" if k in values else "–" for k in keys]


def suite_table(summary: Summary, published: Published | None, title: Title) -> Table:
    """Success per suite, original vs extended, one row per run (libero_10 has no extended tasks; the paper's
    Table VI); the paper's rows below them when `published` is given."""
    keys = [f"{s}/{k}" for s in SUITE_ORDER for k in TaskKind if (s, k) != ("libero_10", TaskKind.EXTENDED)]
    headers = ["Method"]
    headers += [f"{SUITE_LABEL[k.split('/')[0]]} {'Orig' if k.endswith(TaskKind.ORIGINAL) else 'Ext'}" for k in keys]
    rows = []
    for run in summary.runs:
        by_key = {r.group: r for r in run.by_suite}
        cells = [rate_cell(by_key.get(k)) for k in keys]
        rows.append([run.label, *cells, *(rate_cell(run.source(kind)) for kind in TaskKind)])
    for row in published.suites if published else []:
        cells = _published_cells(row.values, [*keys, *TaskKind])
        rows.append([published.label(row.method, "Table VI"), *cells])
    return Table(title(), [*headers, "Total Orig", "Total Ext"], rows)


def dimension_table(summary: Summary, published: Published | None, title: Title) -> Table:
    """Success on extended tasks by dimension, one row per run (the paper's Table VII); the paper's rows below
    when `published` is given."""
    headers = ["Method", *(DIMENSION_LABEL[d] for d in EXTENDED_DIMENSIONS), "Total"]
    rows = []
    for run in summary.runs:
        by_dim = {r.group: r for r in run.by_dimension}
        cells = [rate_cell(r) + f" ({r.tasks})" if (r := by_dim.get(d)) else "–" for d in EXTENDED_DIMENSIONS]
        total = run.source(TaskKind.EXTENDED)
        rows.append([run.label, *cells, rate_cell(total) + f" ({total.tasks})"])
    for row in published.dimensions if published else []:
        cells = _published_cells(row.values, [*EXTENDED_DIMENSIONS, TaskKind.EXTENDED])
        rows.append([published.label(row.method, "Table VII"), *cells])
    return Table(title(), headers, rows)


def beyond_table(summary: Summary, published: Published | None, title: Title) -> Table | None:
    """`dimension_table`'s form for the dimensions beyond the paper's that the runs have (`langgap-beyond`'s ordering,
    negation, paraphrase, attribute reference; other catalogs' such as libero-pro's task and language); None
    when they have none."""
    beyond = shown_dimensions(summary.runs)[len(EXTENDED_DIMENSIONS) :]
    if not beyond:
        return None
    rows = []
    for run in summary.runs:
        by_dim = {r.group: r for r in run.by_dimension}
        rows.append([run.label, *(rate_cell(r) + f" ({r.tasks})" if (r := by_dim.get(d)) else "–" for d in beyond)])
    headers = ["Method", *(label(DIMENSION_LABEL, d) for d in beyond)]
    return Table(title(), headers, rows)


def _side_by_side_label(row: dict[str, RunResults]) -> str:
    """A row's policy, marked as its runs are (`RunResults.label`), and the runs' directories."""
    first = next(iter(row.values()))
    mark = PRIVILEGE_MARK.get(first.privilege)
    directories = ", ".join(run.path.name for run in row.values())
    return f"{first.card['policy']}{f' {mark}' if mark else ''} ({directories})"


def side_by_side_table(summary: Summary, published: Published | None, title: Title) -> Table | None:
    """One policy's runs on several catalogs: a column group per catalog (its originals, each of its
    dimensions, all its extended tasks), success % with its 95% interval; None unless a policy was run
    on two or more catalogs (`summary.side_by_side`)."""
    side: SideBySide | None = summary.side_by_side
    if side is None:
        return None
    names = {**DIMENSION_LABEL, TaskKind.EXTENDED: "All extended"}
    headers = ["Policy", *(f"{c}: {label(names, g)}" for c in side.catalogs for g in side.groups[c])]
    groups = (("", 1), *((c, len(side.groups[c])) for c in side.catalogs))
    rows = []
    for row in side.rows:
        cells = [rate_cell(side.rate(row[c], g)) if c in row else "–" for c in side.catalogs for g in side.groups[c]]
        rows.append([_side_by_side_label(row), *cells])
    return Table(title(), headers, rows, column_groups=groups)


def _count_cell(successes: int, episodes: int) -> str:
    return f"{successes}/{episodes} ({pct(successes / episodes)}%)" if episodes else "–"


def _tasks_text(count: int) -> str:
    return "1 task" if count == 1 else f"{count} tasks"


def _covered_cell(mine: list[Rate], group_tasks: int) -> str:
    """A run's count on the tasks of a published group it ran, and how many of the group's tasks those are."""
    episodes = sum(r.episodes for r in mine)
    if not episodes:
        return "–"
    ran = len({r.group for r in mine if r.episodes})
    covered = f"the same {_tasks_text(group_tasks)}" if ran == group_tasks else f"{ran} of the {group_tasks} tasks"
    return f"{_count_cell(sum(r.successes for r in mine), episodes)} on {covered}"


def published_appendix_table(summary: Summary, published: Published | None, title: Title) -> Table | None:
    """The paper's per-task appendix for π0.5, beside each run's result on the group's tasks it ran; each cell
    says how many of the group's tasks it counts, since a run may cover a group in part (None: the published
    figures are left out)."""
    if published is None:
        return None
    rows = []
    for group in published.appendix:
        row = [label(DIMENSION_LABEL, group.dimension), group.label]
        counted = group.published
        row.append(f"{_count_cell(counted.successes, counted.episodes)} on {_tasks_text(counted.tasks)}")
        for run in summary.runs:
            row.append(_covered_cell([t.rate for t in run.tasks if t.rate.group in group.task_ids], counted.tasks))
        rows.append(row)
    method = published.label(published.appendix_method, "appendix")
    headers = ["Dimension", "Tasks", method, *(run.label for run in summary.runs)]
    return Table(title(method=published.appendix_method), headers, rows)


def published_diagnostic_table(summary: Summary, published: Published | None, title: Title) -> Table | None:
    """The paper's Table II as published (its episode counts, with the Wilson intervals they imply; None: the
    published figures are left out)."""
    if published is None:
        return None
    names = {**DIMENSION_LABEL, **SOURCE_LABEL}
    rows = _rate_rows(published.diagnostic, names, counted_gaps=False)  # the paper reports no gaps
    return Table(title(method=published.diagnostic_method), _RATE_HEADERS, rows)


def split_table(run: RunResults, title: Title) -> Table:
    """Success on the tasks a policy may have trained on against the held-out ones."""
    return Table(title(run=run.label), _RATE_HEADERS, _rate_rows(run.by_split, SPLIT_LABEL))


def mde_table(run: RunResults, title: Title) -> Table:
    """Per dimension: the smallest change in success rate another run of this size would detect."""
    rates = [run.source(TaskKind.ORIGINAL), *run.by_dimension, run.source(TaskKind.EXTENDED)]
    names = {**DIMENSION_LABEL, **SOURCE_LABEL}
    rows = [[label(names, r.group), str(r.episodes), pct(r.rate), pct(r.mde)] for r in rates if r.episodes]
    return Table(title(run=run.label), ["Category", "Episodes", "Rate %", "MDE (points)"], rows)


def spread_table(run: RunResults, title: Title) -> Table | None:
    """Between-seed spread: each repeat's rate beside the pooled rate and its episode interval."""
    if not run.spread:
        return None
    pooled = {r.group: r for r in [*run.by_source, *run.by_dimension]}
    names = {**DIMENSION_LABEL, **SOURCE_LABEL}
    rows = [
        [
            label(names, row.group),
            ", ".join(pct(r.rate) for r in row.rates),
            pct(row.mean),
            pct(row.std),
            rate_cell(pooled.get(row.group)),
        ]
        for row in run.spread
    ]
    headers = ["Category", "Rate % per seed", "Mean %", "Std across seeds (points)", "Pooled %, 95% CI"]
    return Table(title(run=run.label), headers, rows)


def outcome_table(run: RunResults, title: Title) -> Table:
    """What the policy did instead, per dimension (`did source task` is the default-task rate). `wrong order`
    is shown for runs with ordered tasks (or any episode in that outcome); `persisted` never (the table holds
    `given` episodes: only a switch's persist, in `switch_table`)."""
    ordered = any(o.group == Dimension.ORDERING or o.shares[Outcome.WRONG_ORDER] for o in run.outcomes)
    hidden = {Outcome.PERSISTED, *(() if ordered else (Outcome.WRONG_ORDER,))}
    shown = [o for o in JUDGED_OUTCOMES if o not in hidden]
    headers = ["Dimension", "Episodes", *(OUTCOME_LABEL[o] for o in shown), "Gaps"]
    rows = [
        [
            label(OUTCOME_GROUP_LABEL, o.group),
            str(o.episodes),
            *(pct(o.shares[outcome]) for outcome in shown),
            str(o.gaps),
        ]
        for o in run.outcomes
    ]
    return Table(title(run=run.label), headers, rows)


CAPPED_MARK = "⚠"
OTHER_STACK_MARK = "≠"


def task_label(run: RunResults, task_id: str) -> str:
    """A task's id, marked ⚠ when the oracle does not do it at the target rate (unproven) or it is proven
    infeasible (`GateResult.capped_because`), and ≠ when its verdict was made on another physics stack than
    the run's episodes (`STACK_NOTE`)."""
    marks = [mark for mark, on in ((CAPPED_MARK, run.capped), (OTHER_STACK_MARK, run.other_stack)) if task_id in on]
    return " ".join([task_id, *marks])


def _instead_cells(t: TaskRow) -> list[str]:
    if (instead := t.instead) is None:
        return ["–", ""]
    outcome, count = instead
    return [OUTCOME_NAME[outcome], str(count)]


def task_table(run: RunResults, title: Title) -> Table:
    """The appendix: every task, grouped by dimension, with what it most often ended in instead."""
    rows = [
        [
            label(SUITE_LABEL, t.suite),
            label(DIMENSION_LABEL, t.dimension),
            label(SPLIT_LABEL, t.split),
            task_label(run, t.rate.group),
            t.instruction,
            f"{t.rate.successes}/{t.rate.episodes}",
            pct(t.rate.rate),
            ci(t.rate),
            str(t.rate.gaps),
            *ceiling_cells(t.rate),
            *_instead_cells(t),
        ]
        for t in run.tasks
    ]
    headers = ["Suite", "Dimension", "Split", "Task", "Instruction", "Success", "Rate %", "95% CI", "Gaps"]
    headers += ["Oracle %", "Relative %", "Mostly did instead", "Episodes"]
    filters = ("Suite", "Dimension", "Split", "Mostly did instead")
    return Table(title(run=run.label), headers, rows, filters)


def video_table(run: RunResults, title: Title) -> Table | None:
    """The filmed episodes, `did source task` first, with the instruction each was given."""
    if not run.clips:
        return None
    rows = [
        [
            OUTCOME_NAME[c.outcome],
            task_label(run, c.task_id),
            c.condition,
            str(c.init_index),
            str(c.seed),
            c.instruction,
            str(c.path),
        ]
        for c in run.clips
    ]
    headers = ["Outcome", "Task", "Condition", "Init", "Seed", "Instruction", "Video"]
    return Table(title(run=run.label), headers, rows, kind="gallery")  # grouped by outcome on a page


def _paired_cells(t: PairedTest) -> list[str]:
    return [t.name, str(t.pairs), pct(t.rate_a), pct(t.rate_b), str(t.only_a), str(t.only_b), f"{t.p_value:.3g}"]


def _paired_table(title: str, tests: list[PairedTest], a: str, b: str, last: tuple[str, Callable]) -> Table | None:
    """`run`'s paired tests (McNemar) as a table: `a` against `b` episode by episode, then one column
    `last` (its header, and its cell from a test); None without tests."""
    if not tests:
        return None
    header, cell = last
    headers = ["Comparison", "Pairs", f"{a} %", f"{b} %", f"Only {a.lower()}", f"Only {b.lower()}", "p", header]
    rows = [[*_paired_cells(t), cell(t)] for t in tests]
    return Table(title, headers, rows)


def wording_table(run: RunResults, title: Title) -> Table | None:
    """Paraphrases and attribute references against their sources' original sentences, episode by episode."""
    difference = ("Difference (points)", lambda t: f"{100 * (t.successes_b - t.successes_a) / t.pairs:+.1f}")
    return _paired_table(title(run=run.label), run.wording, TaskKind.ORIGINAL.capitalize(), "Reworded", difference)


def condition_table(run: RunResults, title: Title) -> Table | None:
    """Language conditions against `given`, episode by episode."""
    changed = ("Behaviour changed %", lambda t: pct(t.changed_behaviour))
    return _paired_table(title(run=run.label), run.conditions, Condition.GIVEN.capitalize(), "Condition", changed)


def switch_table(run: RunResults, title: Title) -> Table | None:
    """What the policy did after its instruction changed at step K (`switch:K`), per K and dimension, each
    share with its 95% interval; None for a run without a switch. Paired against `given` in the conditions.
    ⚠ counts the group's tasks the switch gate has not accepted at K (unproven there), named in the title."""
    if not run.switches:
        return None
    headers = ["K", "Dimension", "Episodes", *(f"{name.capitalize()} %, 95% CI" for name in SWITCH_CLASSES)]
    headers += ["Gaps", f"{CAPPED_MARK} {Verdict.UNPROVEN} at K"]
    rows = [
        [
            str(row.k),
            label(OUTCOME_GROUP_LABEL, row.group),
            str(row.episodes),
            *(f"{pct(r.rate)} {ci(r)}" for r in row.classes.values()),
            str(row.gaps),
            f"{len(row.unproven)} of {row.tasks}" if row.unproven else "",
        ]
        for row in run.switches
    ]
    heading = title(run=run.label)
    unproven = sorted({(row.k, task) for row in run.switches for task in row.unproven})
    if unproven:
        named = ", ".join(f"{task} at K={k}" for k, task in unproven[:SHOWN_UNPROVEN])
        more = len(unproven) - SHOWN_UNPROVEN
        heading += (
            f"; {CAPPED_MARK} the switch gate (oracle ≥ {percent(SWITCH_RATE)} under {SWITCH}K) has not "
            f"accepted {named}"
        )
        heading += f" and {more} more (the JSON report's switches section lists them)" if more > 0 else ""
    return Table(heading, headers, rows)


SHOWN_UNPROVEN = 6  # task and K pairs a switch table's title names


def mismatch_table(summary: Summary, published: Published | None, title: Title) -> Table | None:
    """The runs not compared with the first because their protocols differ (None: none was refused)."""
    if not summary.refused:
        return None
    rows = [[name, ", ".join(items)] for name, items in summary.mismatches.items()]
    return Table(title(), ["Run", "Differs in"], rows)


def comparison_table(summary: Summary, published: Published | None, title: Title) -> Table | None:
    """The first run against each other run on matched episodes (None: none was paired)."""
    if not summary.comparisons:
        return None
    headers = ["Comparison", "Pairs", "First %", "Second %", "Only first", "Only second", "p"]
    heading = title()
    if summary.mismatches:
        heading += " — protocols differ: " + "; ".join(f"{n}: {', '.join(i)}" for n, i in summary.mismatches.items())
    rows = [_paired_cells(t) for t in summary.comparisons]
    if any(t.retest for t in summary.comparisons):
        # Agreement and κ are a test-retest: shown for runs of one spec only, blank beside any other run.
        heading += "; Agree % and κ: one run spec run twice (test-retest)"
        headers += ["Agree %", "κ"]
        for row, t in zip(rows, summary.comparisons, strict=True):
            row += [pct(t.agreement), "–" if t.kappa is None else f"{t.kappa:.2f}"] if t.retest else ["", ""]
    return Table(heading, headers, rows)


def protocol_table(summary: Summary, published: Published | None, title: Title) -> Table:
    """The protocol card: what determines each run's numbers."""
    rows = [[item, *(run.card[item] for run in summary.runs)] for item in CARD_ITEMS]
    return Table(title(), ["", *(run.label for run in summary.runs)], rows)


def confusion_tables(run: RunResults, title: Title) -> list[Table]:
    """Per scene with two or more tasks: intended × achieved episode counts."""
    tables = []
    for rows in sorted(run.confusion.values(), key=lambda rows: sorted(rows)[0]):
        intended = sorted(rows)
        if len(intended) < 2:
            continue
        columns = intended + sorted({a for row in rows.values() for a in row} - set(intended))
        body = [[task_label(run, task)] + [str(rows[task].get(c, 0) or "") for c in columns] for task in intended]
        suite, scene = intended[0].split("/")[:2]
        tables.append(
            Table(
                title(run=run.label, scene=f"{suite}/{scene}"),
                ["intended \\ achieved", *(task_label(run, c) for c in columns)],
                body,
                kind="heatmap",
            )
        )
    return tables
