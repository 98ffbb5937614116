"""The `lerobot` adapter and `--env.type=langgap`, with a real LeRobot policy (small, random weights).

Runs in the LeRobot environment (`./setup.sh` creates .venv-lerobot); skipped elsewhere.
"""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("lerobot", reason="LeRobot lives in .venv-lerobot (created by ./setup.sh)")

import torch  # noqa: E402
from lerobot.envs.utils import NEW_ROLLOUT_OPTION, preprocess_observation  # noqa: E402
from lerobot.processor.env_processor import LiberoProcessorStep  # noqa: E402

from langgap.engine.context import task_context  # noqa: E402
from langgap.engine.plan import episode_seed  # noqa: E402
from langgap.engine.rollout import env_options_for, run_episode  # noqa: E402
from langgap.errors import LangGapError  # noqa: E402
from langgap.lerobot_env import LangGapEnv  # noqa: E402
from langgap.lerobot_libero import robot_state  # noqa: E402
from langgap.policies import make_policy  # noqa: E402
from langgap.policies.lerobot import CheckpointError  # noqa: E402
from langgap.policies.openpi import OpenpiPolicy  # noqa: E402
from langgap.sim.env import EnvOptions, TaskEnv  # noqa: E402
from tests.support.harness import run_cli  # noqa: E402
from tests.support.lerobot_checkpoints import IMAGE_SIZE, N_ACTION_STEPS, diffusion_checkpoint, lora_adapter  # noqa: E402
from tests.support.servers import free_port, langgap_serve, running, subprocess_env  # noqa: E402

TASK_ID = "spatial/s0/black-bowl-1-on-plate"
SIBLING_ID = "spatial/s0/black-bowl-2-on-plate"
STEPS = 10


@pytest.fixture(scope="module")
def checkpoint(tmp_path_factory) -> Path:
    return diffusion_checkpoint(tmp_path_factory.mktemp("checkpoint"))


@pytest.fixture(scope="module")
def policy(checkpoint):
    return make_policy("lerobot", {"path": str(checkpoint.parent), "threads": "1"})


def short_task(catalog, task_id: str = TASK_ID):
    return dataclasses.replace(catalog.get(task_id), max_steps=STEPS)


def lerobot_libero_batch(env: TaskEnv, instruction: str) -> dict:
    """What `lerobot-eval` gives a policy on LIBERO: LeRobot's own functions on the raw render (LIBERO's upside-down
    orientation of the image taken where robosuite samples its observables) and robot state."""
    raw = {
        "pixels": {
            key: np.ascontiguousarray(env.render(camera)[::-1, ::-1])[None]
            for camera, key in (("agentview", "image"), ("robot0_eye_in_hand", "image2"))
        },
        "robot_state": robot_state(env.robosuite_observation, env.robosuite_env.robots[0].controller.ee_ori_mat),
    }
    raw["robot_state"] = _batched(raw["robot_state"])
    observation = preprocess_observation(raw)
    observation["task"] = [instruction]
    return LiberoProcessorStep().observation(observation)


def _batched(tree):
    return {k: _batched(v) for k, v in tree.items()} if isinstance(tree, dict) else tree[None]


def test_checkpoint_loads_with_its_processors_and_libero_spec(policy, checkpoint):
    assert policy.spec.cameras == ("agentview", "robot0_eye_in_hand")
    assert policy.spec.image_size == IMAGE_SIZE and (policy.spec.chunk, policy.spec.replan) == (1, 1)
    assert policy.config()["type"] == "diffusion" and policy.config()["n_action_steps"] == N_ACTION_STEPS
    assert policy.config()["path"] == str(checkpoint)
    with pytest.raises(CheckpointError, match="no LeRobot checkpoint"):
        make_policy("lerobot", {"path": str(checkpoint.parent / "missing")})


def test_a_missing_checkpoint_is_bad_input_before_the_run_starts(tmp_path):
    missing, run = tmp_path / "missing", tmp_path / "run"
    result = run_cli("eval", "--policy", "lerobot", "--policy-arg", f"path={missing}", "--run", str(run))
    assert result.returncode == 2, result.stderr
    expected = f"error: no LeRobot checkpoint at {missing} (expected config.json there or in pretrained_model/)\n"
    assert result.stderr == expected and not run.exists()


def test_policy_sees_what_lerobot_libero_pipeline_gives(policy, catalog):
    task = short_task(catalog)
    context = task_context(task, catalog, init_index=2, seed=4)
    with TaskEnv(task, env_options_for(policy)) as env:
        env.reset(2, seed=4)
        env.settle(capture=policy.spec.cameras)
        policy.reset(context)
        ours = policy.model_inputs(env.observe(policy.spec.cameras))
        theirs = lerobot_libero_batch(env, context.instruction)
        raw = env.sim.render(camera_name="agentview", width=IMAGE_SIZE, height=IMAGE_SIZE)
    assert set(ours) == {"observation.images.image", "observation.images.image2", "observation.state", "task"}
    for key in ("observation.images.image", "observation.images.image2"):
        assert ours[key].shape == (1, 3, IMAGE_SIZE, IMAGE_SIZE) and ours[key].dtype == torch.float32
        assert torch.equal(ours[key], theirs[key])  # upright: LeRobot's LiberoProcessorStep flips the raw render
    unrotated = torch.from_numpy(raw.copy()).permute(2, 0, 1)[None].float() / 255
    assert not torch.equal(ours["observation.images.image"], unrotated)
    assert ours["observation.state"].shape == (1, 8)
    torch.testing.assert_close(ours["observation.state"], theirs["observation.state"], atol=1e-6, rtol=0)
    assert ours["task"] == theirs["task"] == [task.instruction()]


def test_check_policy_shows_what_a_checkpoint_is_given_and_passes(checkpoint):
    """`langgap check-policy lerobot`: the page names the batch the checkpoint's preprocessor gets (the keys, dtypes
    and shapes of `test_policy_sees_what_lerobot_libero_pipeline_gives`), and the reseeded sampling policy gives the
    same actions on the same episode."""
    from langgap.diagnostics.policy_check import check_policy

    report = check_policy("lerobot", {"path": str(checkpoint.parent), "threads": "1"})
    assert report.exit_code == 0, report.page()
    (inputs,) = [c.detail for c in report.checks if c.name == "inputs"]
    image = f"float32 (1, 3, {IMAGE_SIZE}, {IMAGE_SIZE})"
    sends = (
        f"sends observation.images.image {image}, observation.images.image2 {image}, observation.state float32 (1, 8)"
    )
    assert f"{sends}, task ['pick up the black bowl between the plate and the ramekin and place it on the plate']" in (
        inputs
    )
    assert f"agentview uint8 ({IMAGE_SIZE}, {IMAGE_SIZE}, 3)" in inputs
    (determinism,) = [c.detail for c in report.checks if c.name == "determinism"]
    assert "gave the same actions" in determinism


def _episode(policy, catalog, init_index: int, seed: int) -> np.ndarray:
    task = short_task(catalog)
    actions: list[np.ndarray] = []
    with TaskEnv(task, env_options_for(policy)) as env:
        result = run_episode(
            env,
            policy,
            task_context(task, catalog, init_index=init_index, seed=seed),
            on_step=lambda _env, _i, action: actions.append(action),
        )
    assert result.steps == STEPS and result.policy_calls == STEPS
    return np.array(actions)


def test_chunking_follows_checkpoint_and_seed_makes_episodes_reproducible(policy, catalog):
    model = policy.model
    inferences = []
    original = model.predict_action_chunk
    model.predict_action_chunk = lambda *args, **kwargs: inferences.append(1) or original(*args, **kwargs)
    try:
        first = _episode(policy, catalog, init_index=0, seed=1)
    finally:
        del model.predict_action_chunk
    assert len(inferences) == -(-STEPS // N_ACTION_STEPS)  # one model call per chunk of n_action_steps
    assert first.shape == (STEPS, 7) and np.all(np.abs(first) <= 1.0 + 1e-6)
    np.testing.assert_array_equal(_episode(policy, catalog, init_index=0, seed=1), first)
    assert not np.array_equal(_episode(policy, catalog, init_index=0, seed=2), first)  # diffusion samples noise


def test_the_task_string_is_the_instruction_in_force_and_a_switch_drops_the_queued_chunk(policy, catalog):
    task, switch = short_task(catalog), 3  # before the first chunk of n_action_steps is played out
    sibling = catalog.get(SIBLING_ID).instruction()
    tasks, inferences = [], []
    batch, chunk = policy.model_inputs, policy.model.predict_action_chunk
    policy.model_inputs = lambda observation: (b := batch(observation)) and tasks.append(b["task"]) or b
    policy.model.predict_action_chunk = lambda *args, **kwargs: inferences.append(len(tasks)) or chunk(*args, **kwargs)
    try:
        with TaskEnv(task, env_options_for(policy)) as env:
            context = task_context(task, catalog, init_index=0, seed=1, instruction=sibling)
            result = run_episode(env, policy, context, changes=((switch, task.instruction()),))
    finally:
        del policy.model_inputs, policy.model.predict_action_chunk
    assert result.instructions == [(0, sibling), (switch, task.instruction())]
    assert tasks == [[sibling]] * switch + [[task.instruction()]] * (STEPS - switch)
    assert inferences[:2] == [1, switch + 1]  # asked anew at the switch, not after the old chunk ran out


def test_lora_adapter_on_top_of_checkpoint(policy, checkpoint, catalog, tmp_path):
    from peft import PeftModel

    adapter = lora_adapter(checkpoint, tmp_path / "lora")
    tuned = make_policy("lerobot", {"path": str(checkpoint), "adapter": str(adapter), "threads": "1"})
    assert isinstance(tuned.model, PeftModel) and tuned.config()["adapter"] == str(adapter)
    with_lora = _episode(tuned, catalog, init_index=0, seed=1)
    assert not np.array_equal(with_lora, _episode(policy, catalog, init_index=0, seed=1))
    np.testing.assert_array_equal(with_lora, _episode(tuned, catalog, init_index=0, seed=1))


@pytest.mark.slow
def test_served_checkpoint_matches_in_process(policy, checkpoint, catalog):
    """A checkpoint behind `langgap serve`, driven by the `openpi` policy: the same episodes as in process."""
    port = free_port()
    serve = langgap_serve(port, "lerobot", f"path={checkpoint}", "threads=1")
    with running(serve, port, env=subprocess_env(OMP_NUM_THREADS="1"), startup=180):
        remote = OpenpiPolicy(port=port, connect_timeout=120)
        assert remote.spec == policy.spec
        served = [_episode(remote, catalog, init_index=1, seed=seed) for seed in (3, 4)]
        remote.close()
    for seed, actions in zip((3, 4), served, strict=True):
        np.testing.assert_array_equal(actions, _episode(policy, catalog, init_index=1, seed=seed))


def test_env_type_applies_init_states_instruction_and_lerobot_orientation(catalog):
    config = LangGapEnv(task=TASK_ID, episode_length=STEPS, observation_height=48, observation_width=48)
    (vector,) = config.create_envs(n_envs=2)[TASK_ID].values()
    processor = LiberoProcessorStep()
    reference = TaskEnv(short_task(catalog), EnvOptions(cameras=("agentview",), image_size=48))
    try:
        assert list(vector.call("task_description")) == [catalog.get(TASK_ID).instruction()] * 2
        assert list(vector.call("_max_episode_steps")) == [STEPS, STEPS]
        for batch, seeds in enumerate(([10, 11], [12, 13])):
            raw, info = vector.reset(seed=seeds, options={NEW_ROLLOUT_OPTION: True})
            assert list(info["init_index"]) == [2 * batch, 2 * batch + 1]  # LeRobot's scheme: episode k, init k
            seen = processor.observation(preprocess_observation(raw))
            for index, seed in enumerate(seeds):
                # LangGap's seed rule (langgap.gym): env seed = the seed LeRobot passes + the init index
                reference.reset(2 * batch + index, seed=episode_seed(seed, 2 * batch + index))
                reference.settle(capture=("agentview",))
                expected = torch.from_numpy(reference.render("agentview").copy()).permute(2, 0, 1).float() / 255
                assert torch.equal(seen["observation.images.image"][index], expected)
    finally:
        reference.close()
        vector.close()
    with pytest.raises(LangGapError, match="does not support changing task_ids"):
        LangGapEnv(task_ids=[0])


def test_lerobot_libero_settings_are_the_parity_pages():
    """docs/parity.md's `lerobot-eval` column: `--env.type=libero`'s own step limits (280 on libero_spatial,
    where openpi uses 220) and render size (360), and `--env.type=langgap`'s defaults (openpi's step limit,
    LeRobot's render size) with the flag that reproduces LeRobot's limit."""
    from lerobot.envs.configs import LiberoEnv as LiberoConfig
    from lerobot.envs.libero import TASK_SUITE_MAX_STEPS

    lerobot_limits = {"libero_spatial": 280, "libero_object": 280, "libero_goal": 300, "libero_10": 520}
    assert {suite: TASK_SUITE_MAX_STEPS[suite] for suite in lerobot_limits} == lerobot_limits
    libero, ours = LiberoConfig(), LangGapEnv(task=TASK_ID)
    assert (libero.observation_height, libero.observation_width) == (360, 360)
    assert (ours.observation_height, ours.observation_width) == (360, 360)
    for config, limit in ((ours, 220), (LangGapEnv(task=TASK_ID, episode_length=280), 280)):
        (vector,) = config.create_envs(n_envs=1)[TASK_ID].values()
        try:
            assert list(vector.call("_max_episode_steps")) == [limit]
        finally:
            vector.close()


@pytest.mark.slow
def test_lerobot_eval_runs_langgap_tasks(checkpoint, tmp_path):
    output = tmp_path / "eval"
    command = [
        str(Path(sys.executable).with_name("lerobot-eval")),
        f"--policy.path={checkpoint}",
        "--policy.device=cpu",
        "--env.type=langgap",
        f"--env.task={TASK_ID},{SIBLING_ID}",
        f"--env.episode_length={STEPS}",
        "--env.observation_height=48",
        "--env.observation_width=48",
        "--eval.n_episodes=1",
        "--eval.batch_size=1",
        "--seed=5",
        f"--output_dir={output}",
    ]
    env = subprocess_env(OMP_NUM_THREADS="1")
    done = subprocess.run(command, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    info = json.loads((output / "eval_info.json").read_text())
    per_task = {entry["task_group"]: entry for entry in info["per_task"]}
    assert set(per_task) == {TASK_ID, SIBLING_ID}
    for entry in per_task.values():
        assert entry["metrics"]["successes"] == [False]  # random weights: the plumbing, not the policy
    assert info["overall"]["n_episodes"] == 2
