"""`langgap tasks audit --html DIR` in a real headless Chromium: every recorded finding on the page with its
evidence, the page's data equal to the recorded audit, a row's command reproduces its finding, the filter works,
nothing is fetched."""

from __future__ import annotations

import json
import shlex

import pytest

from tests.support.browser import CHROMIUM, chromium
from tests.support.harness import REPO, run_cli

pytestmark = pytest.mark.requires(CHROMIUM is not None, "Debian's chromium (./setup.sh installs it)")

_FACTS = """(() => {
  const sections = [...document.querySelectorAll("section.finding")];
  const rows = s => [...s.querySelectorAll("tbody tr")].filter(r => !r.hidden)
    .map(r => [...r.cells].map(c => c.textContent));
  return {
    sections: Object.fromEntries(sections.map(s => [s.dataset.name, rows(s)])),
    summary: [...document.querySelectorAll("table.summary tbody tr")].map(r => [...r.cells].map(c => c.textContent)),
    data: JSON.parse(document.getElementById("audit-data").textContent),
    about: Object.fromEntries([...document.querySelectorAll("dl.about > dt")]
      .map(dt => [dt.textContent, dt.nextElementSibling.innerText])),
  };
})()"""


def test_the_audit_page_in_a_real_browser(tmp_path):
    from langgap.audit.findings import read_audit
    from langgap.catalog.catalog import catalog_hash

    result = run_cli("tasks", "audit", "--catalog", "libero-pro", "--html", str(tmp_path / "audit"))
    assert result.returncode == 0, result.stderr
    page_path = tmp_path / "audit" / "index.html"
    assert f"wrote {page_path}" in result.stdout
    _, recorded = read_audit(REPO / "src/langgap/catalog/registry/libero-pro.yaml")
    with chromium() as page:
        page.open(page_path.as_uri())
        facts = page.evaluate(_FACTS)
        # The page shows every recorded finding, one row each, and its data is the recorded audit's.
        assert sorted((f["name"], f["task"], f["detail"]) for f in facts["data"]["findings"]) == sorted(
            (f.name, f.task, f.detail) for f in recorded
        )
        assert facts["data"]["catalog_hash"] == catalog_hash("libero-pro")
        # How the checks ran: each check's settings in words, not JSON.
        assert set(facts["about"]) == {"files", "starts", "references"}
        assert not any("{" in text for text in facts["about"].values())
        assert "expressions judged" in facts["about"]["references"] and "policy image" in facts["about"]["references"]
        shown = {name: len(rows) for name, rows in facts["sections"].items()}
        assert shown == {name: sum(f.name == name for f in recorded) for name in {f.name for f in recorded}}
        assert {row[0]: int(row[1]) for row in facts["summary"]} == {
            name: len({f.task for f in recorded if f.name == name}) for name in shown
        }
        # A row's evidence: the file, its SHA-256 and what the runner sends instead of the file's sentence.
        row = next(r for r in facts["sections"]["runner sends another sentence"] if r[0] == "spatial/s1/pro-lan")
        assert "runner sends: pick up the black bowl next to the ramekin and place it on the plate" in row[2]
        assert "file SHA-256: b2dce057d8b34bb64486e7fd7d820ea2ef7d0bc430c1d6681c9f0382a248157d" in row[2]
        # The filter box hides the rows that do not match.
        page.evaluate("""(() => {
          const input = document.querySelector("section.finding[data-name='runner sends another sentence'] input");
          input.value = "goal/s2"; input.dispatchEvent(new Event("input"));
        })()""")  # fmt: skip
        kept = page.evaluate(_FACTS)["sections"]["runner sends another sentence"]
        assert sorted(r[0] for r in kept) == ["goal/s2/pro-lan", "goal/s2/pro-task"]
        assert page.errors == [] and page.requests == [page_path.as_uri()]
    # The command a row gives makes its finding again.
    duplicate = next(r for r in facts["sections"]["duplicate goal"] if r[0] == "goal/s2/pro-task")
    again = run_cli(*shlex.split(duplicate[3])[1:])
    assert again.returncode == 0, again.stderr
    assert (
        "duplicate goal: 1 task(s)" in again.stdout
        and "goal/s2/pro-task: same goal as goal/s6/pro-task" in again.stdout
    )


def test_an_audit_page_that_cannot_be_written_is_one_error_line(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    result = run_cli("tasks", "audit", "--catalog", "libero-pro", "--html", str(blocker / "audit"))
    assert result.returncode != 0
    assert result.stderr.startswith("error: cannot write") and len(result.stderr.strip().splitlines()) == 1
    assert json.loads((REPO / "src/langgap/catalog/registry/libero-pro.audit.json").read_text())["tasks"]
