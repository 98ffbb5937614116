"""The paper's tables (and LangGap's diagnoses) from stored runs, as Markdown, CSV, LaTeX or JSON."""

from __future__ import annotations

import csv
import io
import json
from dataclasses import dataclass
from pathlib import Path

from langgap.records import EpisodeRecord
from langgap.report import aggregate as agg
from langgap.store import RunStore


@dataclass
class Run:
    name: str
    path: Path
    config: dict
    records: list[EpisodeRecord]


def load_runs(paths: list[str | Path]) -> list[Run]:
    """Read runs from their stores; the name shown is the policy plus the directory name."""
    runs = []
    for path in paths:
        with RunStore.open(path) as store:
            config, records = store.meta("config") or {}, store.records()
        runs.append(
            Run(
                name=f"{config.get('policy', '?')} ({Path(path).name})", path=Path(path), config=config, records=records
            )
        )
    return runs


@dataclass
class Table:
    title: str
    headers: list[str]
    rows: list[list[str]]


def _pct(x: float) -> str:
    return f"{100 * x:.1f}"


def _ci(r: agg.Rate) -> str:
    return f"[{_pct(r.ci_low)}, {_pct(r.ci_high)}]"


def _rate_cell(r: agg.Rate | None) -> str:
    if r is None or r.episodes == 0:
        return "–"
    return f"{_pct(r.rate)} {_ci(r)}" + (f" ({r.gaps} gaps)" if r.gaps else "")


def _rate_rows(rates: list[agg.Rate], label=lambda g: g) -> list[list[str]]:
    return [
        [label(r.group), str(r.tasks), str(r.episodes), str(r.successes), _pct(r.rate), _ci(r), str(r.gaps)]
        for r in rates
    ]


_RATE_HEADERS = ["Category", "Tasks", "Episodes", "Success", "Rate %", "95% CI", "Gaps"]


def summary_table(run: Run) -> Table:
    """Table II: by data source and by perturbation dimension."""
    rows = [["*By data source*", "", "", "", "", "", ""]] + _rate_rows(agg.by_source(run.records))
    rows += [["*By perturbation dimension*", "", "", "", "", "", ""]]
    rows += _rate_rows(agg.by_dimension(run.records), lambda g: agg.DIMENSION_LABEL[g])
    return Table(f"Table II — {run.name}: by data source and dimension", _RATE_HEADERS, rows)


def suite_table(runs: list[Run]) -> Table:
    """Table VI: per suite, original vs extended, one row per run."""
    headers = ["Method"]
    keys = []
    for suite in agg.SUITE_ORDER:
        for kind in ("original", "extended"):
            if suite == "libero_10" and kind == "extended":
                continue
            headers.append(f"{agg.SUITE_LABEL[suite]} {'Orig' if kind == 'original' else 'Ext'}")
            keys.append(f"{suite}/{kind}")
    headers += ["Total Orig", "Total Ext"]
    rows = []
    for run in runs:
        by_key = {r.group: r for r in agg.by_suite_and_kind(run.records)}
        source = {r.group: r for r in agg.by_source(run.records)}
        rows.append(
            [run.name]
            + [_rate_cell(by_key.get(k)) for k in keys]
            + [_rate_cell(source["Original (LIBERO)"]), _rate_cell(source["Extended (LangGap)"])]
        )
    return Table("Table VI — per suite (success %, 95% CI)", headers, rows)


def dimension_table(runs: list[Run]) -> Table:
    """Table VII: extended tasks by dimension, one row per run."""
    headers = ["Method"] + [agg.DIMENSION_LABEL[d] for d in agg.DIMENSION_ORDER] + ["Total"]
    rows = []
    for run in runs:
        by_dim = {r.group: r for r in agg.by_dimension(run.records)}
        total = agg.by_source(run.records)[1]
        cells = []
        for d in agg.DIMENSION_ORDER:
            r = by_dim.get(d)
            cells.append(_rate_cell(r) + (f" ({r.tasks})" if r else ""))
        rows.append([run.name, *cells, _rate_cell(total) + f" ({total.tasks})"])
    return Table("Table VII — extended tasks by dimension (success %, 95% CI, (tasks))", headers, rows)


def split_table(run: Run) -> Table:
    labels = {"original": "Original tasks", "train": "Extended, training split", "heldout": "Extended, held-out"}
    return Table(
        f"Training vs held-out — {run.name}",
        _RATE_HEADERS,
        _rate_rows(agg.by_split(run.records), lambda g: labels.get(g, g)),
    )


def outcome_table(run: Run) -> Table:
    headers = [
        "Dimension",
        "Episodes",
        "Success %",
        "Did source task %",
        "Did other task %",
        "No goal %",
        "Policy error %",
        "Gaps",
    ]
    rows = [
        [
            o.group,
            str(o.episodes),
            _pct(o.success),
            _pct(o.did_source_task),
            _pct(o.did_other_task),
            _pct(o.no_goal_reached),
            _pct(o.policy_error),
            str(o.gaps),
        ]
        for o in agg.outcomes_by_dimension(run.records)
    ]
    return Table(f"What the policy did instead — {run.name} (did source task = default-task rate)", headers, rows)


def task_table(run: Run) -> Table:
    """The appendix: every task, grouped by dimension."""
    meta = {r.task_id: r for r in run.records}
    rates = sorted(
        agg.by_task(run.records),
        key=lambda r: (["original", *agg.DIMENSION_ORDER].index(meta[r.group].dimension), r.group),
    )
    rows = [
        [
            agg.DIMENSION_LABEL[meta[r.group].dimension],
            r.group,
            meta[r.group].instruction,
            f"{r.successes}/{r.episodes}",
            _pct(r.rate),
            _ci(r),
            str(r.gaps),
        ]
        for r in rates
    ]
    return Table(
        f"Per task — {run.name}", ["Dimension", "Task", "Instruction", "Success", "Rate %", "95% CI", "Gaps"], rows
    )


def condition_table(run: Run) -> Table | None:
    tests = agg.condition_tests(run.records)
    if not tests:
        return None
    rows = [
        [
            t.name,
            str(t.pairs),
            _pct(t.rate_a),
            _pct(t.rate_b),
            str(t.only_a),
            str(t.only_b),
            f"{t.p_value:.3g}",
            _pct(t.changed_behaviour),
        ]
        for t in tests
    ]
    return Table(
        f"Language conditions, paired episode by episode (McNemar) — {run.name}",
        ["Comparison", "Pairs", "Given %", "Condition %", "Only given", "Only condition", "p", "Behaviour changed %"],
        rows,
    )


def comparison_table(runs: list[Run]) -> Table | None:
    if len(runs) < 2:
        return None
    rows = []
    for other in runs[1:]:
        test = agg.run_comparison(runs[0].name, runs[0].records, other.name, other.records)
        if test is not None:
            rows.append(
                [
                    test.name,
                    str(test.pairs),
                    _pct(test.rate_a),
                    _pct(test.rate_b),
                    str(test.only_a),
                    str(test.only_b),
                    f"{test.p_value:.3g}",
                ]
            )
    return Table(
        "Runs compared on matched episodes (McNemar)",
        ["Comparison", "Pairs", "First %", "Second %", "Only first", "Only second", "p"],
        rows,
    )


def confusion_tables(run: Run) -> list[Table]:
    tables = []
    for rows in sorted(agg.confusion(run.records).values(), key=lambda rows: sorted(rows)[0]):
        intended = sorted(rows)
        if len(intended) < 2:
            continue
        columns = intended + sorted({a for row in rows.values() for a in row} - set(intended))
        body = [[task] + [str(rows[task].get(c, 0) or "") for c in columns] for task in intended]
        tables.append(
            Table(
                f"Confusion (intended × achieved) — scene of {intended[0].split('/')[1]} ({intended[0].split('/')[0]})",
                ["intended \\ achieved", *columns],
                body,
            )
        )
    return tables


def tables_for(runs: list[Run], *, per_task: bool = True, confusions: bool = True) -> list[Table]:
    tables = []
    for run in runs:
        tables += [summary_table(run), outcome_table(run), split_table(run)]
        if (conditions := condition_table(run)) is not None:
            tables.append(conditions)
    tables += [suite_table(runs), dimension_table(runs)]
    if (comparison := comparison_table(runs)) is not None:
        tables.append(comparison)
    for run in runs:
        if per_task:
            tables.append(task_table(run))
        if confusions:
            tables += confusion_tables(run)
    return tables


# -- formats --------------------------------------------------------------------------------------


def _markdown(table: Table) -> str:
    lines = [
        f"### {table.title}",
        "",
        "| " + " | ".join(table.headers) + " |",
        "|" + "|".join("---" for _ in table.headers) + "|",
    ]
    lines += ["| " + " | ".join(cell.replace("|", "\\|") for cell in row) + " |" for row in table.rows]
    return "\n".join(lines) + "\n"


def _latex(table: Table) -> str:
    def esc(text: str) -> str:
        for a, b in (
            ("\\", r"\textbackslash{}"),
            ("%", r"\%"),
            ("&", r"\&"),
            ("_", r"\_"),
            ("#", r"\#"),
            ("*", ""),
            ("×", r"$\times$"),
        ):
            text = text.replace(a, b)
        return text

    lines = [
        r"\begin{table}[ht]",
        r"\centering",
        rf"\caption{{{esc(table.title)}}}",
        r"\small",
        r"\begin{tabular}{l" + "c" * (len(table.headers) - 1) + "}",
        r"\toprule",
        " & ".join(esc(h) for h in table.headers) + r" \\",
        r"\midrule",
    ]
    lines += [" & ".join(esc(c) for c in row) + r" \\" for row in table.rows]
    lines += [r"\bottomrule", r"\end{tabular}", r"\end{table}"]
    return "\n".join(lines) + "\n"


def _json(runs: list[Run]) -> str:
    out: dict = {
        "runs": [],
        "per_task": [],
        "per_dimension": [],
        "per_suite": [],
        "per_split": [],
        "by_source": [],
        "outcomes": [],
        "conditions": [],
        "confusion": {},
        "comparisons": [],
    }
    for run in runs:
        gaps = sum(r.status == "gap" for r in run.records)
        out["runs"].append(
            {"run": run.name, "path": str(run.path), "episodes": len(run.records), "gaps": gaps, "config": run.config}
        )
        sections = (
            ("per_task", agg.by_task),
            ("per_dimension", agg.by_dimension),
            ("per_suite", agg.by_suite_and_kind),
            ("per_split", agg.by_split),
            ("by_source", agg.by_source),
        )
        for section, fn in sections:
            for row in fn(run.records):
                data = row.as_dict()
                data["id"] = data.pop("group")
                out[section].append({"run": run.name, **data})
        out["outcomes"] += [{"run": run.name, **o.as_dict()} for o in agg.outcomes_by_dimension(run.records)]
        out["conditions"] += [{"run": run.name, **t.as_dict()} for t in agg.condition_tests(run.records)]
        out["confusion"][run.name] = agg.confusion(run.records)
    for other in runs[1:]:
        if (t := agg.run_comparison(runs[0].name, runs[0].records, other.name, other.records)) is not None:
            out["comparisons"].append(t.as_dict())
    return json.dumps(out, indent=1)


def _csv(runs: list[Run]) -> str:
    """Tidy CSV: one row per (run, table, group)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(["run", "table", "group", "tasks", "episodes", "successes", "rate", "ci_low", "ci_high", "gaps"])
    for run in runs:
        for table, fn in (
            ("by_source", agg.by_source),
            ("per_dimension", agg.by_dimension),
            ("per_suite", agg.by_suite_and_kind),
            ("per_split", agg.by_split),
            ("per_task", agg.by_task),
        ):
            for r in fn(run.records):
                writer.writerow(
                    [
                        run.name,
                        table,
                        r.group,
                        r.tasks,
                        r.episodes,
                        r.successes,
                        f"{r.rate:.4f}",
                        f"{r.ci_low:.4f}",
                        f"{r.ci_high:.4f}",
                        r.gaps,
                    ]
                )
    return buffer.getvalue()


FORMATS = ("md", "csv", "latex", "json")


def render(paths: list[str | Path], fmt: str = "md") -> str:
    """The full report of one or more runs (the first is the reference for comparisons)."""
    runs = load_runs(paths)
    if fmt == "json":
        return _json(runs)
    if fmt == "csv":
        return _csv(runs)
    formatter = _latex if fmt == "latex" else _markdown
    head = ""
    if fmt == "md":
        head = "".join(
            f"**{run.name}** — {run.path}: {len(run.records)} episodes, "
            f"{sum(r.status == 'gap' for r in run.records)} gaps; physics "
            + ", ".join(f"{k} {v}" for k, v in run.config.get("physics", {}).items())
            + "\n\n"
            for run in runs
        )
    return head + "\n".join(formatter(t) for t in tables_for(runs))


def diagnosis_text(paths: list[str | Path]) -> str:
    """The short diagnosis: success by dimension (runs side by side) and what each policy did instead."""
    runs = load_runs(paths)
    tables = [dimension_table(runs)]
    for run in runs:
        tables.append(outcome_table(run))
        if (conditions := condition_table(run)) is not None:
            tables.append(conditions)
    return "\n".join(_markdown(t) for t in tables)
