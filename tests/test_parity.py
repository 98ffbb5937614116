"""Parity with openpi's LIBERO evaluation (`examples/libero/main.py`), bit for bit.

The example's loop is written here from its published logic: a fresh `OffScreenRenderEnv` rendering both
cameras at 256x256, `env.seed(seed)`, `reset()`, `set_init_state`, 10 no-op steps with the gripper open,
then the policy's actions, re-planning every 5; each image it sends is robosuite's camera observation
rotated 180 degrees and resized with padding to 224; its state is end-effector position, axis-angle
orientation and gripper joints. LangGap's episode of the same plan entry runs through its openpi client
against a recording openpi server; every state and every image sent must be the same, bit for bit.
"""

from __future__ import annotations

import collections
import json

import numpy as np
import pytest
from openpi_client import image_tools

from langgap.catalog import files
from langgap.catalog.catalog import load_catalog_file
from langgap.engine.context import task_context
from langgap.engine.rollout import env_options_for, run_episode
from langgap.policies import make_policy, protocol
from langgap.policies.openpi import OpenpiPolicy
from langgap.sim.env import EnvOptions, TaskEnv, quat_to_axis_angle
from tests.support.harness import run_cli, store_rows
from tests.support.policies import Reach
from tests.support.servers import free_port, helper_server, running, subprocess_env

TASK_ID = "spatial/s0/black-bowl-1-on-plate"
INIT_INDEX, SEED = 0, 0
EXAMPLE_SETTLE = 10  # the example's num_steps_wait
EXAMPLE_REPLAN = 5
EXAMPLE_RESOLUTION = 256
EXAMPLE_RESIZE = 224
DUMMY_ACTION = [0.0] * 6 + [-1.0]
# One task of every suite: the whole oracle episode (grasps, places, a knob, two objects) must match.
SAMPLE = (
    TASK_ID,
    "object/s0/alphabet-soup-in-basket",
    "goal/s1/black-bowl-on-stove",
    "libero10/s2/turn-on-stove+moka-pot-on-stove",
)


def oracle_actions(task, catalog) -> np.ndarray:
    """The oracle's actions on the plan entry (recorded once, replayed open-loop by both loops below)."""
    oracle = make_policy("oracle", {})
    actions: list[np.ndarray] = []
    with TaskEnv(task, env_options_for(oracle)) as env:
        context = task_context(task, catalog, init_index=INIT_INDEX, seed=SEED)
        result = run_episode(env, oracle, context, on_step=lambda _e, _i, action: actions.append(np.array(action)))
    assert result.success, "the oracle must finish the task: the parity must hold through a grasp and a place"
    return np.array(actions)


def example_state(obs: dict) -> np.ndarray:
    """The example's 8-D state: end-effector position, axis-angle orientation, gripper joints."""
    return np.concatenate(
        (obs["robot0_eef_pos"], quat_to_axis_angle(obs["robot0_eef_quat"]), obs["robot0_gripper_qpos"])
    )


def raw_observations(task, cameras, size, seed, init_index, actions, settle=0) -> list[dict[str, np.ndarray]]:
    """The raw LIBERO env (robosuite's camera observations at `size`, `env.seed(seed)`, init state `init_index`):
    after `settle` no-op steps (their last observation first, where there are any) and after each action, the
    simulator state (`sim`), the 8-D state (`state`) and each camera's image, upright."""
    from libero.libero.envs import OffScreenRenderEnv

    def seen(obs) -> dict[str, np.ndarray]:
        images = {c: obs[f"{c}_image"][::-1, ::-1].copy() for c in cameras}
        return {"sim": raw.get_sim_state().copy(), "state": example_state(obs)} | images

    # The raw env first and alone: two simulators rendering in one process share one current GL context.
    raw = OffScreenRenderEnv(bddl_file_name=str(files.task_bddl_path(task)), camera_heights=size, camera_widths=size)
    try:
        raw.seed(seed)
        raw.reset()
        raw.set_init_state(files.init_states(task)[init_index])
        observed = []
        for _ in range(settle):
            obs, _, _, _ = raw.step(DUMMY_ACTION)
        if settle:
            observed.append(seen(obs))
        for action in actions:
            obs, _, _, _ = raw.step(action.tolist())
            observed.append(seen(obs))
    finally:
        raw.close()
    return observed


def example_episode(task, actions: np.ndarray) -> tuple[list[np.ndarray], list[dict]]:
    """openpi's LIBERO example loop on a fresh LIBERO env: the simulator state after every policy step, and
    every observation sent (the settled state first)."""
    from libero.libero.envs import OffScreenRenderEnv

    env = OffScreenRenderEnv(
        bddl_file_name=str(files.task_bddl_path(task)),
        camera_heights=EXAMPLE_RESOLUTION,
        camera_widths=EXAMPLE_RESOLUTION,
    )
    try:
        env.seed(SEED)
        env.reset()
        obs = env.set_init_state(files.init_states(task)[INIT_INDEX])
        states, sent, plan = [], [], collections.deque()
        for _ in range(EXAMPLE_SETTLE):
            obs, _, _, _ = env.step(DUMMY_ACTION)
        states.append(env.get_sim_state().copy())
        for step in range(len(actions)):
            if not plan:
                image = np.ascontiguousarray(obs["agentview_image"][::-1, ::-1])
                wrist = np.ascontiguousarray(obs["robot0_eye_in_hand_image"][::-1, ::-1])
                sent.append(
                    {
                        "observation/image": image_tools.resize_with_pad(image, EXAMPLE_RESIZE, EXAMPLE_RESIZE),
                        "observation/wrist_image": image_tools.resize_with_pad(wrist, EXAMPLE_RESIZE, EXAMPLE_RESIZE),
                        "observation/state": example_state(obs),
                    }
                )
                plan.extend(actions[step : step + EXAMPLE_REPLAN])  # the server's chunk, first 5 executed
            obs, _, done, _ = env.step(plan.popleft().tolist())
            states.append(env.get_sim_state().copy())
            if done:
                assert step == len(actions) - 1, "the example ended before LangGap's episode did"
    finally:
        env.close()
    return states, sent


@pytest.mark.slow
@pytest.mark.parametrize("stepping", ["exact", "robosuite"])
@pytest.mark.parametrize("task_id", SAMPLE)
def test_episode_is_openpis_example_bit_for_bit(catalog, tmp_path, task_id, stepping):
    task = catalog.get(task_id)
    actions = oracle_actions(task, catalog)
    np.save(tmp_path / "actions.npy", actions)
    expected_states, expected_sent = example_episode(task, actions)

    port = free_port()
    env_vars = subprocess_env(RECORD_DIR=str(tmp_path), REPLY_ACTIONS=str(tmp_path / "actions.npy"))
    with running(helper_server("openpi-record", port), port, env=env_vars):
        policy = OpenpiPolicy(port=port)
        states = []
        with TaskEnv(task, env_options_for(policy, stepping=stepping)) as env:
            # What ran before on the same env (another init state, other actions) must not matter.
            env.reset(3, seed=5, render=False)
            env.settle()
            for action in np.random.default_rng(0).uniform(-1, 1, (8, 7)):
                env.step(action)
            context = task_context(task, catalog, init_index=INIT_INDEX, seed=SEED)
            renders = env.renders
            result = run_episode(
                env,
                policy,
                context,
                on_start=lambda e: states.append(e.sim_state().copy()),
                on_step=lambda e, _i, _a: states.append(e.sim_state().copy()),
            )
            renders = env.renders - renders
        policy.close()

    assert result.success and result.steps == len(actions) == len(expected_states) - 1
    for step, (state, expected) in enumerate(zip(states, expected_states, strict=True)):
        assert np.array_equal(state, expected), f"state after policy step {step} differs from the example's"
    sent = [dict(np.load(path)) for path in sorted(tmp_path.glob("0*.npz"))]
    assert len(sent) == len(expected_sent) == result.policy_calls
    for call, (got, want) in enumerate(zip(sent, expected_sent, strict=True)):
        for key, value in want.items():
            if key == protocol.STATE_KEY:
                value = value.astype(np.float32)
            assert got[key].dtype == value.dtype and np.array_equal(got[key], value), f"query {call}: {key} differs"
    # One render per camera per query; the images for the query after the last step are taken inside that
    # step, before it is known that the goal holds there: at most one set more per episode.
    assert 2 * result.policy_calls <= renders <= 2 * (result.policy_calls + 1)


@pytest.mark.parametrize("stepping", ["exact", "robosuite"])
def test_images_are_robosuites_camera_observations(catalog, stepping):
    """The images `step(capture=...)` takes are robosuite's camera observations of the same step (the raw
    LIBERO env with camera observations on, from the same init state), rotated upright; the state is the
    same to the last bit; steps that capture nothing render nothing."""
    task = catalog.get(TASK_ID)
    cameras = ("agentview", "robot0_eye_in_hand")
    size, init_index = 128, 2
    actions = np.random.default_rng(1).uniform(-0.5, 0.5, (6, 7))
    expected = raw_observations(task, cameras, size, SEED, init_index, actions)
    with TaskEnv(task, EnvOptions(cameras=cameras, image_size=size, stepping=stepping)) as env:
        env.reset(init_index, seed=SEED, render=False)
        renders = env.renders
        for i, (action, images) in enumerate(zip(actions, expected, strict=True)):
            capture = cameras if i % 2 == 0 else ()
            env.step(action, capture=capture)
            np.testing.assert_array_equal(env.sim_state(), images["sim"])
            if capture:
                seen = env.observe()
                for camera in cameras:
                    np.testing.assert_array_equal(seen.images[camera], images[camera])
        assert env.renders - renders == len(cameras) * 3  # the captured steps rendered, nothing else did
        late = env.render("agentview")  # an uncaptured step's image: rendered after the last substep
        assert not np.array_equal(late, images["agentview"])


def test_gymnasium_observations_are_openpis_example_bit_for_bit(catalog):
    """`LangGap/Task-v0` observes what openpi's example sends before its resize: from the settled start on,
    every step's camera images (robosuite's camera observations, upright) and 8-D state equal the raw LIBERO
    env's, bit for bit, on the plan entry the env's seed rule names (env seed = run seed + init index)."""
    import gymnasium as gym

    import langgap.gym  # noqa: F401  (registers the ids)

    cameras = ("agentview", "robot0_eye_in_hand")
    size, init_index, run_seed = 128, 3, 4
    actions = np.random.default_rng(2).uniform(-0.5, 0.5, (5, 7))
    expected = raw_observations(
        catalog.get(TASK_ID), cameras, size, run_seed + init_index, init_index, actions, settle=EXAMPLE_SETTLE
    )
    env = gym.make("LangGap/Task-v0", task=TASK_ID, catalog="langgap99", cameras=cameras, image_size=size)
    try:
        observed = [env.reset(seed=run_seed, options={"init_index": init_index})[0]]
        observed += [env.step(action)[0] for action in actions]
    finally:
        env.close()
    for step, (got, want) in enumerate(zip(observed, expected, strict=True)):
        np.testing.assert_array_equal(got["state"], want["state"].astype(got["state"].dtype), err_msg=f"step {step}")
        for camera in cameras:
            np.testing.assert_array_equal(got[camera], want[camera], err_msg=f"step {step}: {camera}")


def example_starts(task, seed: int, episodes: int) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """openpi's example's starts: one LIBERO env for the task, `env.seed(seed)` once, then per episode `reset()`
    (a hard reset: LIBERO's default) and `set_init_state(k)`; each start's state and fixture placement."""
    from libero.libero.envs.env_wrapper import ControlEnv

    env = ControlEnv(
        bddl_file_name=str(files.task_bddl_path(task)),
        has_renderer=False,
        has_offscreen_renderer=False,
        use_camera_obs=False,
    )
    starts = []
    try:
        env.seed(seed)
        for k in range(episodes):
            env.reset()
            env.set_init_state(files.init_states(task)[k])
            model = env.env.sim.model
            starts.append((env.get_sim_state().copy(), model.body_pos.copy(), model.body_quat.copy()))
            for _ in range(EXAMPLE_SETTLE):  # the episode runs (stepping draws nothing from the stream)
                env.step(DUMMY_ACTION)
    finally:
        env.close()
    return starts


def test_openpi_seed_scheme_places_fixtures_as_openpis_example(catalog):
    from langgap.engine.plan import episode_seed

    task, run_seed, episodes = catalog.get(TASK_ID), 7, 3
    expected = example_starts(task, run_seed, episodes)
    with TaskEnv(task, EnvOptions(seed_scheme="openpi")) as env:
        # Any order: a worker may get episode 2 before 0 (a resumed or split run).
        for k in (2, 0, 1, 2):
            env.reset(k, seed=episode_seed(run_seed, k), render=False)
            state, body_pos, body_quat = expected[k]
            assert np.array_equal(env.sim_state(), state), f"episode {k}: state differs from openpi's"
            assert np.array_equal(env.sim.model.body_pos, body_pos), f"episode {k}: fixtures differ from openpi's"
            assert np.array_equal(env.sim.model.body_quat, body_quat)
            env.settle()
    # The default scheme seeds each episode on its own: from the second episode on, fixtures sit elsewhere.
    with TaskEnv(task, EnvOptions()) as env:
        env.reset(1, seed=episode_seed(run_seed, 1), render=False)
        assert not np.array_equal(env.sim.model.body_pos, expected[1][1])


def test_eval_records_the_openpi_seed_scheme_and_uses_it(short_catalog, tmp_path):
    from langgap.engine.plan import episode_seed

    hashes = {}
    for scheme in ("per-episode", "openpi"):
        run = tmp_path / scheme
        result = run_cli(
            "eval", "--policy", "noop", "--catalog", str(short_catalog), "--tasks", TASK_ID, "--episodes", "2",
            "--seed", "7", "--seed-scheme", scheme, "--run", str(run), "--workers", "1", "--no-progress", "--quiet",
        )  # fmt: skip
        assert result.returncode == 0, result.stderr
        rows = sorted(store_rows(run), key=lambda row: row["init_index"])
        assert [json.loads(row["physics"]).get("seed_scheme") for row in rows] == [
            None if scheme == "per-episode" else scheme
        ] * 2
        hashes[scheme] = [row["t0_hash"] for row in rows]
    with TaskEnv(load_catalog_file(short_catalog).get(TASK_ID), EnvOptions(seed_scheme="openpi")) as env:
        env.reset(1, seed=episode_seed(7, 1), render=False)
        openpi_t0 = env.t0_hash
    assert hashes["openpi"][0] == hashes["per-episode"][0]  # episode 0: the stream's first draw, seed 7 either way
    assert hashes["openpi"][1] == openpi_t0 != hashes["per-episode"][1]


def test_filmed_frames_are_taken_where_robosuite_samples_rendering_once(short_catalog):
    """A clip's frames (every 2 steps) are taken where robosuite samples, like the policy's images (every 3
    steps); a step both read after is rendered once for both."""
    from langgap.engine.episode import video_hook

    catalog = load_catalog_file(short_catalog)
    task = catalog.get(TASK_ID)
    policy = Reach(3, task.max_steps, image_size=64)
    cameras = policy.spec.cameras
    frames: list[np.ndarray] = []
    with TaskEnv(task, env_options_for(policy)) as env:
        hook = video_hook(env, frames, cameras, every=2)
        result = run_episode(env, policy, task_context(task, catalog, init_index=0, seed=0), on_step=hook)
        read_after = {0} | {s for s in range(1, result.steps + 1) if s % 2 == 0 or (s % 3 == 0 and s < result.steps)}
        assert env.renders == len(cameras) * len(read_after)
        # The reference: the same actions, every step's images captured.
        env.reset(0, seed=0, render=False)
        env.settle(capture=cameras)
        sampled = [env.observe().images]
        for action in policy.actions[: result.steps]:
            env.step(action, capture=cameras)
            sampled.append(env.observe().images)
    assert len(frames) == result.steps // 2
    for k, frame in enumerate(frames):
        expected = np.concatenate([sampled[2 * (k + 1)][c] for c in cameras], axis=1)
        np.testing.assert_array_equal(frame, expected, err_msg=f"frame after step {2 * (k + 1)}")
    for k, shown in enumerate(policy.shown):
        for camera in cameras:
            np.testing.assert_array_equal(shown[camera], sampled[3 * k][camera])
