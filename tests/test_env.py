"""The simulation layer on the real LIBERO simulator."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from langgap.errors import InitStateError, SimulationError
from langgap.sim.env import EnvOptions, TaskEnv, quat_to_axis_angle


def _scene(task) -> str:
    """A task's scene as its id names it (e.g. `spatial/s0`)."""
    return task.id.rsplit("/", 1)[0]


def _scenes() -> list:
    """One parameter per scene of LangGap-99; only each suite's first scene runs outside `slow`."""
    from langgap.catalog.catalog import load_catalog

    scenes = sorted({_scene(task) for task in load_catalog("langgap99")})
    first = {scene.split("/")[0]: scene for scene in reversed(scenes)}.values()
    return [pytest.param(s, id=s, marks=() if s in first else pytest.mark.slow) for s in scenes]


@pytest.mark.parametrize("scene", _scenes())
def test_every_task_builds_resets_to_its_init_state_with_goal_false(catalog, scene):
    """Every task of a scene: the env builds from the (generated) BDDL, t0 is the stored init state, the goal is
    false, and all of them start from the identical scene (same init index, same seed)."""
    tasks = [task for task in catalog if _scene(task) == scene]
    t0_hashes = set()
    for task in tasks:
        with TaskEnv(task) as env:
            env.reset(0, seed=0)
            assert np.array_equal(env.sim_state(), env.init_states[0]), task.id
            assert not env.success(), f"{task.id}: goal already true at t0"
            env.settle()
            assert not env.success(), f"{task.id}: goal true after settling"
            t0_hashes.add(env.t0_hash)
    assert tasks and len(t0_hashes) == 1, scene


@pytest.fixture(scope="module")
def env(catalog):
    with TaskEnv(
        catalog.get("spatial/s0/black-bowl-1-on-plate"),
        EnvOptions(cameras=("agentview", "robot0_eye_in_hand"), image_size=64),
    ) as e:
        yield e


def test_observation_conventions(env):
    obs = env.reset(3, seed=1)
    assert obs.state.shape == (8,) and obs.state.dtype == np.float32
    raw = env.robosuite_env._get_observations(force_update=True)
    np.testing.assert_allclose(obs.state[:3], raw["robot0_eef_pos"], rtol=1e-6)
    np.testing.assert_allclose(obs.state[6:], raw["robot0_gripper_qpos"], rtol=1e-6)
    assert set(obs.images) == {"agentview", "robot0_eye_in_hand"}
    image = obs.images["agentview"]
    assert image.shape == (64, 64, 3) and image.dtype == np.uint8
    direct = env.sim.render(camera_name="agentview", width=64, height=64)
    np.testing.assert_array_equal(image, direct[::-1, ::-1])  # upright = raw rotated 180 degrees


def test_axis_angle_matches_robosuite():
    import robosuite.utils.transform_utils as T

    rng = np.random.default_rng(0)
    for _ in range(20):
        quat = rng.normal(size=4)
        quat /= np.linalg.norm(quat)
        np.testing.assert_allclose(quat_to_axis_angle(quat), T.quat2axisangle(quat.copy()), atol=1e-12)


def test_init_index_out_of_range(env):
    with pytest.raises(InitStateError, match="out of range"):
        env.reset(50)
    with pytest.raises(InitStateError):
        env.reset(-1)


def test_same_actions_same_outcome_and_seed_moves_fixtures(env):
    rng = np.random.default_rng(7)
    actions = rng.uniform(-1, 1, size=(15, 7))

    def rollout(seed: int) -> tuple[str, str]:
        env.reset(2, seed=seed)
        t0 = env.t0_hash
        for a in actions:
            env.step(a)
        return t0, env.state_hash()

    first, again, other_seed = rollout(0), rollout(0), rollout(1)
    assert first == again
    assert other_seed[0] != first[0]  # fixture placement comes from the seed, not the init state
    env.reset(2, seed=1)
    assert np.array_equal(env.sim_state(), env.init_states[2])


def _nudge(array: np.ndarray, index) -> Callable[[], None]:
    """Add 1e-3 to `array[index]` in place; returns what puts it back."""
    old = np.array(array[index], copy=True)
    array[index] += 1e-3

    def undo() -> None:
        array[index] = old

    return undo


def _nudge_time(sim) -> Callable[[], None]:
    old = sim.data.time
    sim.data.time = old + 1e-3
    return lambda: setattr(sim.data, "time", old)


def _qpos(sim, joint: str, offset: int = 0) -> int:
    start = sim.model.get_joint_qpos_addr(joint)
    return (start[0] if isinstance(start, tuple) else start) + offset


def _qvel(sim, joint: str) -> int:
    start = sim.model.get_joint_qvel_addr(joint)
    return start[0] if isinstance(start, tuple) else start


# Every part of the scene that goes into the t0 hash (`TaskEnv.state_hash`), each changed on its own:
# the flattened MuJoCo state (time, positions of objects, robot and articulated fixtures, velocities) and
# the fixtures' placements, which live in the model (LIBERO samples them; no init state holds them).
_T0_PARTS = {
    "time": _nudge_time,
    "object position": lambda sim: _nudge(sim.data.qpos, _qpos(sim, "akita_black_bowl_1_joint0")),
    "object rotation": lambda sim: _nudge(sim.data.qpos, _qpos(sim, "akita_black_bowl_1_joint0", 4)),
    "robot arm joint": lambda sim: _nudge(sim.data.qpos, _qpos(sim, "robot0_joint4")),
    "gripper finger": lambda sim: _nudge(sim.data.qpos, _qpos(sim, "gripper0_finger_joint1")),
    "fixture joint (drawer)": lambda sim: _nudge(sim.data.qpos, _qpos(sim, "wooden_cabinet_1_top_level")),
    "velocity": lambda sim: _nudge(sim.data.qvel, _qvel(sim, "plate_1_joint0")),
    "fixture position": lambda sim: _nudge(sim.model.body_pos, (sim.model.body_name2id("flat_stove_1_main"), 0)),
    "fixture rotation": lambda sim: _nudge(sim.model.body_quat, (sim.model.body_name2id("flat_stove_1_main"), 3)),
}


@pytest.mark.parametrize("part", list(_T0_PARTS))
def test_the_t0_hash_covers_each_part_of_the_start(env, part):
    env.reset(1, seed=3)
    assert env.t0_hash == env.state_hash()  # the t0 hash is this function of the state reset left
    undo = _T0_PARTS[part](env.sim)
    changed = env.state_hash()
    undo()
    assert changed != env.t0_hash, f"the t0 hash leaves out the {part}"
    assert env.state_hash() == env.t0_hash  # only that part had changed


def test_soft_reset_leaves_nothing_of_the_previous_episode(catalog):
    """An episode after another one (soft reset) equals the same episode in a fresh env."""
    task = catalog.get("spatial/s2/black-bowl-1-on-plate")
    close = np.array([0.3, 0.0, -0.5, 0.0, 0.0, 0.1, 1.0])
    probe = np.array([0.0, 0.2, 0.0, 0.0, 0.0, 0.0, -1.0])

    def episode(env: TaskEnv) -> str:
        env.reset(1, seed=3)
        env.settle()
        for _ in range(20):
            env.step(probe)
        return env.state_hash()

    with TaskEnv(task) as fresh:
        expected = episode(fresh)
    with TaskEnv(task) as used:
        used.reset(0, seed=0)
        for _ in range(30):
            used.step(close)  # leaves the gripper commanded shut
        assert episode(used) == expected


def test_episode_is_capped_by_the_layer(catalog):
    task = catalog.get("goal/s7/turn-on-stove")
    with TaskEnv(task) as env:
        env.reset(0)
        for _ in range(task.max_steps):
            env.step(np.zeros(7))
        assert env.truncated
        with pytest.raises(SimulationError, match="episode is over"):
            env.step(np.zeros(7))


def test_bad_actions_and_options(env):
    env.reset(0)
    with pytest.raises(SimulationError, match="7 finite"):
        env.step(np.zeros(6))
    with pytest.raises(SimulationError, match="7 finite"):
        env.step(np.full(7, np.nan))
    with pytest.raises(SimulationError, match="unknown camera"):
        EnvOptions(cameras=("frontview_hd",))


def test_no_renderer_unless_a_camera_is_asked_for(catalog):
    with TaskEnv(catalog.get("object/s0/alphabet-soup-in-basket")) as env:
        obs = env.reset(0)
        assert obs.images == {}
        assert env.sim._render_context_offscreen is None
        with pytest.raises(SimulationError, match="not enabled"):
            env.observe(("agentview",))


def test_reflection_pass_off_changes_the_image_slightly(catalog):
    task = catalog.get("spatial/s0/black-bowl-1-on-plate")
    images = []
    for reflection in (True, False):
        with TaskEnv(task, EnvOptions(cameras=("agentview",), image_size=128, reflection=reflection)) as env:
            images.append(env.reset(0).images["agentview"].astype(float))
    difference = np.abs(images[0] - images[1]).mean()
    assert 0 < difference < 5


def test_hard_reset_applies_init_state_after_reset(catalog):
    with TaskEnv(catalog.get("spatial/s1/black-bowl-1-on-plate"), EnvOptions(hard_reset=True)) as env:
        for index in (0, 4):
            env.reset(index, seed=0)
            assert np.array_equal(env.sim_state(), env.init_states[index])


def test_switching_task_within_a_scene_equals_a_fresh_env(catalog):
    """Sibling tasks share the simulator: an env built for one runs another exactly like its own env."""
    rng = np.random.default_rng(5)
    actions = rng.uniform(-0.5, 0.5, size=(25, 7))
    target = catalog.get("spatial/s2/black-bowl-1-on-stove")

    def episode(env: TaskEnv) -> tuple[str, bool, int]:
        env.reset(3, seed=3)
        env.settle()
        success = any(env.step(a) for a in actions)
        return env.state_hash(), success, env.task.max_steps

    with TaskEnv(target) as fresh:
        expected = episode(fresh)
    with TaskEnv(catalog.get("spatial/s2/black-bowl-1-on-plate")) as shared:
        assert shared.can_switch_to(target)
        assert not shared.can_switch_to(catalog.get("spatial/s0/black-bowl-1-on-stove"))
        with pytest.raises(SimulationError, match="not the same scene"):
            shared.switch_task(catalog.get("goal/s1/black-bowl-on-stove"))
        shared.switch_task(target)
        assert episode(shared) == expected


def test_a_goal_watched_under_many_names_is_evaluated_once_a_step(env, monkeypatch):
    """A `full` goal scene watches each goal under ten names (LIBERO-goal's scenes share one layout): the watch
    reads a goal's atoms once a step however many names it has."""
    from langgap.engine.watch import SceneWatch

    env.reset(0, seed=0)
    env.settle()
    goal, calls = env.task.goal, []
    read = env.predicate_holds
    monkeypatch.setattr(env, "predicate_holds", lambda atom: calls.append(atom) or read(atom))
    counts = []
    for names in (["a"], ["a", "b", "c"]):
        watch = SceneWatch(env, dict.fromkeys(names, goal))
        calls.clear()
        for _ in range(3):
            env.step(np.zeros(7))
            watch.observe()
        counts.append(len(calls))
        assert watch.at_start == [] and watch.reached == {}
    assert counts[0] == counts[1] > 0
