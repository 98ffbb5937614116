"""Several `TaskEnv`s in one process (LeRobot's SyncVectorEnv does this) render their own images."""

from __future__ import annotations

import numpy as np

from langgap.catalog.catalog import load_catalog
from langgap.sim.env import EnvOptions, TaskEnv

TASK_ID = "spatial/s0/black-bowl-1-on-plate"


def _image(env: TaskEnv, init_index: int) -> np.ndarray:
    env.reset(init_index, seed=0)
    return env.render("agentview")


def test_render_after_another_env_is_built_and_closed():
    task = load_catalog("langgap99").get(TASK_ID)
    options = EnvOptions(cameras=("agentview",), image_size=32)
    with TaskEnv(task, options) as first:
        before = _image(first, 0)
        with TaskEnv(task, options) as second:
            other = _image(second, 3)
            np.testing.assert_array_equal(first.render("agentview"), before)
        # Closing `second` must neither free `first`'s GL objects nor leave no context current.
        np.testing.assert_array_equal(first.render("agentview"), before)
    assert not np.array_equal(before, other)
