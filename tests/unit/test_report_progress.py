"""A report of a run that holds less than its plan: how many of the planned episodes are stored and why the rest
are not, near the top; a run that holds none is refused with that line (a report of nothing would read as a
policy at 0 %)."""

from __future__ import annotations

from pathlib import Path

import pytest

from langgap.cli.main import main
from langgap.report import diagnosis_text, load_runs, render, summarize
from langgap.report.html import html_page
from langgap.store import PROGRESS, RunStore
from tests.support.reports import reader, write_run

STOP = "stopped after 3 episodes in a row failed with: ConnectionError: policy server unreachable (results are intact)"


def _run(directory: Path, records: list, progress: dict | None) -> Path:
    write_run(directory, "my-vla", records)
    if progress is not None:
        with RunStore.open(directory) as store:
            store.set_meta(PROGRESS, progress)
    return directory


def test_a_run_stopped_before_its_first_episode_is_refused_with_its_plan_and_stop(tmp_path, capsys):
    run = _run(tmp_path / "stopped", [], {"planned": 60, "stopped": STOP})
    assert main(["report", str(run)]) == 2
    assert main(["report", "--summary", str(run)]) == 2
    out, err = capsys.readouterr()
    line = f"the run is empty: 0 of 60 planned episodes stored; it stopped early: {STOP}"
    expected = f"error: nothing to report for {run}: {line}\n"
    assert out == "" and err == expected * 2


def test_an_empty_run_without_a_recorded_plan_is_refused_too(tmp_path, capsys):
    assert main(["report", str(_run(tmp_path / "old", [], None))]) == 2
    assert capsys.readouterr().err.endswith(": the run is empty: it holds no episode\n")


@pytest.mark.parametrize(
    ("stopped", "why"),
    [(STOP, f"it stopped early: {STOP}"), (None, "no stop was recorded (it is still running, or it was killed)")],
)
def test_a_partly_stored_run_says_how_much_of_its_plan_it_holds_after_its_answer(tmp_path, stopped, why):
    run = _run(tmp_path / "partial", reader(), {"planned": 60, "stopped": stopped})
    line = f"partial (my-vla): the run is incomplete: 12 of 60 planned episodes stored; {why}"
    for text in (render([run]), diagnosis_text([run]), render([run], "latex")):
        paragraphs = text.split("\n\n")
        assert line in paragraphs[1]  # right after the run's answer
    assert f'<p class="answer">{line}</p>' in html_page(summarize(load_runs([run])))


def test_a_run_that_holds_its_whole_plan_says_nothing_of_it(tmp_path):
    run = _run(tmp_path / "whole", reader(), {"planned": 12, "stopped": None})
    assert "planned episodes" not in render([run]) + diagnosis_text([run])
