"""One policy's runs on several catalogs side by side (`langgap report RUN1 RUN2 …`), on real runs made by
`langgap eval` (langgap99 and libero-pro, one init state each), in every format; and the "what it did
instead" diagnosis on libero-pro, whose task perturbations share their source's scene."""

from __future__ import annotations

import json
import re
from html.parser import HTMLParser

import pytest

from tests.support.harness import run_cli, store_rows

PRO_SOURCE = "spatial/s0/black-bowl-1-on-plate"
PRO_TASKS = "spatial/s0/*"  # in libero-pro: the original, its LIBERO-PRO task and language perturbations
LANGGAP_TASKS = f"{PRO_SOURCE},spatial/s0/black-bowl-2-on-plate"  # an original and a spatial-description task
RUNS = {  # run directory -> catalog, tasks, policy
    "blind-99": ("langgap99", LANGGAP_TASKS, "blind"),
    "blind-pro": ("libero-pro", PRO_TASKS, "blind"),
    "oracle-99": ("langgap99", PRO_SOURCE, "oracle"),
}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The runs, made as a user makes them (one init state per task, at the catalogs' step limits)."""
    root = tmp_path_factory.mktemp("side-by-side")
    for name, (catalog, tasks, policy) in RUNS.items():
        args = ["--catalog", catalog, "--tasks", tasks, "--policy", policy, "--episodes", "1", "--workers", "0"]
        result = run_cli("eval", *args, "--no-progress", "--quiet", "--run", str(root / name))
        assert result.returncode == 0, result.stderr
    return {name: str(root / name) for name in RUNS}


def _report(*args: str) -> str:
    result = run_cli("report", *args)
    assert result.returncode == 0, result.stderr
    return result.stdout


def _expected_cells(runs) -> dict[tuple[str, str], tuple[int, int]]:
    """(catalog, column) -> (successes, episodes), counted from the stores' rows."""
    cells: dict[tuple[str, str], tuple[int, int]] = {}
    for name in ("blind-99", "blind-pro"):
        rows = store_rows(runs[name])
        for row in rows:
            for column in (row["dimension"], "extended" if row["kind"] == "extended" else None):
                if column is not None:
                    successes, episodes = cells.get((RUNS[name][0], column), (0, 0))
                    cells[(RUNS[name][0], column)] = (successes + row["success"], episodes + 1)
    return cells


def test_one_policys_runs_on_two_catalogs_are_side_by_side_in_every_format(runs, tmp_path):
    paired = [runs["blind-99"], runs["blind-pro"]]
    data = json.loads(_report(*paired, "--format", "json"))
    got = {(r["catalog"], r["id"]): (r["successes"], r["episodes"]) for r in data["side_by_side"]}
    assert got == _expected_cells(runs)
    assert {r["row"] for r in data["side_by_side"]} == {0} and {r["policy"] for r in data["side_by_side"]} == {"blind"}
    assert {"task", "language"} <= {column for catalog, column in got if catalog == "libero-pro"}
    assert got[("libero-pro", "task")] == (0, 1) and got[("libero-pro", "language")] == (1, 1)  # blind read nothing

    markdown = _report(*paired, "--no-published")
    answers = [line for line in markdown.splitlines() if " reads its instruction" in line]
    assert [a.split(" ")[0] for a in answers] == ["blind-99", "blind-pro"]  # one opening sentence per run
    table = markdown.split("### Side by side")[1].split("\n### ")[0]
    assert "| Policy | langgap99: Original | langgap99: Spatial Description | langgap99: All extended |" in table
    pro = "libero-pro: Original | libero-pro: Task (LIBERO-PRO) | libero-pro: Language | libero-pro: All extended"
    assert pro in table
    assert "| blind † (blind-99, blind-pro) | 100.0 [20.7, 100.0] |" in table
    assert "| 0.0 [0.0, 79.3] | 100.0 [20.7, 100.0] | 50.0 [9.5, 90.5] |" in table  # libero-pro: task, language, all
    assert "### Side by side" in _report(*paired, "--summary")  # the diagnosis shows it too

    latex = _report(*paired, "--format", "latex", "--no-published")
    assert r"& \multicolumn{3}{c}{langgap99} & \multicolumn{4}{c}{libero-pro} \\" in latex
    assert "Policy & Original & Spatial Description & All extended & Original & Task (LIBERO-PRO) & Language" in latex

    _report(*paired, "--html", str(tmp_path / "html"))
    page = _Sections()
    page.feed((tmp_path / "html/index.html").read_text())
    side = next(rows for title, rows in page.sections.items() if title.startswith("Side by side"))
    assert side[0] == ["", "langgap99", "libero-pro"]  # the column groups
    assert side[2][0] == "blind † (blind-99, blind-pro)" and side[2][1:4] == table.split("\n")[-2].split(" | ")[1:4]
    embedded = json.loads(page.summary)
    assert embedded["side_by_side"] == data["side_by_side"]


def test_runs_of_different_policies_on_different_catalogs_keep_being_reported_one_by_one(runs):
    data = json.loads(_report(runs["oracle-99"], runs["blind-pro"], "--format", "json"))
    assert data["side_by_side"] == [] and data["comparisons_refused"]
    assert data["protocol_mismatches"] == {"blind-pro (blind)": ["catalog", "catalog hash"]}
    markdown = _report(runs["oracle-99"], runs["blind-pro"])
    assert "Side by side" not in markdown and "Runs not compared" in markdown
    # With a third run that puts blind on two catalogs, oracle gets its own row, empty on libero-pro.
    rows = json.loads(_report(runs["oracle-99"], runs["blind-pro"], runs["blind-99"], "--format", "json"))
    assert {(r["policy"], r["catalog"]) for r in rows["side_by_side"]} == {
        ("oracle", "langgap99"),
        ("blind", "libero-pro"),
        ("blind", "langgap99"),
    }


def test_what_blind_did_instead_on_libero_pro_is_its_sources_task(runs):
    """A LIBERO-PRO task perturbation is set in its source's scene, so the engine watches the source's goal
    and names the episode `did_source_task` when blind does the original task instead."""
    rows = {r["task_id"]: r for r in store_rows(runs["blind-pro"])}
    task = rows["spatial/s0/pro-task"]
    assert task["outcome"] == "did_source_task" and PRO_SOURCE in json.loads(task["reached"])
    data = json.loads(_report(runs["blind-pro"], "--format", "json"))
    outcomes = {o["group"]: o for o in data["outcomes"]}
    assert outcomes["task"]["did_source_task"] == 1.0 and outcomes["language"]["success"] == 1.0
    (scene,) = data["confusion"]["blind-pro (blind)"].values()  # the three tasks share one scene
    assert scene["spatial/s0/pro-task"] == {PRO_SOURCE: 1} and sorted(scene) == sorted(rows)
    (answer,) = data["answers"]
    # The answer rests on the extended tasks that ask for another goal (the run mixes in a rewording): of the
    # task perturbation's one episode, blind did the source task.
    assert answer["default_task_rate"] == 1.0
    summary = _report(runs["blind-pro"], "--summary")
    assert re.search(r"\| Task \(LIBERO-PRO\) \| 1 \| 0\.0 \| 100\.0 \|", summary)  # Episodes, Success %, Did source


class _Sections(HTMLParser):
    """Each section's title -> its table's rows (header rows included, as cell texts); and the embedded JSON."""

    def __init__(self):
        super().__init__()
        self.sections: dict[str, list[list[str]]] = {}
        self.summary = ""
        self._title: str | None = None
        self._in: str | None = None
        self._text = ""

    def handle_starttag(self, tag, attrs):
        if tag in ("h2", "td", "th") or (tag == "script" and ("id", "langgap-summary") in attrs):
            self._in, self._text = tag, ""
        elif tag == "tr" and self._title is not None:
            self.sections[self._title].append([])

    def handle_endtag(self, tag):
        if tag != self._in:
            return
        if tag == "h2":
            self._title = self._text
            self.sections[self._title] = []
        elif tag == "script":
            self.summary = self._text
        elif self._title is not None:
            self.sections[self._title][-1].append(self._text)
        self._in = None

    def handle_data(self, data):
        if self._in is not None:
            self._text += data
