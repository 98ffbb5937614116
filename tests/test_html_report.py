"""The HTML report in a real headless Chromium: every table present, numbers equal to the JSON
report's, sorting and filtering work, no console error, no request beyond the page's own file."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from langgap.report import load_runs, summarize
from langgap.report.published import load_published
from langgap.report.sections import FULL_REPORT, report_tables
from langgap.video import VIDEO_FPS, write_video
from tests.support.browser import CHROMIUM, chromium
from tests.support.harness import run_cli
from tests.support.reports import SOURCE, memoriser, reader, write_run

pytestmark = pytest.mark.requires(CHROMIUM is not None, "Debian's chromium (./setup.sh installs it)")

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
    table_vii: rows(section("Success on extended tasks by dimension")),
    answers: [...document.querySelectorAll("#answer p")].map(p => p.textContent),
    stacks: Object.fromEntries([...document.querySelectorAll("#outcome-chart g.stack")].map(g =>
      [g.dataset.run + " / " + g.dataset.group, [...g.querySelectorAll("rect.segment")].map(r =>
        [r.dataset.outcome, parseFloat(r.getAttribute("height"))])])),
    data: JSON.parse(document.getElementById("langgap-summary").textContent),
  };
})()"""
)


def _filmed(run: Path, records: list, filmed: dict[tuple[str, int], int]) -> list:
    """`records` with real WebM clips (a moving bar, `frames` long) for the (task, init) pairs in `filmed`."""
    for record in records:
        if (frames := filmed.get((record.task_id, record.init_index))) is not None:
            record.video = f"videos/{record.task_id.replace('/', '__')}#{record.init_index}.webm"
            images = [np.zeros((64, 128, 3), np.uint8) for _ in range(frames)]
            for step, image in enumerate(images):
                image[:, 4 * step : 4 * step + 8] = 255
            write_video(run / record.video, images)
    return records


def test_the_html_report_in_a_real_browser(tmp_path):
    clips = {("spatial/s0/ramekin-on-plate", 1): 30, (SOURCE, 0): 20, ("spatial/s0/bowl-on-stove", 0): 25}
    runs = [
        write_run(
            tmp_path / "blind", "blind", _filmed(tmp_path / "blind", memoriser(sees_state=True, sees_goal=True), clips)
        ),
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
        assert facts["titles"] == [t.title for t in report_tables(summary, load_published(), FULL_REPORT.sections)]
        assert facts["data"] == report
        vla_row = next(row for row in facts["table_vii"] if row[0] == "vla (my-vla)")
        extended = next(r for r in report["by_source"] if r["run"] == "vla (my-vla)" and r["id"] == "extended")
        assert vla_row[-1].startswith(f"{100 * extended['rate']:.1f} [{100 * extended['ci_low']:.1f}, ")
        # The page opens with the answer, one sentence per run (the JSON report's).
        assert facts["answers"] == [a["text"] for a in report["answers"]]
        assert facts["answers"][1].startswith("vla (my-vla) reads its instruction: 100 % on original tasks")
        # One stacked outcome bar per run and dimension (original, change object, change target), each full height.
        assert len(facts["stacks"]) == 2 * 3
        heights = {name: sum(h for _, h in segments) for name, segments in facts["stacks"].items()}
        assert max(heights.values()) == pytest.approx(min(heights.values()), abs=0.2)
        assert facts["stacks"]["blind † / change_object"] == [["did_source_task", heights[next(iter(heights))]]]
        stove = [outcome for outcome, _ in facts["stacks"]["vla (my-vla) / change_target"]]
        assert stove == ["success", "no_goal_reached"]
        # Sorting: a click on a column header orders the rows by it, a second click reverses them.
        column = page.evaluate("""(() => {
""" + _SECTION + """
          const tasks = section("Success per task — vla");
          const header = [...tasks.querySelectorAll("th")].find(th => th.textContent === "Rate %");
          const read = () => [...tasks.querySelectorAll("tbody tr")].map(r => parseFloat(r.cells[6].textContent));
          header.click(); const up = read(); header.click(); return [up, read()];
        })()""")  # fmt: skip
        assert column[0] == sorted(column[0]) and column[1] == sorted(column[0], reverse=True)
        # A table with group headings sorts the rows under each heading, the heading staying above them.
        grouped = page.evaluate("""(() => {
""" + _SECTION + """
          const sources = section("Success by data source, suite and dimension — vla");
          const header = [...sources.querySelectorAll("th")].find(th => th.textContent === "Rate %");
          header.click(); header.click();
          return [...sources.querySelectorAll("tbody tr")].map(r => r.cells[0].textContent);
        })()""")  # fmt: skip
        assert grouped[:4] == ["By data source", "Original (LIBERO)", "Total", "Extended (LangGap)"]
        assert grouped[4] == "By suite" and "By perturbation dimension" in grouped
        # Filtering: typing in a table's filter box hides the rows that do not match.
        page.evaluate("""(() => {
""" + _SECTION + """
          const input = section("Success on extended tasks by dimension").querySelector("input.filter");
          input.value = "smolvla";
          input.dispatchEvent(new Event("input"));
        })()""")  # fmt: skip
        assert [row[0] for row in page.evaluate(_FACTS)["table_vii"]] == [
            "SmolVLA (published: LangGap paper, Table VII)"
        ]
        # Per-column filters: the drop-downs of the per-task table combine (and with the text box).
        shown = page.evaluate("""(() => {
""" + _SECTION + """
          const tasks = section("Success per task — blind");
          const choose = (name, value) => {
            const select = tasks.querySelector(`select[aria-label="${name}"]`); select.value = value;
            select.dispatchEvent(new Event("input"));
            return [...tasks.querySelectorAll("tbody tr")].filter(r => !r.hidden).map(r => r.cells[3].textContent);
          };
          return [choose("Mostly did instead", "did source task"), choose("Dimension", "Change Object"),
                  choose("Mostly did instead", "")];
        })()""")  # fmt: skip
        did_source = ["spatial/s0/ramekin-on-plate", "spatial/s0/bowl-on-stove"]
        assert shown == [did_source, did_source[:1], did_source[:1]]
        # Confusion heatmaps: the intended task's cell green, another task's red, shaded by row share.
        heat = page.evaluate("""(() => {
""" + _SECTION + """
          const rows = [...section("Confusion").querySelectorAll("tbody tr")];
          return Object.fromEntries(rows.map(r => [r.cells[0].textContent,
            [...r.cells].slice(1).map(c => getComputedStyle(c).backgroundColor)]));
        })()""")  # fmt: skip
        assert heat[SOURCE][0] == "rgb(44, 160, 44)"  # four of four episodes on the diagonal
        assert heat["spatial/s0/ramekin-on-plate"][0] == "rgb(214, 39, 40)"  # did the source task every time
        # The gallery: did-source-task clips first, each under the instruction it was sent, playable.
        gallery = page.evaluate("""(async () => {
""" + _SECTION + """
          const part = section("Filmed episodes — blind");
          const videos = [...part.querySelectorAll("video")];
          const duration = v => v.readyState >= 1 ? v.duration
            : new Promise(done => { v.addEventListener("loadedmetadata", () => done(v.duration));
                                    v.addEventListener("error", () => done(null)); });
          return {groups: [...part.querySelectorAll("h3")].map(h => h.textContent),
                  captions: [...part.querySelectorAll("figcaption")].map(c => c.textContent),
                  durations: await Promise.all(videos.map(duration)),
                  errors: videos.map(v => v.error && v.error.code)};
        })()""")  # fmt: skip
        assert gallery["groups"] == ["did source task (2)", "success (1)"]
        assert gallery["captions"][0].startswith("“do spatial/s0/bowl-on-stove”")
        assert gallery["errors"] == [None] * 3
        assert [round(d * VIDEO_FPS) for d in gallery["durations"]] == [25, 30, 20]  # frames, at VIDEO_FPS
        shot = page.screenshot(tmp_path / "report.png")
        assert page.errors == []
        # Nothing beyond the page's own files (the video controls' icons are inline data: URLs).
        assert all(url.startswith(("file://", "data:")) for url in page.requests)
        assert sum(url.startswith("file://") and url.endswith(".webm") for url in page.requests) == 3
    assert shot.stat().st_size > 10_000
