"""`langgap.gym`: LangGap tasks as Gymnasium environments (real LIBERO simulation, real worker processes)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.error import ResetNeeded
from gymnasium.utils.env_checker import check_env

import langgap.gym  # noqa: F401  (registers the ids)
from langgap.errors import LangGapError
from langgap.gym import LangGapTaskEnv, policy_observation
from langgap.policies import make_policy
from tests.support.doc_blocks import blocks, run_block, sandbox
from tests.support.harness import REPO, SHORT_STEPS, TINY_TASK, run_cli, store_rows

SIBLING = "spatial/s0/black-bowl-2-on-plate"


@pytest.mark.parametrize(
    "config",
    [{}, {"cameras": ("agentview", "robot0_eye_in_hand"), "image_size": 32, "render_mode": "rgb_array"}],
    ids=["image-less", "images"],
)
def test_gymnasium_env_checker_passes(short_catalog, config):
    env = gym.make("LangGap/Task-v0", task=TINY_TASK, catalog=short_catalog, **config)
    try:
        check_env(env.unwrapped, skip_render_check=False)
        obs, _ = env.reset(seed=1, options={"init_index": 0})
        assert set(obs) == {*config.get("cameras", ()), "state", "instruction"}
        for camera in config.get("cameras", ()):
            assert obs[camera].shape == (32, 32, 3) and obs[camera].dtype == np.uint8
        if config:
            frame = env.render()
            np.testing.assert_array_equal(frame, obs["agentview"])  # render() is the observed agentview frame
    finally:
        env.close()


def test_reset_follows_the_harness_seed_rule_and_keeps_the_global_rng(short_catalog):
    env = gym.make("LangGap/Task-v0", task=TINY_TASK, catalog=short_catalog)
    reference = LangGapTaskEnv(SIBLING, catalog=short_catalog)
    try:
        with pytest.raises(ResetNeeded):
            env.unwrapped.step(np.zeros(7))  # the bare env, not only Gymnasium's order-enforcing wrapper
        np.random.seed(123)
        before = np.random.get_state()
        obs, info = env.reset(seed=5, options={"init_index": 2})
        after = np.random.get_state()
        assert all(np.array_equal(a, b) for a, b in zip(before[1:], after[1:], strict=True))
        assert (info["init_index"], info["seed"]) == (2, 7)  # env seed = run seed + init index, as `langgap eval`
        assert obs["instruction"] == env.unwrapped.task.instruction()
        assert info["context"].privileged is None and "privileged" not in obs
        # Siblings on the same plan entry start from the same simulator state.
        _, sibling = reference.reset(seed=5, options={"init_index": 2})
        assert sibling["t0_hash"] == info["t0_hash"] and sibling["instruction_sha256"] != info["instruction_sha256"]
        # No seed: the last run seed is kept; no init index: drawn from the env's np_random.
        _, again = env.reset(options={"init_index": 2})
        assert (again["seed"], again["t0_hash"]) == (7, info["t0_hash"])
        drawn = [env.reset(seed=9)[1]["init_index"] for _ in range(2)]
        assert drawn[0] == drawn[1] and {env.reset()[1]["init_index"] for _ in range(6)} != {drawn[0]}
        with pytest.raises(LangGapError, match="init_index must be an integer in 0..49"):
            env.reset(options={"init_index": 50})
        with pytest.raises(LangGapError, match="unknown reset option"):
            env.reset(options={"init": 1})
    finally:
        env.close()
        reference.close()


def test_episode_truncates_at_the_step_limit_and_must_be_reset(short_catalog):
    env = gym.make("LangGap/Task-v0", task=TINY_TASK, catalog=short_catalog)
    try:
        env.reset(seed=0, options={"init_index": 0, "condition": "empty"})
        hold = np.array([0, 0, 0, 0, 0, 0, -1.0])
        ends = [env.step(hold)[2:4] for _ in range(SHORT_STEPS)]
        assert ends == [(False, False)] * (SHORT_STEPS - 1) + [(False, True)]
        with pytest.raises(ResetNeeded, match="episode is over"):
            env.unwrapped.step(hold)
        obs, info = env.reset(options={"init_index": 0, "condition": "empty"})
        assert obs["instruction"] == "" and info["steps"] == 0
    finally:
        env.close()
    assert env.unwrapped._sim is None  # the simulator is freed


def _gym_oracle_episode(init_index: int, seed: int) -> dict:
    env = gym.make("LangGap/Task-v0", task=TINY_TASK, privileged=True)
    oracle = make_policy("oracle")
    try:
        obs, info = env.reset(seed=seed, options={"init_index": init_index})
        assert "privileged" in obs and info["context"].privileged is not None
        oracle.reset(info["context"])
        rewards = []
        while True:
            obs, reward, terminated, truncated, info = env.step(oracle.act(policy_observation(obs)))
            rewards.append(reward)
            if terminated or truncated:
                break
        assert sum(rewards) == (1.0 if terminated else 0.0) and rewards[-1] == sum(rewards)
        return info
    finally:
        env.close()


@pytest.mark.slow
def test_one_episode_two_doors_oracle_through_gym_equals_langgap_eval(tmp_path):
    run = tmp_path / "run"
    result = run_cli(
        "eval", "--policy", "oracle", "--tasks", TINY_TASK, "--episodes", "2", "--seed", "3", "--run", str(run)
    )
    assert result.returncode == 0, result.stderr
    rows = store_rows(run)
    assert len(rows) == 2
    for row in rows:
        info = _gym_oracle_episode(row["init_index"], seed=3)
        assert info["seed"] == row["seed"] and info["t0_hash"] == row["t0_hash"]
        assert info["instruction_sha256"] == row["instruction_sha256"]
        assert (info["steps"], info["is_success"]) == (row["steps"], bool(row["success"]))
        assert info["outcome"] == row["outcome"]
        assert info["reached"] == json.loads(row["reached"])
    assert any(row["success"] for row in rows)


def test_async_vector_env_in_spawned_workers_autoresets_next_step(short_catalog):
    envs = gym.make_vec(
        "LangGap/Task-v0",
        num_envs=2,
        vectorization_mode="async",
        vector_kwargs={"context": "spawn"},
        task=TINY_TASK,
        catalog=short_catalog,
    )
    single = LangGapTaskEnv(TINY_TASK, catalog=short_catalog)
    try:
        assert envs.metadata["autoreset_mode"] == gym.vector.AutoresetMode.NEXT_STEP
        obs, info = envs.reset(seed=10)
        for i in range(2):  # sub-env i is seeded 10 + i; its init index is drawn from that seed
            reference, expected = single.reset(seed=10 + i)
            assert (info["init_index"][i], info["t0_hash"][i]) == (expected["init_index"], expected["t0_hash"])
            np.testing.assert_array_equal(obs["state"][i], reference["state"])
        hold = np.tile([0, 0, 0, 0, 0, 0, -1.0], (2, 1))
        for _ in range(SHORT_STEPS):
            obs, _, terminated, truncated, info = envs.step(hold)
        assert truncated.all() and not terminated.any()
        obs, reward, terminated, truncated, info = envs.step(hold)  # Gymnasium 1.x: this step resets
        assert list(info["steps"]) == [0, 0] and not (terminated | truncated).any() and not reward.any()
    finally:
        envs.close()
        single.close()


def test_same_scene_vector_env_holds_the_sibling_tasks_on_one_init_state(short_catalog):
    envs = gym.make_vec("LangGap/SameScene-v0", scene="spatial/s0", num_envs=3, catalog=short_catalog)
    try:
        assert envs.unwrapped.tasks == [TINY_TASK, SIBLING, "spatial/s0/open-cabinet-top-drawer"]
        for seed in (1, 2):
            obs, info = envs.reset(seed=seed)
            assert len(set(info["t0_hash"])) == 1 and len(set(info["init_index"])) == 1
            assert len(set(obs["instruction"])) == 3  # only the instruction differs
            np.testing.assert_array_equal(obs["state"][0], obs["state"][1])
        actions = np.tile([0, 0, 0, 0, 0, 0, -1.0], (3, 1))
        for _ in range(SHORT_STEPS + 2):  # ended sub-envs stay ended (latched) until the next reset
            obs, reward, terminated, truncated, info = envs.step(actions)
        assert truncated.all() and not reward.any()
        _, info = envs.reset(options={"init_index": 4})
        assert list(info["init_index"]) == [4, 4, 4]
    finally:
        envs.close()
    with pytest.raises(LangGapError, match="has 3 sibling tasks"):
        gym.make_vec("LangGap/SameScene-v0", scene=TINY_TASK, num_envs=4, catalog=short_catalog)


def test_registered_through_the_module_id_in_a_fresh_interpreter():
    code = (
        f"import gymnasium as gym; env = gym.make('langgap.gym:LangGap/Task-v0', task='{TINY_TASK}');"
        "print(type(env.unwrapped).__name__, env.action_space.shape)"
    )
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, env=env)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["LangGapTaskEnv", "(7,)"]


@pytest.mark.slow
def test_docs_examples_run_as_shown(tmp_path):
    examples = [b for b in blocks("docs/gymnasium.md") if b.language == "python"]
    assert len(examples) == 3
    root = sandbox(tmp_path / "repo")
    outputs = []
    for block in examples:
        done = run_block(block, root)
        assert done.returncode == 0, done.stderr[-3000:]
        outputs.append(done.stdout.split("\n"))
    assert outputs[0][0].split()[2:4] == ["(128,", "128,"]
    assert outputs[1][0].split()[0] == "True"  # the oracle succeeds through the gym door
    assert "spatial/s0/black-bowl-1-on-plate" in outputs[2][1]


def test_a_switch_changes_the_observed_instruction_at_step_k_and_info_says_persisted(catalog):
    """`blind` through the env under `switch:56` on an extended task: the instruction the policy sees is the
    source's until step 56, then the task's own; blind does the source's task anyway, after the switch."""
    task = catalog.get(SIBLING)
    env = gym.make("LangGap/Task-v0", task=SIBLING, privileged=True)
    blind = make_policy("blind")
    try:
        obs, info = env.reset(seed=0, options={"init_index": 0, "condition": "switch:56"})
        first = catalog.get(task.source).instruction()
        assert info["instructions"] == [(0, first)]
        blind.reset(info["context"])
        seen = []
        while True:
            seen.append(obs["instruction"])
            obs, _, terminated, truncated, info = env.step(blind.act(policy_observation(obs)))
            if terminated or truncated:
                break
        assert seen[:56] == [first] * 56 and set(seen[56:]) == {task.instruction()}
        assert info["instructions"] == [(0, first), (56, task.instruction())]
        assert info["outcome"] == "persisted" and not info["is_success"] and info["reached"][task.source] >= 56
    finally:
        env.close()


def test_nonsense_and_malformed_switches_at_reset(short_catalog):
    from langgap.catalog.catalog import load_catalog
    from langgap.engine.plan import condition_instruction

    catalog = load_catalog(short_catalog)
    env = LangGapTaskEnv(TINY_TASK, catalog=short_catalog)
    try:
        obs, info = env.reset(seed=0, options={"init_index": 1, "condition": "nonsense"})
        assert obs["instruction"] == condition_instruction(catalog.get(TINY_TASK), catalog, "nonsense", "libero", 1)
        assert info["instructions"] == [(0, obs["instruction"])] and obs["instruction"] != env.task.instruction()
        with pytest.raises(LangGapError, match="unknown condition 'switch:x'"):
            env.reset(options={"condition": "switch:x"})
        with pytest.raises(LangGapError, match=f"ends at step {SHORT_STEPS}, before its instruction would switch"):
            env.reset(options={"condition": f"switch:{SHORT_STEPS}"})
    finally:
        env.close()
