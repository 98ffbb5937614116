"""The JSON report byte for byte (key names, order, rounding, nulls), the CSV drawn from it, and the Markdown
report and diagnosis (every section, in order, under its heading), on synthetic stores whose report has every
section: compared with files written by the report as it was before its sections and rows were given one
serialisation path (`report_outputs/`), never with output of the code under test."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from langgap.catalog.verdicts import GateResult
from langgap.report import diagnosis_text, render
from langgap.vocabulary import Outcome
from tests.support.reports import SOURCE, beyond_episode, memoriser, reader, write_run

EXPECTED = Path(__file__).parent / "report_outputs"
RAMEKIN, STOVE = "spatial/s0/ramekin-on-plate", "spatial/s0/bowl-on-stove"
PASSIVE, ORDERED = "spatial/s0/bowl-on-plate~passive", "spatial/s0/first-open-drawer-then-bowl-on-plate"


def _repeated(records: list) -> list:
    """`records` and a second repeat of them (seeds 1000 + init index)."""
    return records + [dataclasses.replace(r, seed=1000 + r.init_index) for r in records]


def _every_section() -> list[Path]:
    """A policy run twice on one spec (a test-retest) and a scripted blind run of the same protocol: two repeats
    (the seed spread), a language condition and a switch, rewordings beside tasks asking for another goal, filmed
    episodes, and gate verdicts that mark tasks ⚠ (a proof) and ≠ (another physics stack)."""
    switched = [
        dataclasses.replace(r, outcome=Outcome.PERSISTED) if r.kind == "extended" and r.judged else r
        for r in memoriser(condition="switch:20")
    ]
    beyond = [beyond_episode(PASSIVE, "paraphrase", k, success=k != 0, reached={SOURCE: 5}) for k in range(4)]
    beyond += [beyond_episode(ORDERED, "ordering", k, reached={SOURCE: 5}, wrong_order=True) for k in range(4)]
    vla = _repeated(reader() + beyond) + reader(condition="empty") + switched
    again = [dataclasses.replace(r, success=False, outcome=Outcome.NO_GOAL_REACHED) if r.seed == 1 else r for r in vla]
    blind = _repeated(memoriser(sees_state=True, sees_goal=True))
    for r in blind:
        if r.init_index == 0 and r.judged:
            r.video = f"videos/{r.task_id.replace('/', '_')}-{r.seed}.webm"
    gates = {
        SOURCE: GateResult(4, 4, True, inits=4),
        RAMEKIN: GateResult(4, 3, True, inits=4, failed_inits=[2], physics={"mujoco": "3.3.0"}),
        STOVE: GateResult(4, 0, False, reason="oracle 0/4", inits=4, failed_inits=[0, 1, 2, 3], proof="Out of reach"),
    }
    return [
        write_run(Path("vla"), "my-vla", vla, gates, repeats=2),
        write_run(Path("again"), "my-vla", again, gates, repeats=2),
        write_run(Path("blind"), "blind", blind, gates, repeats=2),
    ]


def _side_by_side() -> list[Path]:
    """One policy on two catalogs (side by side; their protocols differ, so they are not paired)."""
    return [
        write_run(Path("vla-99"), "my-vla", reader(range(2)), catalog="langgap99"),
        write_run(Path("vla-pro"), "my-vla", memoriser(range(2)), catalog="libero-pro"),
    ]


OUTPUTS = {  # file suffix -> the report it holds
    "json": lambda paths: render(paths, "json"),
    "csv": lambda paths: render(paths, "csv"),
    "md": lambda paths: render(paths, "md"),
    "summary.md": lambda paths: diagnosis_text(paths, "md"),
}


@pytest.mark.parametrize(
    ("runs", "output"),
    [(_every_section, output) for output in OUTPUTS] + [(_side_by_side, "json"), (_side_by_side, "csv")],
)
def test_the_reports_are_byte_for_byte_as_stored(runs, output, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # runs named by relative paths: the report's paths read the same in any directory
    expected = EXPECTED / f"{runs.__name__.removeprefix('_')}.{output}"
    assert OUTPUTS[output](runs()) == expected.read_bytes().decode()
