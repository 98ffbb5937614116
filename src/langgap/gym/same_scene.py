"""`LangGap/SameScene-v0`: the sibling tasks of one scene side by side, a batch where only the instruction
(and the goal judged) differs.

Sub-env i holds the scene's i-th task (catalog order). Every `reset` puts all of them on the same init
state with the same env seed, so they start from the identical simulator state (equal `t0_hash`).
A sub-env whose episode ended keeps its last observation (reward 0, its `terminated` / `truncated`
latched) until the next `reset`, which restarts the whole batch: Gymnasium's `AutoresetMode.DISABLED`.
The sub-envs step in this process, one after another.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.error import ResetNeeded
from gymnasium.vector.utils import batch_space, concatenate, create_empty_array

from langgap.catalog.catalog import DEFAULT_CATALOG, Catalog, load_catalog
from langgap.catalog.task import Task
from langgap.errors import CatalogError, LangGapError
from langgap.gym.task_env import LangGapTaskEnv, run_seed


def scene_siblings(catalog: Catalog, scene: str) -> list[Task]:
    """The tasks of `scene` that share its init states, in catalog order. `scene` is a scene prefix of
    task ids (`spatial/s0`) or any task id of the scene."""
    try:
        anchor = catalog.get(scene)
    except CatalogError:
        members = [t for t in catalog if t.id.startswith(scene.rstrip("/") + "/")]
        if not members:
            raise CatalogError(f"no scene {scene!r}: give a scene prefix such as spatial/s0, or a task id") from None
        anchor = members[0]
    # Scene mates of libero_goal use other init states: "the same init state" needs the same scene task.
    return [t for t in catalog.scene_mates(anchor) if t.scene_task == anchor.scene_task]


class SameSceneVectorEnv(gym.vector.VectorEnv):
    """`num_envs` sibling tasks of `scene` on one init state per reset; other arguments as `LangGapTaskEnv`'s."""

    metadata = {"autoreset_mode": gym.vector.AutoresetMode.DISABLED, "render_modes": ["rgb_array"]}

    def __init__(self, scene: str, num_envs: int | None = None, catalog: str = DEFAULT_CATALOG, **env_kwargs: Any):
        tasks = scene_siblings(load_catalog(catalog), scene)
        num_envs = len(tasks) if num_envs is None else num_envs
        if not 1 <= num_envs <= len(tasks):
            raise LangGapError(f"scene {scene!r} has {len(tasks)} sibling tasks; num_envs must be 1..{len(tasks)}")
        self.envs = [LangGapTaskEnv(task.id, catalog=catalog, **env_kwargs) for task in tasks[:num_envs]]
        self.tasks = [env.task.id for env in self.envs]
        self.num_envs = num_envs
        self.render_mode = self.envs[0].render_mode
        self.single_observation_space = self.envs[0].observation_space
        self.single_action_space = self.envs[0].action_space
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self._run_seed: int | None = None
        self._last: list[dict] = []
        self._ended = np.zeros(num_envs, dtype=bool)
        self._terminated = np.zeros(num_envs, dtype=bool)
        self._truncated = np.zeros(num_envs, dtype=bool)
        self._started = False

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Reset every sub-env to one init state (`options["init_index"]`, else drawn from `np_random`) with
        one env seed (seed rule as `LangGapTaskEnv`'s). `options` may also name a `condition`."""
        super().reset(seed=seed)
        options = dict(options or {})
        if options.get("init_index") is None:
            options["init_index"] = int(self.np_random.integers(len(self.envs[0].simulator.init_states)))
        self._run_seed = run_seed(seed, self._run_seed, self.np_random)
        observations, infos = [], {}
        for i, env in enumerate(self.envs):
            observation, info = env.reset(seed=self._run_seed, options=options)
            observations.append(observation)
            infos = self._add_info(infos, info, i)
        self._last = observations
        self._ended[:] = self._terminated[:] = self._truncated[:] = False
        self._started = True
        return self._batch(observations), infos

    def step(self, actions):
        """Step every sub-env whose episode is still running; ended ones repeat their last observation."""
        if not self._started:
            raise ResetNeeded("call reset() before step()")
        rewards = np.zeros(self.num_envs, dtype=np.float64)
        infos: dict[str, Any] = {}
        for i, env in enumerate(self.envs):
            if self._ended[i]:
                continue
            observation, rewards[i], self._terminated[i], self._truncated[i], info = env.step(actions[i])
            self._last[i] = observation
            self._ended[i] = self._terminated[i] or self._truncated[i]
            infos = self._add_info(infos, info, i)
        return self._batch(self._last), rewards, self._terminated.copy(), self._truncated.copy(), infos

    def _batch(self, observations: list[dict]):
        buffer = create_empty_array(self.single_observation_space, self.num_envs)
        return concatenate(self.single_observation_space, observations, buffer)

    def render(self) -> tuple[np.ndarray | None, ...]:
        """Each sub-env's agentview frame (`render_mode="rgb_array"`)."""
        return tuple(env.render() for env in self.envs)

    def close_extras(self, **kwargs: Any) -> None:
        for env in self.envs:
            env.close()
