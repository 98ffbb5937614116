"""`(Moved o)` on a real simulation: "place it anywhere but on the plate" accepts the bowl set down on the bare
table, and not on the plate, not in the hand, not untouched."""

from __future__ import annotations

import numpy as np
import pytest

from langgap.bddl import Predicate
from langgap.catalog.catalog import load_catalog
from langgap.engine.context import task_context
from langgap.policies.oracle.policy import OraclePolicy
from langgap.sim.env import SETTLE_ACTION, EnvOptions, TaskEnv
from langgap.sim.resting import MOVED_M, RESTING_M_S

NOT_WHERE = "spatial/s0/black-bowl-1-on-plate~not-where"
BOWL = "akita_black_bowl_1"
MOVED = Predicate.of("Moved", (BOWL,))
# A bare spot of the table in this scene (init state 0), 20 cm from where the bowl starts and clear of
# everything else; the plate's origin, for the bowl set down on it.
BARE_TABLE = np.array([-0.17, 0.03])
HOLD = np.array([0, 0, 0, 0, 0, 0, 1.0])  # no motion, gripper closed


@pytest.fixture(scope="module")
def catalog():
    return load_catalog("langgap-beyond")


@pytest.fixture(scope="module")
def env(catalog):
    with TaskEnv(catalog.get(NOT_WHERE), EnvOptions(privileged=True)) as env:
        yield env


def _start(env: TaskEnv) -> None:
    env.reset(0, render=False)
    env.settle()


def _set_down(env: TaskEnv, xy: np.ndarray, steps: int = 20) -> list[bool]:
    """Put the bowl 3 cm above `xy` out of the hand and let it fall and settle; whether the task's goal held
    after each step."""
    inner = env.robosuite_env
    joint = inner.get_object(BOWL).joints[-1]
    qpos = inner.sim.data.get_joint_qpos(joint).copy()
    qpos[:2] = xy
    qpos[2] += 0.03
    inner.sim.data.set_joint_qpos(joint, qpos)
    inner.sim.data.set_joint_qvel(joint, np.zeros(6))
    inner.sim.forward()
    return [env.step(SETTLE_ACTION) for _ in range(steps)]


def _bowl(env: TaskEnv) -> np.ndarray:
    inner = env.robosuite_env
    return np.array(inner.sim.data.body_xpos[inner.obj_body_id[BOWL]])


def test_the_bowl_set_down_on_the_bare_table_meets_anywhere_but_on_the_plate(env):
    _start(env)
    held = _set_down(env, BARE_TABLE)
    assert not held[0]  # still falling: not at rest
    assert held[-1] and env.success() and env.predicate_holds(MOVED)
    assert not env.predicate_holds(Predicate.of("On", (BOWL, "plate_1")))


def test_the_bowl_untouched_or_set_down_on_the_plate_does_not(env):
    _start(env)
    untouched = [env.step(SETTLE_ACTION) for _ in range(10)]
    assert not any(untouched) and not env.predicate_holds(MOVED)
    inner = env.robosuite_env
    plate = inner.sim.data.body_xpos[inner.obj_body_id["plate_1"]][:2]
    held = _set_down(env, plate)
    assert env.predicate_holds(Predicate.of("On", (BOWL, "plate_1")))
    assert env.predicate_holds(MOVED) and not any(held)  # moved and resting, but on the plate


def test_the_bowl_held_still_in_the_hand_is_not_moved(env, catalog):
    # The oracle does the source task ("… on the plate") until it has lifted the bowl away from where it
    # started; then the hand holds it still: away and at rest, but in the hand, so not `Moved`.
    task = catalog.get(NOT_WHERE)
    context = task_context(catalog.get(task.source), catalog, init_index=0, seed=0)
    policy = OraclePolicy()
    env.reset(0, render=False)
    policy.reset(context.for_policy(policy.spec))
    env.settle()
    start = _bowl(env)
    inner = env.robosuite_env
    gripper, bowl = inner.robots[0].gripper, inner.get_object(BOWL)
    while not (inner.check_contact(gripper, bowl) and _bowl(env)[2] - start[2] > MOVED_M):
        assert not env.step(policy.act(env.observe(()))), "the bowl was never lifted"
    held_still = [env.step(HOLD) for _ in range(15)]
    speed = np.linalg.norm(inner.sim.data.get_joint_qvel(bowl.joints[-1])[:3])
    assert inner.check_contact(gripper, bowl) and speed < RESTING_M_S
    assert not any(held_still) and not env.predicate_holds(MOVED)
