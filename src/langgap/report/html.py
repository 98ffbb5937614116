"""The report as one self-contained HTML page: every table of the Markdown report, sortable and
filterable in the page, a per-dimension chart with 95 % intervals and coloured confusion matrices.

Nothing is fetched: styles, script and chart are inline, so the page opens from `file://` or any
static server. The summary's JSON is embedded too, so the page's numbers can be checked against it.
"""

from __future__ import annotations

import html
import json
from pathlib import Path

from langgap.catalog.labels import DIMENSION_LABEL, EXTENDED_DIMENSIONS
from langgap.report.published import Published
from langgap.report.summary import Summary
from langgap.report.tables import PRIVILEGED_NOTE, PUBLISHED_NOTE, Table, full_report

_STYLE = """
body { font: 14px/1.4 system-ui, sans-serif; margin: 2em auto; max-width: 1200px; color: #222; }
h1 { font-size: 1.6em; } h2 { font-size: 1.15em; margin-top: 2em; }
table { border-collapse: collapse; margin: .5em 0; }
th, td { border: 1px solid #ccc; padding: .25em .5em; text-align: left; }
th { background: #f3f3f3; cursor: pointer; user-select: none; }
th[aria-sort=ascending]::after { content: " ▲"; } th[aria-sort=descending]::after { content: " ▼"; }
input.filter { margin: .25em 0; padding: .2em .4em; width: 20em; }
.note { color: #555; font-size: .9em; }
svg text { font: 11px system-ui, sans-serif; }
"""

_SCRIPT = """
function cellValue(cell) {
  const number = parseFloat(cell.textContent.replace(/[^0-9.+-].*$/, ""));
  return isNaN(number) ? cell.textContent.trim().toLowerCase() : number;
}
document.querySelectorAll("table.report").forEach(table => {
  table.querySelectorAll("th").forEach((th, column) => th.addEventListener("click", () => {
    const ascending = th.getAttribute("aria-sort") !== "ascending";
    table.querySelectorAll("th").forEach(other => other.removeAttribute("aria-sort"));
    th.setAttribute("aria-sort", ascending ? "ascending" : "descending");
    const body = table.tBodies[0];
    const rows = Array.from(body.rows);
    rows.sort((a, b) => {
      const x = cellValue(a.cells[column]), y = cellValue(b.cells[column]);
      const order = typeof x === typeof y ? (x < y ? -1 : x > y ? 1 : 0) : (typeof x === "number" ? -1 : 1);
      return ascending ? order : -order;
    });
    rows.forEach(row => body.appendChild(row));
  }));
});
document.querySelectorAll("input.filter").forEach(input => input.addEventListener("input", () => {
  const table = document.getElementById(input.dataset.table);
  const needle = input.value.trim().toLowerCase();
  Array.from(table.tBodies[0].rows).forEach(row => {
    row.hidden = needle !== "" && !row.textContent.toLowerCase().includes(needle);
  });
}));
"""


def _table(table: Table, index: int) -> str:
    ident = f"t{index}"
    heads = "".join(f"<th>{html.escape(h)}</th>" for h in table.headers)
    rows = "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>" for row in table.rows)
    heat = " confusion" if table.title.startswith("Confusion") else ""
    return (
        f"<section><h2>{html.escape(table.title)}</h2>"
        f'<input class="filter" data-table="{ident}" placeholder="filter rows" aria-label="filter rows">'
        f'<table class="report{heat}" id="{ident}"><thead><tr>{heads}</tr></thead><tbody>{rows}</tbody></table>'
        "</section>"
    )


_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b")


def dimension_chart(summary: Summary) -> str:
    """Success per dimension (and on the originals) with 95 % intervals, runs side by side, as inline SVG."""
    groups = ["original", *EXTENDED_DIMENSIONS]
    width, height, left, bottom = 760, 260, 40, 40
    slot = (width - left) / len(groups)
    bar = slot * 0.8 / max(1, len(summary.runs))
    parts = [f'<svg id="dimension-chart" width="{width}" height="{height + 20}" role="img">']
    for tick in (0, 25, 50, 75, 100):
        y = height - bottom - tick / 100 * (height - bottom - 10)
        parts.append(f'<line x1="{left}" x2="{width}" y1="{y:.1f}" y2="{y:.1f}" stroke="#eee"/>')
        parts.append(f'<text x="{left - 6}" y="{y + 4:.1f}" text-anchor="end">{tick}</text>')
    for j, group in enumerate(groups):
        x0 = left + j * slot + slot * 0.1
        label = html.escape(DIMENSION_LABEL[group])
        parts.append(
            f'<text x="{left + (j + 0.5) * slot:.1f}" y="{height - bottom + 16}" text-anchor="middle">{label}</text>'
        )
        for i, run in enumerate(summary.runs):
            rates = {r.group: r for r in run.by_dimension} | {"original": run.source("original")}
            rate = rates.get(group)
            if rate is None or rate.episodes == 0:
                continue
            low, high = rate.ci

            def y(value: float) -> float:
                return height - bottom - value * (height - bottom - 10)

            x = x0 + i * bar
            colour = _COLOURS[i % len(_COLOURS)]
            title = html.escape(f"{run.label} — {DIMENSION_LABEL[group]}: {100 * rate.rate:.1f} %")
            parts.append(
                f'<rect class="bar" x="{x:.1f}" y="{y(rate.rate):.1f}" width="{bar * 0.9:.1f}" '
                f'height="{y(0) - y(rate.rate):.1f}" fill="{colour}"><title>{title}</title></rect>'
            )
            middle = x + bar * 0.45
            parts.append(
                f'<line x1="{middle:.1f}" x2="{middle:.1f}" y1="{y(low):.1f}" y2="{y(high):.1f}" stroke="#000"/>'
            )
    legend = "".join(
        f'<tspan fill="{_COLOURS[i % len(_COLOURS)]}">■ </tspan><tspan>{html.escape(run.label)}   </tspan>'
        for i, run in enumerate(summary.runs)
    )
    parts.append(f'<text x="{left}" y="{height + 12}">{legend}</text></svg>')
    return "".join(parts)


def html_page(summary: Summary, published: Published | None = None) -> str:
    """The whole report as one HTML document."""
    tables = "".join(_table(t, i) for i, t in enumerate(full_report(summary, published)))
    notes = [note for note, shown in ((PRIVILEGED_NOTE, summary.privileged), (PUBLISHED_NOTE, published)) if shown]
    runs = ", ".join(html.escape(run.label) for run in summary.runs)
    data = json.dumps(summary.to_dict()).replace("</", "<\\/")
    return (
        '<!doctype html><html lang="en"><head><meta charset="utf-8">'
        f"<title>LangGap report — {runs}</title><style>{_STYLE}</style></head><body>"
        f"<h1>LangGap report</h1><p>{runs}</p>"
        + "".join(f'<p class="note">{html.escape(n)}</p>' for n in notes)
        + "<h2>Success by dimension (95 % Wilson intervals)</h2>"
        + dimension_chart(summary)
        + tables
        + f'<script type="application/json" id="langgap-summary">{data}</script>'
        + f"<script>{_SCRIPT}</script></body></html>"
    )


def write_html(summary: Summary, published: Published | None, directory: str | Path) -> Path:
    """Write the report to `directory/index.html`; returns its path."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / "index.html"
    path.write_text(html_page(summary, published), encoding="utf-8")
    return path
