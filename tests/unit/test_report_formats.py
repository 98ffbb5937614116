"""Every output format renders the one summary: same numbers in JSON, CSV, Markdown and LaTeX."""

from __future__ import annotations

import csv
import io
import json

import pytest

from langgap.report import FORMATS, load_runs, render, summarize
from langgap.report.sections import report_data
from tests.support.harness import run_cli
from tests.support.reports import memoriser, reader, write_run


@pytest.fixture
def runs(tmp_path):
    return [
        write_run(tmp_path / "blind", "blind", memoriser(sees_state=True, sees_goal=True)),
        write_run(tmp_path / "vla", "my-vla", reader()),
    ]


def test_json_is_the_summary(runs):
    summary = summarize(load_runs(runs))
    report = json.loads(render(runs, "json"))
    assert report == json.loads(json.dumps(report_data(summary)))
    blind_dims = {row["id"]: row for row in report["per_dimension"] if row["run"] == "blind"}
    assert blind_dims["change_target"]["gaps"] == 1 and blind_dims["change_target"]["episodes"] == 3
    assert report["comparisons"][0]["pairs"] == 11


def test_csv_rows_are_the_json_rate_rows(runs):
    report = json.loads(render(runs, "json"))
    rows = list(csv.DictReader(io.StringIO(render(runs, "csv"))))
    expected = [(s, r) for s in ("by_source", "per_dimension", "per_suite", "per_split", "per_task") for r in report[s]]
    assert len(rows) == len(expected)
    for row, (section, source) in zip(rows, expected, strict=True):
        assert (row["table"], row["group"], int(row["successes"]), int(row["gaps"])) == (
            section,
            source["id"],
            source["successes"],
            source["gaps"],
        )
        assert float(row["ci_high"]) == pytest.approx(source["ci_high"], abs=1e-4)
    assert {row["run"]: row["privilege"] for row in rows} == {"blind": "goal", "vla (my-vla)": "none"}


def test_markdown_and_latex_hold_the_papers_tables_and_mark_privileged_runs(runs):
    markdown, latex = render(runs, "md"), render(runs, "latex")
    # Each heading says what its table holds, then the paper's table it reproduces.
    headings = (
        "Success by data source, suite and dimension — blind † (the paper's Table II)",
        "Success per suite, original vs extended tasks — success %, 95% CI (the paper's Table VI)",
        "Success on extended tasks by dimension — success %, 95% CI, (tasks) (the paper's Table VII)",
        "Success by data source and dimension — π0.5 as published (the paper's Table II)",
        "What the policy did instead — blind †",
        "Success per task — vla (my-vla)",
        "Confusion (intended × achieved) — blind †",
    )
    for heading in headings:
        assert f"### {heading}" in markdown
        escaped = heading.replace("%", r"\%").replace("†", r"$^\dagger$").replace("×", r"$\times$")
        assert r"\caption{" + escaped in latex
    assert not [line for line in markdown.splitlines() if line.startswith("### Table")]
    assert "| blind † |" in markdown and "not a policy under test" in markdown
    assert "| 0.0 [0.0, 56.1] (1 gaps) (1) |" in markdown  # change target: 0/3, one gap, one task
    assert "†" not in render(runs[1:], "md")
    assert r"\toprule" in latex and r"blind $^\dagger$" in latex
    assert sorted(FORMATS) == ["csv", "json", "latex", "md"]


def test_a_directory_without_a_run_is_one_error_line(tmp_path):
    result = run_cli("report", str(tmp_path))
    assert result.returncode == 2
    assert result.stderr == f"error: no run store at {tmp_path} (expected {tmp_path / 'episodes.sqlite'})\n"


def test_the_papers_published_rows_are_shown_beside_the_runs_and_can_be_left_out(runs):
    markdown = render(runs, "md")
    assert "| π0 (published: LangGap paper, Table VII) | 10.8 | 0.0 | 20.0 | 0.0 | 8.6 |" in markdown
    assert (
        "| SmolVLA (published: LangGap paper, Table VI) | 17.0 | 3.2 | 44.0 | 0.0 | 50.0 | 13.2 | 41.0 | 38.0 | 6.4 |"
        in markdown
    )
    assert "| Original (LIBERO) | 40 | 800 | 750 | 93.8 | [91.9, 95.2] | – |" in markdown  # Table II, published counts
    assert "not re-run" in markdown and "(published: LangGap paper" in render(runs, "latex")
    assert "(published:" not in render(runs, "md", published=False)
    assert "(published:" not in render(runs, "json")  # the JSON holds this report's numbers only
    cli = run_cli("report", str(runs[1]), "--no-published", "--summary")
    assert cli.returncode == 0 and "Table VII" in cli.stdout and "(published:" not in cli.stdout
    assert "(published: LangGap paper, Table VII)" in run_cli("report", str(runs[1]), "--summary").stdout


def test_the_published_appendix_adds_up_to_table_ii_and_sits_beside_the_runs(runs):
    from langgap.report.published import load_published

    published = load_published()
    table_ii = {r.group: (r.successes, r.episodes) for r in published.diagnostic}
    for dimension in ("change_object", "change_target", "spatial_description", "drawer_action"):
        groups = [g.published for g in published.appendix if g.dimension == dimension]
        assert (sum(g.successes for g in groups), sum(g.episodes for g in groups)) == table_ii[dimension]
        assert (
            sum(len(g.task_ids) for g in published.appendix if g.dimension == dimension) * 20 == table_ii[dimension][1]
        )
    assert "| Drawer Action | open the middle drawer | 13/20 (65.0%) on 1 task | – | – |" in render(runs, "md")


def test_allow_mismatch_on_the_command_line_pairs_runs_whose_protocols_differ(tmp_path):
    first = write_run(tmp_path / "a", "blind", memoriser())
    other = write_run(tmp_path / "b", "my-vla", reader(), physics={"mujoco": "3.3.0"})
    refused = run_cli("report", str(first), "--compare", str(other), "--no-published")
    assert (
        "Runs not compared: their protocols differ" in refused.stdout and "| b (my-vla) | physics |" in refused.stdout
    )
    allowed = run_cli("report", str(first), "--compare", str(other), "--no-published", "--allow-mismatch")
    assert "Runs compared on matched episodes (McNemar) — protocols differ: b (my-vla): physics" in allowed.stdout


def test_runs_from_before_the_blas_kernel_was_recorded_pair_with_runs_that_record_it(tmp_path):
    from langgap.report.summary import protocol_differences, results

    older = write_run(tmp_path / "a", "blind", memoriser())
    newer = write_run(tmp_path / "b", "my-vla", reader(), physics={"mujoco": "3.2.3", "blas": "Haswell"})
    other = write_run(tmp_path / "c", "my-vla", reader(), physics={"mujoco": "3.2.3", "blas": "SkylakeX"})
    a, b, c = (results(run) for run in load_runs([older, newer, other]))
    assert protocol_differences(a, b) == [] and protocol_differences(b, c) == ["physics"]


def test_a_report_with_its_html_page_reads_each_run_once(runs, tmp_path, monkeypatch, capsys):
    from langgap.cli.main import main
    from langgap.report import load
    from langgap.store import RunStore

    opened = []
    real_open = RunStore.open.__func__

    def counted(cls, path, *args, **kwargs):
        opened.append(str(path))
        return real_open(cls, path, *args, **kwargs)

    monkeypatch.setattr(load.RunStore, "open", classmethod(counted))
    assert main(["report", str(runs[0]), "--compare", str(runs[1]), "--html", str(tmp_path / "page")]) == 0
    assert sorted(opened) == sorted(map(str, runs))  # the text and the page are two views of one reading
    assert (tmp_path / "page" / "index.html").exists()
    assert capsys.readouterr().out.startswith(render(runs, "md"))
