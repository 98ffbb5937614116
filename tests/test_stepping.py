"""Fast stepping reproduces robosuite's own stepping to the last bit, on real rollouts."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from langgap.engine.context import task_context
from langgap.engine.rollout import env_options_for, run_episode
from langgap.policies import make_policy
from langgap.sim.env import TaskEnv
from tests.support.harness import run_cli, store_rows


def _states(catalog, task_id: str, fast: bool, hard_reset: bool = False) -> np.ndarray:
    task = catalog.get(task_id)
    policy = make_policy("oracle", {})
    options = replace(env_options_for(policy), stepping="exact" if fast else "robosuite", hard_reset=hard_reset)
    states: list[np.ndarray] = []
    with TaskEnv(task, options) as env:
        for init in (0, 1):  # the second episode starts after a reset of a used simulator
            run_episode(
                env,
                policy,
                task_context(task, catalog, init_index=init, seed=0),
                on_step=lambda env_, _step, _action: states.append(env_.sim_state().copy()),
            )
    return np.array(states)


@pytest.mark.parametrize(
    "task_id, hard_reset",
    [
        ("spatial/s0/black-bowl-1-on-plate", False),  # grasp, carry, place: contacts and the gripper
        ("libero10/s3/close-cabinet-bottom-drawer+black-bowl-in-cabinet-bottom-drawer", True),  # joints, new sim
    ],
)
def test_fast_stepping_is_bit_identical(catalog, task_id, hard_reset):
    fast = _states(catalog, task_id, fast=True, hard_reset=hard_reset)
    plain = _states(catalog, task_id, fast=False, hard_reset=hard_reset)
    assert len(fast) > 100 and fast.shape == plain.shape
    assert np.array_equal(fast, plain), f"first differing step {np.argmax(np.any(fast != plain, axis=1))}"


def test_an_episode_does_not_depend_on_what_ran_before(catalog):
    """Same init state and seed: the same trajectory in a fresh simulator and in one used for other episodes."""
    task = catalog.get("spatial/s0/black-bowl-1-on-plate")
    policy = make_policy("oracle", {})

    def trajectory(env: TaskEnv, init: int) -> np.ndarray:
        states: list[np.ndarray] = []
        context = task_context(task, catalog, init_index=init, seed=0)
        run_episode(env, policy, context, on_step=lambda env_, _s, _a: states.append(env_.sim_state().copy()))
        return np.array(states)

    with TaskEnv(task, env_options_for(policy)) as env:
        fresh = trajectory(env, 1)
    with TaskEnv(task, env_options_for(policy)) as env:
        trajectory(env, 0)
        trajectory(env, 2)
        after_others = trajectory(env, 1)
    assert fresh.shape == after_others.shape and np.array_equal(fresh, after_others)


def test_substeps_between_actions_run_langgap_s_controller(catalog):
    """LIBERO's control configuration is the one `OscSubsteps` reproduces: every substep but the policy
    step runs through it (the bit-identity test above then holds for it)."""
    from langgap.sim.osc import OscSubsteps

    task = catalog.get("spatial/s0/black-bowl-1-on-plate")
    with TaskEnv(task, env_options_for(make_policy("oracle", {}))) as env:
        env.reset(0)
        stepping = env.robosuite_env.step
        env.step(np.zeros(7))
        osc = stepping._substep_control()
        assert isinstance(osc, OscSubsteps) and OscSubsteps.supports(env.robosuite_env)
        calls = []
        control = osc.control
        osc.control = lambda action: (calls.append(1), control(action))
        env.step(np.zeros(7))
        inner = env.robosuite_env
        assert len(calls) == round(inner.control_timestep / inner.model_timestep) - 1


def test_fast_stepping_differs_in_the_last_bits_and_keeps_the_verdict(catalog):
    """`fast` computes each substep's dynamics once, with a compiled controller: the same states as
    `exact` to ~1e-12 at first (it is the same physics), not bit-identical (it is another computation),
    and the oracle's episode still succeeds."""
    from langgap.sim.osc import OscSubsteps

    task = catalog.get("spatial/s0/black-bowl-1-on-plate")
    states = {}
    for stepping in ("exact", "fast"):
        policy = make_policy("oracle", {})
        trajectory: list[np.ndarray] = []
        with TaskEnv(task, replace(env_options_for(policy), stepping=stepping)) as env:
            result = run_episode(
                env,
                policy,
                task_context(task, catalog, init_index=0, seed=0),
                on_step=lambda env_, _step, _action, kept=trajectory: kept.append(env_.sim_state().copy()),
            )
            osc = env.robosuite_env.step._substep_control()
            assert isinstance(osc, OscSubsteps) and osc.compiled == (stepping == "fast")
        assert result.success
        states[stepping] = np.array(trajectory)
    first = np.abs(states["exact"][:10] - states["fast"][:10])
    assert first.max() < 1e-12 and first.max() > 0


def test_eval_records_the_fast_stepping_it_ran(tmp_path):
    run = tmp_path / "run"
    result = run_cli(
        "eval", "--policy", "oracle", "--tasks", "spatial/s0/black-bowl-1-on-plate",
        "--episodes", "1", "--run", str(run), "--stepping", "fast", "--workers", "1", "--no-progress", "--quiet",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    rows = store_rows(run)
    assert len(rows) == 1 and json.loads(rows[0]["physics"])["stepping"] == "fast" and rows[0]["success"] == 1
