"""The HTML report in a real headless Chromium: every table present, numbers equal to the JSON
report's, sorting and filtering work, no console error, no request beyond the page's own file."""

from __future__ import annotations

import json

import pytest

from langgap.report import load_runs, summarize
from langgap.report.published import load_published
from langgap.report.tables import full_report
from tests.browser import CHROMIUM, chromium
from tests.conftest import run_cli
from tests.unit.reports import memoriser, reader, write_run

pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="needs Debian's chromium (./setup.sh installs it)")

# The page's section whose heading starts with a title.
_SECTION = """const section = title => [...document.querySelectorAll("section")]
    .find(s => s.querySelector("h2").textContent.startsWith(title));"""
_FACTS = (
    """(() => {"""
    + _SECTION
    + """
  const rows = part => [...part.querySelectorAll("tbody tr")].filter(r => !r.hidden)
      .map(r => [...r.cells].map(c => c.textContent));
  return {
    titles: [...document.querySelectorAll("section h2")].map(h => h.textContent),
    table_vii: rows(section("Table VII")),
    bars: document.querySelectorAll("#dimension-chart rect.bar").length,
    data: JSON.parse(document.getElementById("langgap-summary").textContent),
  };
})()"""
)


def test_the_html_report_in_a_real_browser(tmp_path):
    runs = [
        write_run(tmp_path / "blind", "blind", memoriser(privileged=True)),
        write_run(tmp_path / "vla", "my-vla", reader()),
    ]
    result = run_cli("report", str(runs[0]), "--compare", str(runs[1]), "--html", str(tmp_path / "html"))
    assert result.returncode == 0, result.stderr
    page_path = tmp_path / "html" / "index.html"
    summary = summarize(load_runs(runs))
    report = json.loads(run_cli("report", str(runs[0]), "--compare", str(runs[1]), "--format", "json").stdout)
    with chromium() as page:
        page.open(page_path.as_uri())
        facts = page.evaluate(_FACTS)
        # Every table of the Markdown report is on the page, and its data is the JSON report's.
        assert facts["titles"] == [t.title for t in full_report(summary, load_published())]
        assert facts["data"] == report
        vla_row = next(row for row in facts["table_vii"] if row[0] == "my-vla (vla)")
        extended = next(r for r in report["by_source"] if r["run"] == "my-vla (vla)" and r["id"] == "extended")
        assert vla_row[-1].startswith(f"{100 * extended['rate']:.1f} [{100 * extended['ci_low']:.1f}, ")
        assert facts["bars"] == 2 * 3  # two runs × (original, change object, change target)
        # Sorting: a click on a column header orders the rows by it, a second click reverses them.
        column = page.evaluate("""(() => {
""" + _SECTION + """
          const tasks = section("Per task — my-vla");
          const header = [...tasks.querySelectorAll("th")].find(th => th.textContent === "Rate %");
          const read = () => [...tasks.querySelectorAll("tbody tr")].map(r => parseFloat(r.cells[4].textContent));
          header.click(); const up = read(); header.click(); return [up, read()];
        })()""")  # fmt: skip
        assert column[0] == sorted(column[0]) and column[1] == sorted(column[0], reverse=True)
        # Filtering: typing in a table's filter box hides the rows that do not match.
        page.evaluate("""(() => {
""" + _SECTION + """
          const input = section("Table VII").querySelector("input.filter"); input.value = "smolvla";
          input.dispatchEvent(new Event("input"));
        })()""")  # fmt: skip
        assert [row[0] for row in page.evaluate(_FACTS)["table_vii"]] == [
            "SmolVLA (published: LangGap paper, Table VII)"
        ]
        shot = page.screenshot(tmp_path / "report.png")
        assert page.errors == []
        assert page.requests and all(url.startswith("file://") for url in page.requests)
    assert shot.stat().st_size > 10_000
