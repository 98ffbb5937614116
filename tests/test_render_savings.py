"""An image policy's episode renders only what the policy is shown, and shows it the same pixels."""

from __future__ import annotations

import numpy as np
import pytest

from langgap.catalog.catalog import load_catalog_file
from langgap.engine.context import task_context
from langgap.engine.rollout import env_options_for, run_episode
from langgap.sim.env import CAMERAS, TaskEnv
from tests.support.policies import Reach

TASK_ID = "spatial/s0/black-bowl-1-on-plate"


def reference_images(env: TaskEnv, policy: Reach, steps: int) -> list[dict[str, np.ndarray]]:
    """What the policy must see: a reset that renders, settling, then both cameras at every query step (taken
    where robosuite samples its observables, inside the step before)."""
    env.reset(0, seed=0)
    env.settle(capture=CAMERAS)
    seen = []
    for step in range(steps):
        if step % policy.spec.replan == 0:
            seen.append(env.observe(CAMERAS).images)
        env.step(policy.actions[step], capture=CAMERAS if (step + 1) % policy.spec.replan == 0 else ())
    return seen


@pytest.mark.parametrize("replan", [1, 5])
def test_an_episode_renders_each_camera_once_per_query_and_the_same_pixels(short_catalog, replan):
    task = load_catalog_file(short_catalog).get(TASK_ID)
    policy = Reach(replan, task.max_steps)
    with TaskEnv(task, env_options_for(policy)) as env:
        result = run_episode(env, policy, task_context(task, load_catalog_file(short_catalog), init_index=0, seed=0))
        assert result.steps == task.max_steps and result.policy_calls == -(-task.max_steps // replan)
        # Nothing rendered at reset, nor between queries: the saving measured by bench/bench_render.py.
        assert env.renders == result.policy_calls * len(CAMERAS)
        expected = reference_images(env, policy, result.steps)
    for step, (shown, reference) in enumerate(zip(policy.shown, expected, strict=True)):
        for camera in CAMERAS:
            np.testing.assert_array_equal(shown[camera], reference[camera], err_msg=f"query {step}, {camera}")
    # The arm moves: a stale image (one render reused across queries) would fail the comparison above.
    assert not np.array_equal(expected[0]["robot0_eye_in_hand"], expected[-1]["robot0_eye_in_hand"])


def test_the_query_at_an_instruction_switch_sees_images_taken_where_robosuite_samples(short_catalog):
    """A switch mid-chunk asks the policy at once: its images are taken inside the step before, as every
    other query's are (not rendered on demand one substep late)."""
    catalog = load_catalog_file(short_catalog)
    task = catalog.get(TASK_ID)
    policy, switch = Reach(5, 2 * task.max_steps), 3  # the switch asks once more: actions to spare
    executed: list[np.ndarray] = []
    with TaskEnv(task, env_options_for(policy)) as env:
        run_episode(
            env,
            policy,
            task_context(task, catalog, init_index=0, seed=0),
            changes=((switch, "put the bowl somewhere else"),),
            on_step=lambda _e, _i, action: executed.append(np.array(action)),
        )
        queries = {0, *range(switch, len(executed), 5)}
        env.reset(0, seed=0)
        env.settle(capture=CAMERAS)
        expected = []
        for step, action in enumerate(executed):
            if step in queries:
                expected.append(env.observe(CAMERAS).images)
            env.step(action, capture=CAMERAS if step + 1 in queries else ())
    assert len(policy.shown) == len(expected)
    for query, (shown, reference) in enumerate(zip(policy.shown, expected, strict=True)):
        for camera in CAMERAS:
            np.testing.assert_array_equal(shown[camera], reference[camera], err_msg=f"query {query}, {camera}")
