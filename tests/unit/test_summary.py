"""The report's one aggregation, on synthetic stores: every number a table shows is computed here."""

from __future__ import annotations

import dataclasses
import json

import pytest

from langgap.records import Privilege
from langgap.report import load_runs, render, summarize
from langgap.report.sections import report_data, report_tables
from langgap.vocabulary import Outcome
from tests.support.reports import SOURCE, TASKS, memoriser, reader, write_run


@pytest.fixture
def summary(tmp_path):
    blind = write_run(tmp_path / "blind", "blind", memoriser(sees_state=True, sees_goal=True))
    vla = write_run(tmp_path / "vla", "my-vla", reader() + reader(condition="empty"))
    return summarize(load_runs([blind, vla]))


def test_rates_leave_gaps_out_but_count_them(summary):
    blind = summary.runs[0]
    extended = blind.source("extended")
    assert (extended.episodes, extended.successes, extended.gaps, extended.tasks) == (7, 0, 1, 2)
    assert blind.source("original").rate == 1.0 and blind.gaps == 1 and blind.episodes == 12
    stove = next(r for r in blind.by_dimension if r.group == "change_target")
    assert (stove.episodes, stove.gaps) == (3, 1)
    assert [r.group for r in blind.by_split] == ["original", "train", "heldout"]
    assert [r.group for r in blind.by_suite] == ["libero_spatial/original", "libero_spatial/extended"]


def test_only_the_given_instruction_makes_the_benchmark_numbers(summary):
    vla = summary.runs[1]
    assert vla.source("total").episodes == 12  # the `empty` condition's 12 episodes are not in the rates
    assert [t.rate.group for t in vla.tasks] == [SOURCE, "spatial/s0/ramekin-on-plate", "spatial/s0/bowl-on-stove"]
    assert vla.tasks[2].rate.successes == 3 and vla.tasks[2].dimension == "change_target"


def test_what_the_policy_did_instead(summary):
    blind, vla = summary.runs
    shares = {o.group: o.shares for o in blind.outcomes}
    assert shares["extended"]["did_source_task"] == 1.0 and shares["original"]["success"] == 1.0
    assert [o.group for o in blind.outcomes] == ["change_object", "change_target", "extended", "original"]
    vla_shares = {o.group: o.shares for o in vla.outcomes}
    assert vla_shares["change_target"] == pytest.approx(
        {
            "success": 0.75,
            "persisted": 0,
            "wrong_order": 0,
            "did_source_task": 0,
            "did_other_task": 0,
            "no_goal_reached": 0.25,
            "policy_error": 0,
        }  # fmt: skip
    )


def test_confusion_counts_intended_against_achieved(summary):
    (matrix,) = summary.runs[0].confusion.values()
    assert matrix["spatial/s0/ramekin-on-plate"] == {SOURCE: 4}
    assert matrix["spatial/s0/bowl-on-stove"] == {SOURCE: 3}  # the gap is not an achievement
    assert summary.runs[1].confusion["libero_spatial/s0"]["spatial/s0/bowl-on-stove"] == {
        "spatial/s0/bowl-on-stove": 3,
        "none": 1,
    }


def test_condition_and_run_comparisons_are_paired(summary):
    (condition,) = summary.runs[1].conditions
    assert condition.name == "given vs empty" and condition.pairs == 12 and condition.only_a == 0
    (comparison,) = summary.comparisons
    assert comparison.pairs == 11  # the gap has no partner
    assert (comparison.successes_a, comparison.successes_b) == (4, 10)
    assert comparison.p_value == pytest.approx(0.03125)
    # Agreement 5 of 11 pairs; chance gives (4 x 10 + 7 x 1) / 121: κ = (55 - 47) / (121 - 47).
    assert comparison.agreement == pytest.approx(5 / 11) and comparison.kappa == pytest.approx(8 / 74)


def test_agreement_and_kappa_are_shown_only_for_one_spec_run_twice(tmp_path, summary):
    """Cohen's κ of two runs is a test-retest figure: one spec run twice, never two policies (blind vs my-vla)."""
    (table,) = report_tables(summary, None, ["comparisons"])
    assert not summary.comparisons[0].retest and table.headers[-1] == "p"
    markdown = render([run.path for run in summary.runs], "md")
    assert report_data(summary)["comparisons"][0]["kappa"] is None and "κ" not in markdown
    # The same spec twice (a policy that samples: one episode came out otherwise), and the same policy with other
    # arguments (another spec, though its protocol card, and so its pairing, is the same).
    again = [
        dataclasses.replace(r, success=False, outcome=Outcome.NO_GOAL_REACHED) if r.task_id == SOURCE else r
        for r in reader()
    ]
    runs = [
        write_run(tmp_path / "first", "my-vla", reader()),
        write_run(tmp_path / "again", "my-vla", again),
        write_run(tmp_path / "other", "my-vla", reader(), policy_args={"temperature": "0.5"}),
    ]
    retest = summarize(load_runs(runs))
    assert [t.retest for t in retest.comparisons] == [True, False]
    (table,) = report_tables(retest, None, ["comparisons"])
    assert table.headers[-2:] == ["Agree %", "κ"] and "one run spec run twice (test-retest)" in table.title
    # 8 of 12 pairs agree; chance gives (11 x 7 + 1 x 5) / 144: κ = (96 - 82) / (144 - 82)
    assert table.rows[0][-2:] == ["66.7", "0.23"] and table.rows[1][-2:] == ["", ""]
    compared = report_data(retest)["comparisons"]
    assert compared[0]["kappa"] == pytest.approx(14 / 62) and compared[1]["agreement"] is None
    assert "| Agree % | κ |" in render(runs, "md")


def test_runs_are_named_by_label_and_policy_once_and_privileged_runs_are_marked(summary):
    assert [run.privilege for run in summary.runs] == [Privilege.GOAL, Privilege.NONE]
    # run directory `blind` of policy blind: the name once, not "blind (blind)"; directory `vla` of policy my-vla
    assert summary.runs[0].label == "blind †" and summary.runs[1].label == "vla (my-vla)"
    assert [run["privilege"] for run in report_data(summary)["runs"]] == ["goal", "none"]


def test_a_learned_policy_that_reads_simulator_state_is_not_called_a_scripted_reference(tmp_path):
    bc = write_run(tmp_path / "bc", "small-bc", reader(sees_state=True))
    blind = write_run(tmp_path / "blind", "blind", memoriser(sees_state=True, sees_goal=True))
    summary = summarize(load_runs([bc, blind]))
    assert [run.privilege for run in summary.runs] == [Privilege.STATE, Privilege.GOAL]
    assert [run.label for run in summary.runs] == ["bc (small-bc) ‡", "blind †"]
    assert summary.runs[0].card["privileged"] == "reads simulator state (not told the goal)"
    assert summary.runs[1].card["privileged"] == "told the goal (a scripted reference)"
    markdown = render([bc], "md")
    assert "| bc (small-bc) ‡ |" in markdown and "‡ reads simulator state" in markdown
    assert "scripted reference" not in markdown and "†" not in markdown


def test_the_protocol_card_says_what_determines_the_numbers(summary):
    blind, vla = summary.runs
    assert blind.card["step limits"] == "libero_spatial 220" and blind.card["settle steps"] == "10"
    assert blind.card["init states"] == "0–3" and blind.card["seeds"] == "run seed 0 + init index"
    assert blind.card["physics"] == "mujoco 3.2.3" and blind.card["privileged"].startswith("told the goal")
    assert vla.card["privileged"] == "no" and vla.card["policy"] == "my-vla"
    assert summary.mismatches == {} and not summary.refused


def test_runs_whose_protocols_differ_are_not_paired_unless_allowed(tmp_path):
    first = write_run(tmp_path / "a", "blind", memoriser())
    other = write_run(tmp_path / "b", "my-vla", reader(), physics={"mujoco": "3.3.0"}, seed=7)
    refused = summarize(load_runs([first, other]))
    assert refused.mismatches == {"b (my-vla)": ["seeds", "physics"]} and refused.refused
    assert refused.comparisons == []
    allowed = summarize(load_runs([first, other]), allow_mismatch=True)
    assert not allowed.refused and allowed.comparisons[0].pairs == 11


def test_repeats_give_the_between_seed_spread(tmp_path):
    # Two repeats on init states 0..3: the second repeat's seeds are 1000 + k.
    first = reader()
    second = [dataclasses.replace(r, seed=1000 + r.init_index, success=r.kind == "original") for r in reader()]
    run = write_run(tmp_path / "r", "my-vla", first + second, repeats=2)
    (results,) = summarize(load_runs([run])).runs
    rows = {row.group: row for row in results.spread}
    assert [r.rate for r in rows["extended"].rates] == [7 / 8, 0.0]
    assert rows["extended"].mean == pytest.approx(7 / 16) and rows["extended"].std == pytest.approx(0.61872, abs=1e-4)
    assert [r.rate for r in rows["original"].rates] == [1.0, 1.0] and rows["original"].std == 0
    assert results.card["seeds"] == "run seed 0 + init index, 2 repeats"
    assert results.source("extended").episodes == 16  # the pooled rate counts every episode


def test_a_single_seed_run_has_no_spread(summary):
    assert summary.runs[1].spread == []


def test_each_task_says_what_it_mostly_did_instead(summary):
    blind, vla = summary.runs
    assert [t.instead for t in blind.tasks] == [None, ("did_source_task", 4), ("did_source_task", 3)]
    assert [t.instead for t in vla.tasks] == [None, None, ("no_goal_reached", 1)]
    assert (vla.tasks[1].suite, vla.tasks[1].split) == ("libero_spatial", "train")


def test_filmed_episodes_show_did_source_task_first_with_their_instruction(tmp_path):
    records = memoriser()
    for r in records:
        if r.init_index == 0 and r.judged:
            r.video = f"videos/{r.task_id.replace('/', '_')}.webm"
    run = write_run(tmp_path / "blind", "blind", records)
    (blind,) = summarize(load_runs([run])).runs
    assert [(c.outcome, c.task_id) for c in blind.clips] == [
        ("did_source_task", "spatial/s0/bowl-on-stove"),
        ("did_source_task", "spatial/s0/ramekin-on-plate"),
        ("success", SOURCE),
    ]
    assert blind.clips[0].instruction == "do spatial/s0/bowl-on-stove"
    assert blind.clips[0].path == run / "videos" / "spatial_s0_bowl-on-stove.webm"


def test_the_switch_table_per_k_and_dimension(tmp_path):
    """A memoriser keeps doing the source task after its instruction switches; a reader switches with it."""
    persisted = [
        dataclasses.replace(r, outcome=Outcome.PERSISTED) if r.kind == "extended" and r.judged else r
        for r in memoriser(condition="switch:20")
    ]
    run = write_run(tmp_path / "run", "my-vla", reader() + persisted + reader(condition="switch:60"))
    (results,) = summarize(load_runs([run])).runs
    rows = {(row.k, row.group): row.classes for row in results.switches}
    assert [key for key in rows if key[0] == 20] == [(20, "change_object"), (20, "change_target"), (20, "extended"),
                                                     (20, "original")]  # fmt: skip
    extended = rows[(20, "extended")]
    assert (extended["persisted"].successes, extended["persisted"].episodes, extended["persisted"].gaps) == (7, 7, 1)
    assert extended["success"].rate == extended["other"].rate == extended["none"].rate == 0
    assert rows[(20, "original")]["success"].rate == 1.0
    stove = rows[(60, "change_target")]  # the reader fails the stove task at init 0: nothing happens
    assert (stove["success"].successes, stove["none"].successes, stove["success"].episodes) == (3, 1, 4)
    assert stove["success"].ci == pytest.approx((0.3006, 0.9544), abs=1e-3)
    markdown = render([run], "md")
    assert "Instruction switched at step K" in markdown
    assert "| 20 | All extended | 7 | 0.0 [0.0, 35.4] | 100.0 [64.6, 100.0] |" in markdown
    assert "given vs switch:20" in markdown  # paired against `given` (McNemar) with the other conditions
    (exported,) = [
        s for s in report_data(summarize(load_runs([run])))["switches"] if (s["k"], s["group"]) == (20, "extended")
    ]
    assert exported["persisted"] == 1.0 and exported["episodes"] == 7 and exported["gaps"] == 1


def test_a_switch_s_instructions_reach_the_gallery_caption_and_the_episode_export(tmp_path):
    from langgap.report.export import episode_rows

    timeline = [[0, "do the first"], [20, "do the second"]]
    switched = [dataclasses.replace(r, video="videos/a.webm", instructions=timeline) for r in reader(range(1))]
    run = write_run(tmp_path / "run", "my-vla", switched + reader(range(1), condition="empty", video="videos/b.webm"))
    clips = summarize(load_runs([run])).runs[0].clips
    assert {c.instruction for c in clips if c.condition == "given"} == {"do the first → at step 20: do the second"}
    assert {c.instruction for c in clips if c.condition == "empty"} == {f"do {t}" for t in TASKS}  # one instruction
    exported = {(r["task_id"], r["condition"]): json.loads(r["instructions"]) for r in episode_rows([run])}
    assert exported[(SOURCE, "given")] == timeline and exported[(SOURCE, "empty")] == [[0, f"do {SOURCE}"]]
