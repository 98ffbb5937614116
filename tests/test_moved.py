"""`(Moved o)` on a real simulation: "pick up the black bowl … and place it anywhere but on the plate" accepts the
bowl picked up and set down on the bare table, and not on the plate, not in the hand, not untouched, not
shifted without the hand."""

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
ON_PLATE = Predicate.of("On", (BOWL, "plate_1"))
# A bare spot of the table in this scene (init state 0), 20 cm from where the bowl starts, clear of everything.
BARE_TABLE = np.array([-0.17, 0.03])
HOLD = np.array([0, 0, 0, 0, 0, 0, 1.0])  # no motion, gripper closed
RAISE = np.array([0, 0, 1.0, 0, 0, 0, 1.0])  # up, gripper closed


@pytest.fixture(scope="module")
def catalog():
    return load_catalog("langgap-beyond")


@pytest.fixture(scope="module")
def env(catalog):
    with TaskEnv(catalog.get(NOT_WHERE), EnvOptions(privileged=True)) as env:
        yield env


def _bowl(env: TaskEnv) -> np.ndarray:
    inner = env.robosuite_env
    return np.array(inner.sim.data.body_xpos[inner.obj_body_id[BOWL]])


def _in_hand(env: TaskEnv) -> bool:
    inner = env.robosuite_env
    return bool(inner.check_contact(inner.robots[0].gripper, inner.get_object(BOWL)))


def _lift(env: TaskEnv, catalog) -> tuple[list[bool], np.ndarray]:
    """From init state 0, the oracle does the source task ("… on the plate") until it has lifted the bowl away
    from where it started; whether the task's goal held after each step, and where the bowl started."""
    context = task_context(catalog.get(catalog.get(NOT_WHERE).source), catalog, init_index=0, seed=0)
    policy = OraclePolicy()
    env.reset(0, render=False)
    policy.reset(context.for_policy(policy.spec))
    env.settle()
    start = _bowl(env)
    held = []
    while not (_in_hand(env) and _bowl(env)[2] - start[2] > MOVED_M):
        held.append(env.step(policy.act(env.observe(()))))
        assert len(held) < 200, "the bowl was never lifted"
    return held, start


def _drop(env: TaskEnv, xy: np.ndarray, steps: int = 20) -> list[bool]:
    """Put the bowl 3 cm above `xy`, out of the hand, and let it fall and settle with the gripper open; whether
    the task's goal held after each step."""
    inner = env.robosuite_env
    joint = inner.get_object(BOWL).joints[-1]
    qpos = inner.sim.data.get_joint_qpos(joint).copy()
    qpos[:2] = xy
    qpos[2] = inner.sim.data.body_xpos[inner.obj_body_id["plate_1"]][2] + 0.03
    inner.sim.data.set_joint_qpos(joint, qpos)
    inner.sim.data.set_joint_qvel(joint, np.zeros(6))
    inner.sim.forward()
    return [env.step(SETTLE_ACTION) for _ in range(steps)]


def _plate(env: TaskEnv) -> np.ndarray:
    inner = env.robosuite_env
    return np.array(inner.sim.data.body_xpos[inner.obj_body_id["plate_1"]][:2])


def test_the_bowl_picked_up_and_set_down_on_the_bare_table_meets_anywhere_but_on_the_plate(env, catalog):
    assert not any(_lift(env, catalog)[0])
    held = _drop(env, BARE_TABLE)  # carried there: it leaves the hand above the bare table
    assert not held[0]  # still falling: not at rest
    assert held[-1] and env.success() and env.predicate_holds(MOVED) and not env.predicate_holds(ON_PLATE)


def test_the_bowl_held_still_in_the_hand_is_not_moved(env, catalog):
    # away and at rest, but in the hand
    assert not any(_lift(env, catalog)[0])
    held_still = [env.step(HOLD) for _ in range(15)]
    inner = env.robosuite_env
    speed = np.linalg.norm(inner.sim.data.get_joint_qvel(inner.get_object(BOWL).joints[-1])[:3])
    assert _in_hand(env) and speed < RESTING_M_S
    assert not any(held_still) and not env.predicate_holds(MOVED)


def test_the_bowl_set_down_on_the_plate_or_back_where_it_was_does_not(env, catalog):
    _, start = _lift(env, catalog)
    held = _drop(env, _plate(env))
    assert env.predicate_holds(ON_PLATE) and env.predicate_holds(MOVED)  # moved and resting, but on the plate
    assert not any(held)
    _, start = _lift(env, catalog)
    for _ in range(15):  # the hand up and clear of where the bowl started
        env.step(RAISE)
    back = _drop(env, start[:2])  # handled, out of the hand, at rest, but where it started
    assert np.linalg.norm(_bowl(env)[:2] - start[:2]) < 0.01
    assert not any(back) and not env.predicate_holds(MOVED)


def test_the_bowl_untouched_or_shifted_without_the_hand_does_not(env):
    env.reset(0, render=False)
    env.settle()
    untouched = [env.step(SETTLE_ACTION) for _ in range(10)]
    assert not any(untouched) and not env.predicate_holds(MOVED)
    # 20 cm away and at rest, but the hand never touched it (as a drawer or a box it stands on would carry it)
    shifted = _drop(env, BARE_TABLE)
    assert np.linalg.norm(_bowl(env)[:2] - BARE_TABLE) < 0.01
    assert not any(shifted) and not env.predicate_holds(MOVED)
