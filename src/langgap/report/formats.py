"""Output formats, chosen by name; every one renders the same `Summary` (nothing is counted here)."""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Callable
from pathlib import Path

from langgap.report.load import load_runs
from langgap.report.summary import Summary, summarize
from langgap.report.tables import PRIVILEGED_NOTE, Table, diagnosis, full_report


def markdown_table(table: Table) -> str:
    lines = [
        f"### {table.title}",
        "",
        "| " + " | ".join(table.headers) + " |",
        "|" + "|".join("---" for _ in table.headers) + "|",
    ]
    lines += ["| " + " | ".join(cell.replace("|", "\\|") for cell in row) + " |" for row in table.rows]
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
)


def _latex_escape(text: str) -> str:
    for a, b in _LATEX_ESCAPES:
        text = text.replace(a, b)
    return text


def latex_table(table: Table) -> str:
    lines = [
        r"\begin{table}[ht]",
        r"\centering",
        rf"\caption{{{_latex_escape(table.title)}}}",
        r"\small",
        r"\begin{tabular}{l" + "c" * (len(table.headers) - 1) + "}",
        r"\toprule",
        " & ".join(_latex_escape(h) for h in table.headers) + r" \\",
        r"\midrule",
    ]
    lines += [" & ".join(_latex_escape(c) for c in row) + r" \\" for row in table.rows]
    lines += [r"\bottomrule", r"\end{tabular}", r"\end{table}"]
    return "\n".join(lines) + "\n"


def _header(summary: Summary) -> str:
    """One line per run: where it is, its size, its physics stack."""
    return "".join(
        f"**{run.label}** — {run.path}: {run.episodes} episodes, {run.gaps} gaps; physics "
        + ", ".join(f"{k} {v}" for k, v in run.spec.get("physics", {}).items())
        + "\n\n"
        for run in summary.runs
    )


def _footnote(summary: Summary, render: Callable[[str], str]) -> str:
    return render(PRIVILEGED_NOTE) if summary.privileged else ""


def to_markdown(summary: Summary, tables: list[Table] | None = None) -> str:
    body = "\n".join(markdown_table(t) for t in (full_report(summary) if tables is None else tables))
    head = _header(summary) if tables is None else ""
    return head + body + _footnote(summary, lambda note: f"\n{note}\n")


def to_latex(summary: Summary) -> str:
    body = "\n".join(latex_table(t) for t in full_report(summary))
    return body + _footnote(summary, lambda note: f"\n% {note}\n\\noindent {_latex_escape(note)}\n")


def to_json(summary: Summary) -> str:
    return json.dumps(summary.to_dict(), indent=1)


CSV_SECTIONS = ("by_source", "per_dimension", "per_suite", "per_split", "per_task")


def to_csv(summary: Summary) -> str:
    """Tidy CSV: one row per (run, table, group), the JSON report's rate rows."""
    data = summary.to_dict()
    privileged = {run["run"]: run["privileged"] for run in data["runs"]}
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    columns = ["tasks", "episodes", "successes", "rate", "ci_low", "ci_high", "gaps"]
    writer.writerow(["run", "privileged", "table", "group", *columns])
    for section in CSV_SECTIONS:
        for row in data[section]:
            values = [f"{row[c]:.4f}" if isinstance(row[c], float) else row[c] for c in columns]
            writer.writerow([row["run"], int(privileged[row["run"]]), section, row["id"], *values])
    return buffer.getvalue()


FORMATS: dict[str, Callable[[Summary], str]] = {"md": to_markdown, "csv": to_csv, "latex": to_latex, "json": to_json}


def render(paths: list[str | Path], fmt: str = "md") -> str:
    """The full report of one or more runs (the first is the reference for comparisons)."""
    return FORMATS[fmt](summarize(load_runs(paths)))


def diagnosis_text(paths: list[str | Path]) -> str:
    """The short diagnosis (Markdown): success by dimension and what each policy did instead."""
    summary = summarize(load_runs(paths))
    return to_markdown(summary, diagnosis(summary))
