"""Shared rollouts (`--share-rollouts`): an instruction-blind policy's episodes that start alike run as one rollout,
and every record equals the one its own episode gives (real simulation, real worker processes, real stores)."""

from __future__ import annotations

import json
import shutil
import sqlite3

import pytest

from tests.support.catalogs import cut_down_catalog
from tests.support.harness import TINY_TASK, run_cli, store_rows

# Measured, not results: how long it took, when it ended, which worker ran it.
MEASURED = {"wall_time_s", "finished_at", "worker"}
# `blind` puts bowl 1 on the plate (its source task) in about 70 steps: the source succeeds early, its
# siblings run to the limit and record the source's goal as reached instead.
STEPS = 90
SCENE_TASKS = (TINY_TASK, "spatial/s0/black-bowl-2-on-plate", "spatial/s0/open-cabinet-top-drawer")
# switch:20 switches before the source's early success, switch:80 after it: a member that ended first never sent it.
SWITCHES = ("--condition", "switch:20", "--condition", "switch:80")
BLIND = ("--policy", "blind", "--episodes", "2", "--condition", "given", "--condition", "nonsense", *SWITCHES)


@pytest.fixture(scope="module")
def scene_catalog(tmp_path_factory):
    """Three tasks of one scene (spatial/s0, the source among them) with a 90-step limit."""
    return str(cut_down_catalog(tmp_path_factory.mktemp("catalog") / "scene.yaml", SCENE_TASKS, steps=STEPS))


@pytest.fixture(scope="module")
def runs(scene_catalog, tmp_path_factory):
    """The same `blind` plan run episode by episode (in this process) and with shared rollouts (a worker process)."""
    root = tmp_path_factory.mktemp("runs")
    common = (*BLIND, "--catalog", scene_catalog, "--no-progress", "--quiet")
    separate = run_cli("eval", *common, "--workers", "0", "--run", str(root / "separate"))
    assert separate.returncode == 0, separate.stderr
    shared = run_cli("eval", *common, "--workers", "1", "--share-rollouts", "--run", str(root / "shared"))
    assert shared.returncode == 0, shared.stderr
    return root, shared.stdout


def _results(run) -> list[dict]:
    return [{k: v for k, v in row.items() if k not in MEASURED} for row in store_rows(run)]


def test_shared_rollouts_give_each_episode_its_own_record(runs):
    """`eval --share-rollouts` (`runs`): every field but the measured ones equals the separate run's."""
    root, stdout = runs
    # 3 tasks x 2 conditions share one rollout per init state; the switch:K episodes one per init state and K.
    assert "shared rollouts: 24 episodes in 6 rollouts" in stdout
    separate, shared = _results(root / "separate"), _results(root / "shared")
    assert len(separate) == 24
    assert shared == separate
    switched = [r for r in shared if r["condition"].startswith("switch:")]
    assert {r["outcome"] for r in switched} >= {"persisted", "success"}
    assert {len(json.loads(r["instructions"])) for r in switched if r["condition"] == "switch:80" and r["success"]} == {
        1
    }
    shared = [r for r in shared if not r["condition"].startswith("switch:")]
    # What the cut has to get right: a member that ends early, members that run on past it to the limit
    # and see its goal reached instead, each with its own end state, policy calls and instruction.
    early = [r for r in shared if r["success"]]
    late = [r for r in shared if not r["success"]]
    assert early and all(r["task_id"] == TINY_TASK and r["steps"] < STEPS for r in early)
    assert late and all(r["steps"] == STEPS and TINY_TASK in r["reached"] for r in late)
    assert {r["policy_calls"] for r in early} != {STEPS}
    for init in (0, 1):  # six instructions in one rollout, each member's record with its own
        assert len({r["instruction"] for r in shared if r["init_index"] == init}) == 6


def test_a_resumed_shared_run_reruns_only_the_missing_members_of_a_rollout(runs, scene_catalog):
    """`--resume --share-rollouts` runs a rollout whose members are partly stored, for the missing ones only."""
    root, _ = runs
    resumed = root / "resumed"
    shutil.copytree(root / "shared", resumed)
    db = sqlite3.connect(resumed / "episodes.sqlite")
    with db:  # an interrupted run: two members of init state 1's rollout never stored
        db.execute(
            "DELETE FROM episodes WHERE init_index = 1 AND condition = 'nonsense' AND task_id != ?", (TINY_TASK,)
        )
    db.close()
    common = (*BLIND, "--catalog", scene_catalog, "--no-progress", "--quiet", "--share-rollouts")
    result = run_cli("eval", *common, "--workers", "0", "--run", str(resumed), "--resume")
    assert result.returncode == 0, result.stderr
    assert "22 already stored, 2 run" in result.stdout
    assert "shared rollouts: 2 episodes in 1 rollouts" in result.stdout
    assert _results(resumed) == _results(root / "separate")
    again = run_cli("eval", *common, "--workers", "0", "--run", str(resumed), "--resume")
    assert "24 already stored, 0 run" in again.stdout and "shared rollouts" not in again.stdout


def test_a_malformed_action_ends_every_member_still_running_as_its_own_episode_would(short_catalog, tmp_path):
    """`ErrsOnInitsPolicy` holds still (instruction-blind, as `noop`) and errs at its 5th call on init state 0."""
    policy = ("--policy", "tests.support.policies:ErrsOnInitsPolicy", "--policy-arg", "inits=0")
    common = (*policy, "--catalog", short_catalog, "--episodes", "2", "--workers", "0", "--no-progress", "--quiet")
    separate = run_cli("eval", *common, "--run", str(tmp_path / "separate"))
    shared = run_cli("eval", *common, "--share-rollouts", "--run", str(tmp_path / "shared"))
    assert separate.returncode == shared.returncode == 0, shared.stderr
    assert "shared rollouts: 6 episodes in 2 rollouts" in shared.stdout
    rows = _results(tmp_path / "shared")
    assert rows == _results(tmp_path / "separate")
    assert {(r["init_index"], r["outcome"]) for r in rows} == {(0, "policy_error"), (1, "no_goal_reached")}


def test_a_failure_after_a_member_ended_keeps_its_record_and_leaves_the_rest_as_gaps(scene_catalog, tmp_path):
    """`BlindFailingAt` fails at its 80th call: after the source's success (about step 70), before the limit."""
    policy = ("--policy", "tests.support.policies:BlindFailingAt", "--max-attempts", "1", "--episodes", "1")
    common = (*policy, "--catalog", scene_catalog, "--workers", "1", "--no-progress", "--quiet")
    separate = run_cli("eval", *common, "--run", str(tmp_path / "separate"))
    shared = run_cli("eval", *common, "--share-rollouts", "--run", str(tmp_path / "shared"))
    assert separate.returncode == shared.returncode == 3, shared.stderr  # a run that ends with gaps
    assert "shared rollouts: 3 episodes in 1 rollouts" in shared.stdout
    judged = [[r for r in _results(tmp_path / run) if r["status"] == "done"] for run in ("separate", "shared")]
    assert judged[0] == judged[1] and [r["task_id"] for r in judged[1]] == [TINY_TASK]
    gaps = [[r["task_id"] for r in _results(tmp_path / run) if r["status"] == "gap"] for run in ("separate", "shared")]
    assert gaps[0] == gaps[1] and len(gaps[1]) == 2


def test_a_policy_that_reads_its_instruction_never_shares_a_rollout(short_catalog, tmp_path):
    """`InstructionLogPolicy` holds still like `noop` but reads its instruction: each episode is its own."""
    logs = tmp_path / "logs"
    logs.mkdir()
    policy = ("--policy", "tests.support.policies:InstructionLogPolicy", "--policy-arg", f"log_dir={logs}")
    result = run_cli(
        *("eval", *policy, "--catalog", short_catalog, "--episodes", "1", "--share-rollouts"),
        *("--workers", "0", "--no-progress", "--quiet", "--run", str(tmp_path / "run")),
    )
    assert result.returncode == 0, result.stderr
    assert "shared rollouts" not in result.stdout
    told = sorted({line for log in logs.iterdir() for line in log.read_text().splitlines()})
    assert len(list(logs.iterdir())) == 3
    assert told == sorted(r["instruction"] for r in store_rows(tmp_path / "run"))


def test_validate_blind_shares_the_blind_rollouts_only(runs, scene_catalog, tmp_path):
    """`validate --blind --share-rollouts`: `blind`'s episodes share rollouts (records as the separate run's),
    the oracle's run on their own (it reads its instruction: each task reached by its own plan)."""
    root, _ = runs
    run = tmp_path / "gate"
    result = run_cli(
        *("validate", "all", "--catalog", scene_catalog, "--inits", "1", "--blind", "--share-rollouts"),
        *("--search-budget", "0", "--workers", "0", "--no-progress", "--run", str(run)),
    )
    assert "error" not in result.stderr, result.stderr
    separate = [r for r in _results(root / "separate") if r["init_index"] == 0 and r["condition"] == "given"]
    assert _results(tmp_path / "gate-blind") == separate
    oracle = {r["task_id"]: r for r in store_rows(run)}
    # One rollout would have followed one task's plan (bowl 1 onto the plate) for all three.
    assert oracle["spatial/s0/open-cabinet-top-drawer"]["success"]
    assert TINY_TASK not in oracle["spatial/s0/black-bowl-2-on-plate"]["reached"]
