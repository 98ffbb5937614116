"""The report as one self-contained HTML page: the answer first (one sentence per run), a stacked
outcome bar per dimension, then every table of the Markdown report, sortable and filterable in the
page, and coloured confusion matrices.

Nothing is fetched: styles, script and chart are inline, so the page opens from `file://` or any
static server. The summary's JSON is embedded too, so the page's numbers can be checked against it.
"""

from __future__ import annotations

import html
import json
import shutil
import urllib.parse
from pathlib import Path

from langgap.page_style import PAGE_STYLE
from langgap.report.formats import answers
from langgap.report.labels import DIMENSION_LABEL, label
from langgap.report.published import Published
from langgap.report.sections import FULL_REPORT, report_data, report_tables
from langgap.report.summary import Summary, shown_dimensions
from langgap.report.tables import OUTCOME_NAME, Table, notes, selection_text
from langgap.vocabulary import Condition, Outcome, TaskKind

MEDIA_DIR = "media"

_STYLE = (
    PAGE_STYLE
    + """
th { background: #f3f3f3; cursor: pointer; user-select: none; }
th[aria-sort=ascending]::after { content: " ▲"; } th[aria-sort=descending]::after { content: " ▼"; }
#answer p { font-size: 1.1em; border-left: 4px solid #2ca02c; padding: .2em .8em; background: #f6faf6; }
svg text { font: 11px system-ui, sans-serif; }
select.column-filter { margin: .25em 0 .25em .5em; }
table.heatmap td { text-align: center; min-width: 2em; }
tr.column-groups td { text-align: center; font-weight: bold; background: #f3f3f3; }
tr.heading th { text-align: left; font-style: italic; background: #fafafa; cursor: default; }
.clips { display: flex; flex-wrap: wrap; gap: 1em; }
figure { margin: 0; width: 370px; } figure video { width: 100%; background: #000; }
figcaption { font-size: .9em; }
"""
)

_SCRIPT = """
function cellValue(cell) {
  const number = parseFloat(cell.textContent.replace(/[^0-9.+-].*$/, ""));
  return isNaN(number) ? cell.textContent.trim().toLowerCase() : number;
}
document.querySelectorAll("table.report").forEach(table => {
  const headers = table.tHead.querySelectorAll("th");
  headers.forEach((th, column) => th.addEventListener("click", () => {
    const ascending = th.getAttribute("aria-sort") !== "ascending";
    headers.forEach(other => other.removeAttribute("aria-sort"));
    th.setAttribute("aria-sort", ascending ? "ascending" : "descending");
    const body = table.tBodies[0];
    // Rows are sorted within their group: a heading row stays above the rows it heads.
    const groups = [[]];
    Array.from(body.rows).forEach(row =>
      row.classList.contains("heading") ? groups.push([row]) : groups[groups.length - 1].push(row));
    groups.forEach(group => {
      const heading = group.length && group[0].classList.contains("heading") ? group.splice(0, 1) : [];
      group.sort((a, b) => {
        const x = cellValue(a.cells[column]), y = cellValue(b.cells[column]);
        const order = typeof x === typeof y ? (x < y ? -1 : x > y ? 1 : 0) : (typeof x === "number" ? -1 : 1);
        return ascending ? order : -order;
      });
      [...heading, ...group].forEach(row => body.appendChild(row));
    });
  }));
});
function applyFilters(ident) {
  const table = document.getElementById(ident);
  const box = document.querySelector(`input.filter[data-table="${ident}"]`);
  const needle = box ? box.value.trim().toLowerCase() : "";
  const choices = Array.from(document.querySelectorAll(`select.column-filter[data-table="${ident}"]`))
    .filter(select => select.value !== "").map(select => [Number(select.dataset.column), select.value]);
  Array.from(table.tBodies[0].rows).forEach(row => {
    row.hidden = (needle !== "" && !row.textContent.toLowerCase().includes(needle))
      || choices.some(([column, value]) => row.cells[column].textContent !== value);
  });
}
document.querySelectorAll("input.filter, select.column-filter").forEach(control =>
  control.addEventListener("input", () => applyFilters(control.dataset.table)));
"""


def _filters(table: Table, ident: str) -> str:
    """A text box over every row, and one drop-down per categorical column the table names."""
    parts = [f'<input class="filter" data-table="{ident}" placeholder="filter rows" aria-label="filter rows">']
    for name in table.filters:
        column = table.headers.index(name)
        values = sorted({row[column] for row in table.rows if row[column] not in ("", "–")})
        options = "".join(f"<option>{html.escape(v)}</option>" for v in values)
        parts.append(
            f'<select class="column-filter" data-table="{ident}" data-column="{column}" '
            f'aria-label="{html.escape(name)}"><option value="">{html.escape(name)}: all</option>{options}</select>'
        )
    return "".join(parts)


def _heat_cell(text: str, total: int, diagonal: bool) -> str:
    """A count shaded by its share of the row: green on the diagonal (the intended task), red elsewhere."""
    count = int(text) if text.isdigit() else 0
    if not count:
        return "<td></td>"
    share = count / total
    colour = f"rgba(44, 160, 44, {share:.2f})" if diagonal else f"rgba(214, 39, 40, {share:.2f})"
    return f'<td class="heat" style="background: {colour}" title="{100 * share:.0f} % of the row">{count}</td>'


def _rows(table: Table) -> str:
    if table.kind != "heatmap":
        return "".join(
            f'<tr class="heading"><th scope="rowgroup" colspan="{len(row)}">{html.escape(row[0])}</th></tr>'
            if i in table.headings
            else "<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>"
            for i, row in enumerate(table.rows)
        )
    rows = []
    for row in table.rows:
        total = sum(int(c) for c in row[1:] if c.isdigit()) or 1
        cells = [_heat_cell(c, total, table.headers[j + 1] == row[0]) for j, c in enumerate(row[1:])]
        rows.append(f"<tr><th scope=row>{html.escape(row[0])}</th>{''.join(cells)}</tr>")
    return "".join(rows)


def _column_groups(table: Table) -> str:
    """A header row naming each column group over its columns (cells, not headers: a click on a column's
    header sorts by that column)."""
    if not table.column_groups:
        return ""
    spans = "".join(f'<td colspan="{width}">{html.escape(name)}</td>' for name, width in table.column_groups)
    return f'<tr class="column-groups">{spans}</tr>'


def _table(table: Table, ident: str) -> str:
    heads = "".join(f"<th>{html.escape(h)}</th>" for h in table.headers)
    return (
        f"<section><h2>{html.escape(table.title)}</h2>{_filters(table, ident)}"
        f'<table class="report {table.kind}" id="{ident}"><thead>{_column_groups(table)}<tr>{heads}</tr></thead>'
        f"<tbody>{_rows(table)}</tbody></table></section>"
    )


def _gallery(table: Table, ident: str, media: dict[str, str]) -> str:
    """Filmed episodes grouped by outcome (in the table's order), each clip with the instruction it was given."""
    column = {name: j for j, name in enumerate(table.headers)}
    groups: dict[str, list[list[str]]] = {}
    for row in table.rows:
        groups.setdefault(row[column["Outcome"]], []).append(row)
    parts = [f"<section class=gallery id={ident}><h2>{html.escape(table.title)}</h2>"]
    for outcome, rows in groups.items():
        parts.append(
            f'<h3 data-outcome="{html.escape(outcome)}">{html.escape(outcome)} ({len(rows)})</h3><div class=clips>'
        )
        for row in rows:
            source = media.get(row[column["Video"]])
            player = (
                f'<video controls muted preload="metadata" src="{html.escape(source)}"></video>'
                if source
                else '<p class="note">clip not found</p>'
            )
            where = f"{row[column['Task']]} · init {row[column['Init']]} · seed {row[column['Seed']]}"
            if row[column["Condition"]] != Condition.GIVEN:
                where += f" · condition {row[column['Condition']]}"
            parts.append(
                f"<figure>{player}<figcaption>“{html.escape(row[column['Instruction']])}”"
                f"<br><span class=note>{html.escape(where)}</span></figcaption></figure>"
            )
        parts.append("</div>")
    return "".join(parts) + "</section>"


_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b")
# Each outcome's colour in the stacked bars: success at the bottom, the outcomes that explain failures above.
OUTCOME_COLOURS = {
    Outcome.SUCCESS: "#2ca02c",
    Outcome.DID_SOURCE_TASK: "#ff7f0e",
    Outcome.PERSISTED: "#8c564b",
    Outcome.WRONG_ORDER: "#9467bd",
    Outcome.DID_OTHER_TASK: "#d62728",
    Outcome.NO_GOAL_REACHED: "#bbbbbb",
    Outcome.POLICY_ERROR: "#555555",
}


_CHAR_WIDTH = 6.5  # pixels of one character of the chart's 11 px labels, a generous average


def fitted(name: str, width: float) -> str:
    """`name` as it fits under a bar `width` pixels wide: whole, or cut with an ellipsis (its <title> holds it
    whole)."""
    room = max(1, int(width / _CHAR_WIDTH))
    return name if len(name) <= room else name[: room - 1].rstrip() + "…"


def outcome_chart(summary: Summary) -> str:
    """Per dimension (and the originals), one stacked bar per run, named under it: the share of each outcome
    (success, did source task, other task, no goal, ...), with the success rate's 95 % interval, as inline SVG."""
    groups = [TaskKind.ORIGINAL, *shown_dimensions(summary.runs)]
    width, height, left, bottom = 760, 280, 40, 56
    slot = (width - left) / len(groups)
    bar = slot * 0.8 / max(1, len(summary.runs))

    def y(value: float) -> float:
        return height - bottom - value * (height - bottom - 10)

    parts = [f'<svg id="outcome-chart" width="{width}" height="{height}" role="img">']
    for tick in (0.0, 0.25, 0.5, 0.75, 1.0):
        parts.append(f'<line x1="{left}" x2="{width}" y1="{y(tick):.1f}" y2="{y(tick):.1f}" stroke="#eee"/>')
        parts.append(f'<text x="{left - 6}" y="{y(tick) + 4:.1f}" text-anchor="end">{100 * tick:.0f}</text>')
    for j, group in enumerate(groups):
        name = label(DIMENSION_LABEL, group)
        x_mid = left + (j + 0.5) * slot
        parts.append(f'<text x="{x_mid:.1f}" y="{y(0) + 30}" text-anchor="middle">{html.escape(name)}</text>')
        for i, run in enumerate(summary.runs):
            row = next((o for o in run.outcomes if o.group == group), None)
            if row is None or row.episodes == 0:
                continue
            x = left + j * slot + slot * 0.1 + i * bar
            parts.append(f'<g class="stack" data-run="{html.escape(run.label)}" data-group="{group}">')
            base = 0.0
            for outcome, colour in OUTCOME_COLOURS.items():
                if (share := row.shares[outcome]) <= 0:
                    continue
                title = html.escape(f"{run.label} — {name}: {OUTCOME_NAME[outcome]} {100 * share:.1f} %")
                parts.append(
                    f'<rect class="segment" data-outcome="{outcome}" x="{x:.1f}" y="{y(base + share):.1f}" '
                    f'width="{bar * 0.9:.1f}" height="{y(base) - y(base + share):.1f}" fill="{colour}">'
                    f"<title>{title}</title></rect>"
                )
                base += share
            rates = {r.group: r for r in run.by_dimension} | {TaskKind.ORIGINAL: run.source(TaskKind.ORIGINAL)}
            low, high = rates[group].ci
            middle = x + bar * 0.45
            parts.append(
                f'<line x1="{middle:.1f}" x2="{middle:.1f}" y1="{y(low):.1f}" y2="{y(high):.1f}" stroke="#000"/>'
            )
            parts.append(
                f'<text class="run-name" x="{middle:.1f}" y="{y(0) + 13}" text-anchor="middle">'
                f"<title>{html.escape(run.label)}</title>{html.escape(fitted(run.label, bar))}</text></g>"
            )
    outcomes = "".join(
        f'<tspan fill="{colour}">■ </tspan><tspan>{OUTCOME_NAME[outcome]}   </tspan>'
        for outcome, colour in OUTCOME_COLOURS.items()
    )
    parts.append(f'<text x="{left}" y="{height - 4}">{outcomes}</text></svg>')
    return "".join(parts)


def answer_block(summary: Summary) -> str:
    """The sentences the page opens with, one per run (and how much of its plan each incomplete run holds)."""
    sentences = "".join(f'<p class="answer">{html.escape(sentence)}</p>' for sentence in answers(summary))
    return f'<div id="answer">{sentences}</div>'


def html_page(summary: Summary, published: Published | None = None, media: dict[str, str] | None = None) -> str:
    """The whole report as one HTML document; `media` maps each clip's file to its address from the page."""
    tables = "".join(
        _gallery(t, f"t{i}", media or {}) if t.kind == "gallery" else _table(t, f"t{i}")
        for i, t in enumerate(report_tables(summary, published, FULL_REPORT.sections))
    )
    runs = ", ".join(html.escape(run.label) for run in summary.runs)
    selections = "".join(f"<li>{html.escape(f'{run.label} — {selection_text(run)}')}</li>" for run in summary.runs)
    data = json.dumps(report_data(summary)).replace("</", "<\\/")
    return (
        '<!doctype html><html lang="en"><head><meta charset="utf-8">'
        f"<title>LangGap report — {runs}</title><style>{_STYLE}</style></head><body>"
        f"<h1>LangGap report</h1>{answer_block(summary)}"
        + "<h2>What each run did, by dimension (outcome shares; the line: success's 95 % Wilson interval)</h2>"
        + outcome_chart(summary)
        + f"<ul>{selections}</ul>"
        + "".join(f'<p class="note">{html.escape(n)}</p>' for n in notes(summary, published))
        + tables
        + f'<script type="application/json" id="langgap-summary">{data}</script>'
        + f"<script>{_SCRIPT}</script></body></html>"
    )


def write_html(summary: Summary, published: Published | None, directory: str | Path) -> Path:
    """Write the report to `directory/index.html`, the clips it shows to `directory/media/`; returns its path."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    media = {}
    for number, run in enumerate(summary.runs):
        for clip in run.clips:
            if clip.path.is_file():
                target = directory / MEDIA_DIR / str(number) / clip.path.name
                target.parent.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(clip.path, target)
                media[str(clip.path)] = urllib.parse.quote(target.relative_to(directory).as_posix())
    path = directory / "index.html"
    path.write_text(html_page(summary, published, media), encoding="utf-8")
    return path
