"""Closed-loop language: the instruction changes during an episode (`switch:K`), and the `nonsense` control."""

from __future__ import annotations

import json

import pytest

from langgap.engine.evaluate import evaluate
from langgap.engine.plan import build_plan, condition_instruction, switch_note
from langgap.engine.spec import ExecutionOptions, RunSpec
from langgap.errors import CatalogError
from tests.support.harness import SHORT_STEPS, run_cli, store_rows
from tests.support.servers import free_port, langgap_serve, running

EXTENDED, ORIGINAL = "spatial/s0/black-bowl-2-on-plate", "spatial/s0/black-bowl-1-on-plate"


def test_a_switch_starts_under_the_source_or_a_sibling_chosen_by_the_seed(catalog):
    extended, original = catalog.get(EXTENDED), catalog.get(ORIGINAL)
    plan = build_plan([extended, original], catalog, episodes=4, conditions=("switch:20",), repeats=3)
    assert {p.key.condition for p in plan} == {"switch:20"}
    for p in plan:
        task = catalog.get(p.task_id)
        assert p.changes == ((20, task.instruction()),)
        assert p.instruction == catalog.get(p.started_as).instruction() != task.instruction()
    assert {p.started_as for p in plan if p.task_id == EXTENDED} == {extended.source}
    siblings = {p.key.seed: p.started_as for p in plan if p.task_id == ORIGINAL}
    assert set(siblings.values()) <= {t.id for t in catalog.scene_mates(original)} - {ORIGINAL}
    assert len(set(siblings.values())) > 1  # spread over the scene by the episode's seed...
    again = build_plan([original], catalog, episodes=4, conditions=("switch:20",), repeats=3)
    assert {p.key.seed: p.started_as for p in again} == siblings  # ...and the same in every run


def test_an_original_alone_in_its_scene_is_left_unswitched_and_said_so(catalog, tmp_path):
    """Ten LangGap-99 originals (eight of libero_10) have no sibling to start under: their switch episodes are
    not planned (the other conditions are), the CLI says which, and a selection of only such tasks is one
    error line."""
    alone, original = catalog.get("libero10/s2/turn-on-stove+moka-pot-on-stove"), catalog.get(ORIGINAL)
    plan = build_plan([alone, original], catalog, episodes=2, conditions=("given", "switch:20"))
    assert {(p.task_id, p.key.condition) for p in plan} == {
        (alone.id, "given"),
        (original.id, "given"),
        (original.id, "switch:20"),
    }
    note = switch_note([alone, original], catalog, ("given", "switch:20"))
    assert note.startswith("note: 1 task(s) have no other task") and alone.id in note and original.id not in note
    assert switch_note([alone, original], catalog, ("given",)) == ""
    with pytest.raises(CatalogError, match="no selected task has another task in its scene"):
        build_plan([alone], catalog, episodes=1, conditions=("switch:20",))
    run = tmp_path / "run"
    result = run_cli("eval", "--policy", "noop", "--tasks", alone.id, "--run", str(run), "--condition", "switch:20")
    assert result.returncode != 0 and not run.exists()
    assert result.stdout.startswith("note: 1 task(s)") and result.stderr.strip().startswith("error: switch: no")
    counted = run_cli("tasks", "gate", "--condition", "switch:20").stdout
    assert "10 of 99 task(s) have no other task in their scene to start under: never switched" in counted
    assert "not gated at switch:20" not in counted  # the shipped switch verdicts cover every other task


def test_nonsense_is_as_many_words_of_the_catalog_s_vocabulary(catalog):
    task = catalog.get(EXTENDED)
    vocabulary = {word for t in catalog for word in t.instruction().split()}
    sentences = [condition_instruction(task, catalog, "nonsense", "libero", k) for k in range(5)]
    for sentence in sentences:
        assert len(sentence.split()) == len(task.instruction().split()) and set(sentence.split()) <= vocabulary
    assert len(set(sentences)) == 5 and task.instruction() not in sentences
    assert sentences == [condition_instruction(task, catalog, "nonsense", "libero", k) for k in range(5)]


@pytest.mark.parametrize(
    ("condition", "says"),
    [
        ("switch:0", "'switch:0': switch:K takes K, the policy step at which the instruction changes, as a whole"),
        ("switch:x", "'switch:x': switch:K takes K"),
        ("switch:", "'switch:': switch:K takes K"),
        ("swap", "unknown condition(s) ['swap']"),
    ],
)
def test_a_malformed_condition_is_one_error_line(short_catalog, tmp_path, condition, says):
    run = tmp_path / "run"
    result = run_cli(
        "eval", "--policy", "noop", "--catalog", short_catalog, "--run", str(run), "--condition", condition
    )
    assert result.returncode != 0 and result.stderr.strip().splitlines()[-1].startswith(f"error: {says}")
    assert not run.exists()


def test_a_switch_after_the_step_limit_is_one_error_line(short_catalog, tmp_path):
    run = tmp_path / "run"
    args = ("eval", "--policy", "noop", "--catalog", short_catalog, "--run", str(run))
    result = run_cli(*args, f"--condition=switch:{SHORT_STEPS}")
    assert result.returncode != 0 and not run.exists()
    assert (
        result.stderr.strip()
        .splitlines()[-1]
        .endswith(f"ends at step {SHORT_STEPS}, before its instruction would switch")
    )


def _in_force(timeline: list, steps: int) -> list[str]:
    """The instruction in force at each policy step of an episode, from its stored timeline."""
    return [[text for step, text in timeline if step <= s][-1] for s in range(steps)]


def _check_the_policy_saw_the_timeline(run, logs, k: int) -> None:
    rows = store_rows(run)
    assert {r["condition"] for r in rows} == {"given", f"switch:{k}", "nonsense"}
    for row in rows:
        timeline = json.loads(row["instructions"])
        assert timeline[0] == [0, row["instruction"]]
        if row["condition"].startswith("switch"):
            assert len(timeline) == 2 and timeline[1][0] == k and timeline[1][1] != row["instruction"]
        else:
            assert len(timeline) == 1
    # Every query carried the instruction in force, whichever process the policy ran in.
    seen = sorted(log.read_text().splitlines() for log in logs.iterdir())
    assert seen == sorted(_in_force(json.loads(r["instructions"]), r["steps"]) for r in rows)


_RUN = ("--episodes", "1", "--condition", "given", "--condition", "switch:5", "--condition", "nonsense")


@pytest.mark.parametrize("workers", [["--workers", "0"], ["--workers", "2"], ["--workers", "2", "--shared-policy"]])
def test_every_query_carries_the_instruction_in_force(short_catalog, tmp_path, workers):
    run, logs = tmp_path / "run", tmp_path / "logs"
    logs.mkdir()
    policy = ["--policy", "tests.support.policies:InstructionLogPolicy", "--policy-arg", f"log_dir={logs}"]
    result = run_cli("eval", *policy, "--catalog", short_catalog, "--run", str(run), *_RUN, *workers, "--quiet")
    assert result.returncode == 0, result.stderr
    assert len(store_rows(run)) == 9
    _check_the_policy_saw_the_timeline(run, logs, 5)


def test_the_openpi_prompt_is_the_instruction_in_force(short_catalog, tmp_path):
    run, logs, port = tmp_path / "run", tmp_path / "logs", free_port()
    logs.mkdir()
    with running(langgap_serve(port, "tests.support.policies:InstructionLogPolicy", f"log_dir={logs}"), port):
        policy = ["--policy", "openpi", "--policy-arg", f"port={port}"]
        result = run_cli("eval", *policy, "--catalog", short_catalog, "--run", str(run), *_RUN, "--workers", "0")
    assert result.returncode == 0, result.stderr
    assert all(r["steps"] == SHORT_STEPS for r in store_rows(run))
    _check_the_policy_saw_the_timeline(run, logs, 5)


@pytest.fixture(scope="module")
def switched_references(tmp_path_factory):
    """oracle and blind on an extended task whose instruction switches from its source's at step 56, when
    the oracle is carrying the source task's bowl toward the plate (dropped there, it would do the source task)."""
    runs = {}
    for policy in ("oracle", "blind"):
        spec = RunSpec.create(policy, catalog="langgap99", tasks=EXTENDED, episodes=1, conditions=("switch:56",))
        runs[policy] = tmp_path_factory.mktemp(policy) / "run"
        evaluate(spec, runs[policy], ExecutionOptions(workers=0, progress=False))
    return {policy: store_rows(run)[0] for policy, run in runs.items()}


def test_the_oracle_follows_a_switch(switched_references, catalog):
    row = switched_references["oracle"]
    assert row["outcome"] == "success"
    assert json.loads(row["instructions"])[1][0] == 56
    # It put the bowl it carried down where no goal of the scene holds (not on the plate it was headed for).
    assert catalog.get(EXTENDED).source not in json.loads(row["reached"])


def test_blind_persists_by_construction(switched_references, catalog):
    row = switched_references["blind"]
    source = catalog.get(EXTENDED).source
    assert row["outcome"] == "persisted" and not row["success"]
    assert json.loads(row["reached"])[source] >= 56  # the first instruction's goal, reached after the switch


def test_the_oracle_closes_the_drawer_it_opened_when_the_new_goal_needs_it(tmp_path, catalog):
    """Under `open the middle drawer` the oracle has the middle drawer open by step 120; the switch asks for the
    bottom drawer, whose handle the open middle drawer overhangs: it pushes the middle one shut, then opens
    the bottom one (left open, the bottom drawer is never reached in the 300 steps)."""
    task = catalog.get("goal/s0/open-cabinet-bottom-drawer")
    spec = RunSpec.create("oracle", catalog="langgap99", tasks=task.id, episodes=1, conditions=("switch:120",))
    evaluate(spec, tmp_path / "run", ExecutionOptions(workers=0, progress=False))
    (row,) = store_rows(tmp_path / "run")
    assert json.loads(row["reached"])[task.source] < 120  # it had opened the middle drawer before the switch
    assert row["outcome"] == "success"
    assert json.loads(row["goals_at_end"]) == [task.id]  # the middle drawer is closed again
