"""Output formats, chosen by name; every one renders the same `Summary` (nothing is counted here)."""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Callable
from pathlib import Path

from langgap.report.data import to_data
from langgap.report.load import load_runs
from langgap.report.pooled import PooledRow, pool, pooled_table, replicate_tests, replicate_tests_table
from langgap.report.published import Published, load_published
from langgap.report.sections import CSV_REPORT, DIAGNOSIS, FULL_REPORT, Layout, report_data, report_tables
from langgap.report.summary import Summary, summarize
from langgap.report.tables import Table, notes, selection_text


def markdown_table(table: Table) -> str:
    lines = [
        f"### {table.title}",
        "",
        "| " + " | ".join(table.headers) + " |",
        "|" + "|".join("---" for _ in table.headers) + "|",
    ]
    for i, row in enumerate(table.rows):
        cells = [cell.replace("|", "\\|") for cell in row]
        if i in table.headings:
            cells[0] = f"*{cells[0]}*"
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


_LATEX_ESCAPES = (
    ("\\", r"\textbackslash{}"),
    ("%", r"\%"),
    ("&", r"\&"),
    ("_", r"\_"),
    ("#", r"\#"),
    ("*", ""),
    ("×", r"$\times$"),
    ("†", r"$^\dagger$"),
    ("<", r"$<$"),
    ("‡", r"$^\ddagger$"),
)


def _latex_escape(text: str) -> str:
    for a, b in _LATEX_ESCAPES:
        text = text.replace(a, b)
    return text


def _latex_headers(table: Table) -> list[str]:
    """The header lines: with column groups, a row spanning each group over its columns (ruled below),
    then the columns without their group's name."""
    if not table.column_groups:
        return [" & ".join(_latex_escape(h) for h in table.headers) + r" \\"]
    spans, rules, headers, first = [], [], [], 1
    for name, width in table.column_groups:
        spans.append(rf"\multicolumn{{{width}}}{{c}}{{{_latex_escape(name)}}}" if name else "")
        if name:
            rules.append(rf"\cmidrule(lr){{{first}-{first + width - 1}}}")
        headers += [h.removeprefix(f"{name}: ") for h in table.headers[first - 1 : first - 1 + width]]
        first += width
    return [" & ".join(spans) + r" \\", " ".join(rules), " & ".join(_latex_escape(h) for h in headers) + r" \\"]


def latex_table(table: Table) -> str:
    lines = [
        r"\begin{table}[ht]",
        r"\centering",
        rf"\caption{{{_latex_escape(table.title)}}}",
        r"\small",
        r"\begin{tabular}{l" + "c" * (len(table.headers) - 1) + "}",
        r"\toprule",
        *_latex_headers(table),
        r"\midrule",
    ]
    lines += [" & ".join(_latex_escape(c) for c in row) + r" \\" for row in table.rows]
    lines += [r"\bottomrule", r"\end{tabular}", r"\end{table}"]
    return "\n".join(lines) + "\n"


def answers(summary: Summary) -> list[str]:
    """The sentences a report opens with: one per run (`langgap.report.answer`), each followed by how much of its
    plan the run holds when it is not all of it."""
    sentences = []
    for run in summary.runs:
        sentences.append(run.answer.text)
        if run.progress:
            sentences.append(f"{run.label}: {run.progress}")
    return sentences


def _header(summary: Summary, published: Published | None) -> str:
    """One line per run (where it is, its size, its tasks), then the notes; the protocol card follows."""
    runs = "".join(
        f"**{run.label}** — {run.path}: {run.episodes} episodes, {run.gaps} gaps; {selection_text(run)}\n\n"
        for run in summary.runs
    )
    return runs + "".join(f"{note}\n\n" for note in notes(summary, published))


def to_markdown(summary: Summary, published: Published | None = None, layout: Layout = FULL_REPORT) -> str:
    """The report in Markdown, opening with the answer: the sections of `layout` (the full report, or the
    diagnosis), with the runs' header first or the notes last as it says."""
    opening = "".join(f"{sentence}\n\n" for sentence in answers(summary))
    body = "\n".join(markdown_table(t) for t in report_tables(summary, published, layout.sections))
    if layout.header:
        return opening + _header(summary, published) + body
    return opening + body + "".join(f"\n{note}\n" for note in notes(summary, published, ceiling=False))


def to_latex(summary: Summary, published: Published | None = None, layout: Layout = FULL_REPORT) -> str:
    """The report in LaTeX, opening with the answer: the sections of `layout` (the full report, or the
    diagnosis), then the notes."""
    opening = "".join(f"\\noindent {_latex_escape(sentence)}\n\n" for sentence in answers(summary))
    body = "\n".join(latex_table(t) for t in report_tables(summary, published, layout.sections))
    shown = notes(summary, published, ceiling=layout.header)
    return opening + body + "".join(f"\n\\noindent {_latex_escape(note)}\n" for note in shown)


def to_json(summary: Summary, published: Published | None = None) -> str:
    """The summary's data (`JSON_REPORT`'s sections); published figures are left out (they are not this report's
    numbers)."""
    return json.dumps(report_data(summary), indent=1)


def to_csv(summary: Summary, published: Published | None = None) -> str:
    """Tidy CSV: one row per (run, table, group), the JSON report's rate rows (`CSV_REPORT`'s sections)."""
    privilege = {run.name: str(run.privilege) for run in summary.runs}
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    columns = [
        "tasks",
        "episodes",
        "successes",
        "rate",
        "ci_low",
        "ci_high",
        "gaps",
        "oracle_rate",
        "relative_to_oracle",
    ]
    writer.writerow(["run", "privilege", "table", "group", *columns])
    for section, rows in report_data(summary, CSV_REPORT).items():
        for row in rows:
            values = [f"{v:.4f}" if isinstance(v := row[c], float) else ("" if v is None else v) for c in columns]
            writer.writerow([row["run"], privilege[row["run"]], section, row["id"], *values])
    return buffer.getvalue()


FORMATS: dict[str, Callable[[Summary, Published | None], str]] = {
    "md": to_markdown,
    "csv": to_csv,
    "latex": to_latex,
    "json": to_json,
}


def render(
    paths: list[str | Path],
    fmt: str = "md",
    *,
    published: bool = True,
    allow_mismatch: bool = False,
    split: str | None = None,
) -> str:
    """The full report of one or more runs (the first is the reference for comparisons); `published`
    adds the paper's results as reference rows to the formats that show tables; `allow_mismatch`
    pairs runs whose protocols differ; `split` groups episodes by a stored split (`load_runs`)."""
    summary = summarize(load_runs(paths, split=split), allow_mismatch=allow_mismatch)
    return format_summary(summary, fmt, published=published)


# The formats that show the short diagnosis (`report --summary`): json and csv hold every number already.
DIAGNOSIS_FORMATS: dict[str, Callable[[Summary, Published | None, Layout], str]] = {
    "md": to_markdown,
    "latex": to_latex,
}


def diagnosis_text(
    paths: list[str | Path],
    fmt: str = "md",
    *,
    published: bool = False,
    allow_mismatch: bool = False,
    split: str | None = None,
) -> str:
    """The short diagnosis: the answer, the protocol card, success by dimension, what each policy did instead
    (`fmt`: a name in `DIAGNOSIS_FORMATS`; `allow_mismatch` pairs runs whose protocols differ; `split` groups
    episodes by a stored split: `load_runs`)."""
    summary = summarize(load_runs(paths, split=split), allow_mismatch=allow_mismatch)
    return format_summary(summary, fmt, published=published, diagnosis=True)


def format_summary(summary: Summary, fmt: str = "md", *, published: bool = True, diagnosis: bool = False) -> str:
    """A summary already made, as text: what `render` (or, with `diagnosis`, `diagnosis_text`) prints, for a
    caller that also needs the summary itself (the CLI's `--html` and `--plots`), so the runs are read once.

    Args:
        summary: What `summarize` made of the runs.
        fmt: A name in `FORMATS` (with `diagnosis`, in `DIAGNOSIS_FORMATS`).
        published: Add the paper's results as reference rows to the formats that show tables.
        diagnosis: The short diagnosis instead of the full report.

    Returns:
        The report's text.
    """
    reference = load_published() if published else None
    if diagnosis:
        return DIAGNOSIS_FORMATS[fmt](summary, reference, DIAGNOSIS)
    return FORMATS[fmt](summary, reference)


def _pooled_csv(rows: list[PooledRow]) -> str:
    """Tidy CSV: one row per (pool, group, run), then the pool's own row (run `pooled`)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(["pool", "group", "run", "episodes", "successes", "rate", "ci_low", "ci_high", "gaps"])
    for row in rows:
        for cell in row.cells:
            for run, rate in [*zip(row.runs, cell.replicates, strict=True), ("pooled", cell.pooled)]:
                low, high = rate.ci
                figures = [rate.episodes, rate.successes, f"{rate.rate:.4f}", f"{low:.4f}", f"{high:.4f}", rate.gaps]
                writer.writerow([row.label, cell.group, str(run), *figures])
    return buffer.getvalue()


def _pooled_tables(rows: list[PooledRow], render: Callable[[Table], str]) -> str:
    """The pooled table, then the tests between pools over their runs (when two pools have several runs)."""
    tests = replicate_tests(rows)
    tables = [pooled_table(rows), *([replicate_tests_table(tests)] if tests else [])]
    return "\n".join(render(table) for table in tables)


POOLED_FORMATS: dict[str, Callable[[list[PooledRow]], str]] = {
    "md": lambda rows: _pooled_tables(rows, markdown_table),
    "latex": lambda rows: _pooled_tables(rows, latex_table),
    "json": lambda rows: json.dumps(to_data({"pools": rows, "tests": replicate_tests(rows)}), indent=1),
    "csv": _pooled_csv,
}


def pooled_text(
    pools: dict[str, list[str | Path]], fmt: str = "md", *, allow_mismatch: bool = False, split: str | None = None
) -> str:
    """The pooled table of replicate runs (`langgap.report.pooled.pool`) in `fmt` (a name in `POOLED_FORMATS`),
    its groups a stored split's when `split` names one."""
    return POOLED_FORMATS[fmt](pool(pools, allow_mismatch=allow_mismatch, split=split))
