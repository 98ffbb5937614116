"""The sentence every report opens with, on constructed runs: how well the policy reads its instruction."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest

from langgap.catalog.verdicts import GateResult
from langgap.report import load_runs, render, summarize
from langgap.vocabulary import Outcome
from tests.support.harness import run_cli
from tests.support.reports import SOURCE, TASKS, episode, memoriser, reader, write_run

RAMEKIN, STOVE = "spatial/s0/ramekin-on-plate", "spatial/s0/bowl-on-stove"


def _answers(*runs, allow_mismatch=False) -> list[str]:
    return [run.answer.text for run in summarize(load_runs(list(runs)), allow_mismatch=allow_mismatch).runs]


def test_a_policy_that_reads_its_instruction(tmp_path):
    (text,) = _answers(write_run(tmp_path / "vla", "my-vla", reader()))
    assert text == (
        "vla (my-vla) reads its instruction: 100 % on original tasks vs 88 % [53, 98] on extended tasks (paired "
        "with their originals: p = 1); no oracle verdict covers them; 0 % of its extended-task failures did the "
        "scene's original task instead (0 % [0, 32] of its extended episodes)."
    )


def test_a_policy_that_reads_weakly_beside_the_oracles_ceiling(tmp_path):
    # Originals all done; the ramekin task done, the stove task never: the scene's original task instead.
    records = [episode(SOURCE, k, success=True, reached={SOURCE: 5}) for k in range(4)]
    records += [episode(RAMEKIN, k, success=True, reached={RAMEKIN: 5}) for k in range(4)]
    records += [episode(STOVE, k, reached={SOURCE: 5}) for k in range(4)]
    gates = {t: GateResult(episodes=4, successes=4 - (t == STOVE), feasible=True, inits=4) for t in TASKS}
    (text,) = _answers(write_run(tmp_path / "vla", "my-vla", records, gates=gates))
    assert text == (
        "vla (my-vla) reads its instruction weakly: 100 % on original tasks vs 50 % [22, 78] on extended tasks "
        "(paired with their originals: p = 0.12); the oracle reaches 88 % on them; 100 % of its extended-task "
        "failures did the scene's original task instead (50 % [22, 78] of its extended episodes)."
    )


def test_a_policy_that_hardly_reads_against_a_compared_blind_run(tmp_path):
    blind = write_run(tmp_path / "blind", "blind", memoriser(sees_state=True, sees_goal=True))
    vla = write_run(tmp_path / "vla", "my-vla", memoriser())
    _, text = _answers(blind, vla)
    assert text.startswith("vla (my-vla) hardly reads its instruction: 100 % on original tasks vs 0 % [0, 35]")
    assert "(paired with their originals: p = 0.016; against blind, 0 % on the same 7 episodes: p = 1)" in text
    assert text.endswith("100 % of its extended-task failures did the scene's original task instead "
                         "(100 % [65, 100] of its extended episodes); 1 episode was a gap, left out.")  # fmt: skip
    # The reader against the same blind run: it succeeds where blind did the original task.
    reads = _answers(blind, write_run(tmp_path / "reader", "my-vla", reader()))[1]
    assert "against blind, 0 % on the same 7 episodes: p = 0.031" in reads


def test_a_blind_run_with_another_protocol_is_not_paired_unless_allowed(tmp_path):
    scripted = memoriser(sees_state=True, sees_goal=True)
    blind = write_run(tmp_path / "blind", "blind", scripted, physics={"mujoco": "3.3.0"})
    vla = write_run(tmp_path / "vla", "my-vla", reader())
    assert "against blind" not in _answers(blind, vla)[1]
    assert "against blind, 0 % on the same 7 episodes" in _answers(blind, vla, allow_mismatch=True)[1]


def test_runs_without_extended_tasks_or_without_original_success_say_what_cannot_be_told(tmp_path):
    originals = write_run(tmp_path / "o", "my-vla", [episode(SOURCE, k, success=k < 3) for k in range(4)])
    assert _answers(originals) == [
        "o (my-vla): 75 % on original tasks [30, 95]; the run has no extended tasks, so it does not show whether "
        "the policy reads its instruction."
    ]
    nothing = write_run(tmp_path / "n", "my-vla", [episode(t, k) for t in TASKS for k in range(2)])
    (text,) = _answers(nothing)
    assert text.startswith("n (my-vla) does no original task, so the gap cannot be measured: 0 % on original tasks")


def test_a_run_of_switch_episodes_only_says_what_the_policy_did_after_the_switch(tmp_path):
    """A `switch:K` episode of an extended task asks for another task first: the run has extended tasks, under
    the switch, and its sentence says whether the policy followed the switch or went on with the first task."""
    persisted = [
        replace(r, outcome=Outcome.PERSISTED) if r.kind == "extended" and r.judged else r
        for r in memoriser(condition="switch:20")
    ]
    followed = reader(condition="switch:60")
    (text,) = _answers(write_run(tmp_path / "switched", "my-vla", persisted + followed))
    assert text == (
        "switched (my-vla): no episode under the given instruction; its extended tasks ran only under a switch "
        "(another task's instruction first, their own from policy step K): at K=20 it did the task switched to in "
        "0 % [0, 35] of 7 extended episodes and went on with the first instruction's task in 100 % [65, 100]; at "
        "K=60 it did the task switched to in 88 % [53, 98] of 8 extended episodes and went on with the first "
        "instruction's task in 0 % [0, 32] (a policy that reads its instruction does the task switched to; one "
        "that ignores it goes on with the first)."
    )
    assert "no extended tasks" not in text


@pytest.fixture
def runs(tmp_path):
    return [
        write_run(tmp_path / "blind", "blind", memoriser(sees_state=True, sees_goal=True)),
        write_run(tmp_path / "vla", "my-vla", reader()),
    ]


def test_every_report_opens_with_the_answer(runs):
    blind, vla = _answers(*runs)
    assert render(runs, "md").startswith(f"{blind}\n\n{vla}\n\n")
    summary = run_cli("report", str(runs[0]), "--compare", str(runs[1]), "--summary")
    assert summary.returncode == 0 and summary.stdout.startswith(f"{blind}\n\n{vla}\n\n")
    assert render(runs, "latex").startswith(r"\noindent blind $^\dagger$ hardly reads its instruction: 100 \%")
    assert [a["text"] for a in json.loads(render(runs, "json"))["answers"]] == [blind, vla]


def test_summary_honours_format_and_allow_mismatch(tmp_path, runs):
    latex = run_cli("report", *map(str, runs[1:]), "--summary", "--format", "latex", "--no-published")
    assert latex.returncode == 0 and r"\begin{tabular}" in latex.stdout and "### " not in latex.stdout
    assert r"\noindent vla (my-vla) reads its instruction" in latex.stdout
    for fmt in ("json", "csv"):
        refused = run_cli("report", str(runs[1]), "--summary", "--format", fmt)
        assert refused.returncode == 2 and refused.stdout == ""
        assert refused.stderr == (
            f"error: --summary shows the diagnosis as md or latex; --format {fmt} holds every number of the full "
            "report: drop --summary\n"
        )
    other = write_run(tmp_path / "other", "my-vla", reader(), physics={"mujoco": "3.3.0"})
    base = ["report", str(runs[0]), "--compare", str(other), "--summary", "--no-published"]
    refused = run_cli(*base)
    assert "Runs not compared: their protocols differ" in refused.stdout and "against blind" not in refused.stdout
    allowed = run_cli(*base, "--allow-mismatch")
    assert "Runs not compared" not in allowed.stdout and "against blind, 0 % on the same 7" in allowed.stdout


def test_no_verdict_when_every_extended_task_asks_for_its_originals_goal(tmp_path):
    """A rewording of the original's own goal (LIBERO-Plus's language variants, paraphrases) is done as well by a
    policy that ignores its instruction: such tasks alone cannot show that it reads."""

    reworded = [replace(episode(RAMEKIN, k, success=True, reached={SOURCE: 5}), dimension="language") for k in range(4)]
    originals = [episode(SOURCE, k, success=True, reached={SOURCE: 5}) for k in range(4)]
    (run,) = summarize(load_runs([write_run(tmp_path / "blind", "blind", originals + reworded)])).runs
    assert run.answer.verdict is None
    assert run.answer.text == (
        "blind: 100 % on original tasks vs 100 % [51, 100] on extended tasks (paired with their originals: "
        "p = 1); every extended task asks for its original's goal in other words, which a policy that ignores its "
        "instruction does as well, so these tasks cannot show whether it reads it."
    )
    # One task that asks for another goal is enough for a verdict, and it rests on such tasks alone: blind does
    # the rewordings (as LIBERO-PRO's language variants beside its task variants) but not the other goal.
    mixed = reworded[:2] + [episode(STOVE, k, reached={SOURCE: 5}) for k in range(2)]
    (run,) = summarize(load_runs([write_run(tmp_path / "mixed", "blind", originals + mixed)])).runs
    assert run.answer.verdict == "hardly reads its instruction"
    assert run.answer.text == (
        "mixed (blind) hardly reads its instruction: 100 % on original tasks vs 0 % [0, 66] on extended tasks that "
        "ask for another goal (paired with their originals: p = 0.5); no oracle verdict covers them; 100 % of its "
        "extended-task failures did the scene's original task instead (100 % [34, 100] of its extended episodes); "
        "1 task that rewords the original's goal left out (a policy that ignores its instruction does them as well)."
    )
    assert run.source("extended").rate == 0.5  # the table's extended row keeps every extended task
