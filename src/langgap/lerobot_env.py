"""LangGap as a LeRobot environment type: `lerobot-eval --env.type=langgap --env.task=<selection> --policy.path=...`.

`LangGapEnv` extends LeRobot's own LIBERO env config, so features, camera keys, the 20 Hz control
rate and the env processor (`LiberoProcessorStep`: 180-degree flip, 8-D state) are LeRobot's. What
differs is where episodes come from: `--env.task` is a LangGap task selection (ids, globs,
`paper:N`, `spatial&heldout`, ...), each selected task is one vector env (reported under its task
id), the instruction is the catalog's (`--env.style`), and each sub-env is a thin layer over
LangGap's Gymnasium env (`langgap.gym.LangGapTaskEnv`): the task's fixed init states applied after
reset, then LangGap's 10 settle steps, the goal judged by LangGap. Resets are soft by default, as in
`langgap eval` (LeRobot's LIBERO env rebuilds the model each time): `TaskEnv`'s soft reset gives the
same episode as a fresh env, and a test pins that.

Episode `k` of a task (k = batch * batch_size + sub-env index, LeRobot's scheme) uses init state
`i = k mod 50`, and LangGap's seed rule on the seed LeRobot passes to `reset` (`--seed` + k): env
seed = that seed + i, as `langgap.gym` does.
The package `lerobot_env_langgap` (plugins/) imports this module, which registers the type.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from lerobot.envs.configs import EnvConfig, LiberoEnv
from lerobot.envs.utils import _LazyAsyncVectorEnv, freeze_after_episode_end, parse_camera_names

from langgap.catalog.catalog import DEFAULT_CATALOG, load_catalog
from langgap.catalog.task import DEFAULT_STYLE
from langgap.errors import LangGapError
from langgap.lerobot_libero import CAMERA_KEYS, FPS, LIBERO_CAMERA_NAMES, robot_state


def _vector(shape: tuple[int, ...]) -> spaces.Box:
    return spaces.Box(low=-np.inf, high=np.inf, shape=shape, dtype=np.float64)


class LangGapLiberoEnv(gym.Wrapper):
    """One LangGap task (`langgap.gym`'s `LangGapTaskEnv`) with LeRobot's LIBERO observations (`pixels` raw,
    `robot_state` nested)."""

    def __init__(
        self,
        task_id: str,
        catalog: str = DEFAULT_CATALOG,
        style: str = DEFAULT_STYLE,
        cameras: tuple[str, ...] = tuple(CAMERA_KEYS),
        image_size: int = 360,
        episode_length: int | None = None,
        hard_reset: bool = False,
        episode_index: int = 0,
        n_envs: int = 1,
    ):
        # Imported here: the `lerobot` policy imports this module for `LangGapEnv` (its processors) and must
        # not pull in the Gymnasium env, which sits above the policy layer (engine).
        from langgap.gym import LangGapTaskEnv

        super().__init__(
            LangGapTaskEnv(
                task_id,
                catalog=catalog,
                cameras=cameras,
                image_size=image_size,
                style=style,
                render_mode="rgb_array",
                max_steps=episode_length,
                hard_reset=hard_reset,
            )
        )
        self.task = task_id
        self.task_description = self.env.task.instruction(style)
        self._max_episode_steps = self.env.task.max_steps
        self._next_init = episode_index
        self._stride = n_envs
        pixels = {
            CAMERA_KEYS[c]: spaces.Box(0, 255, shape=(image_size, image_size, 3), dtype=np.uint8) for c in cameras
        }
        self.observation_space = spaces.Dict(
            {
                "pixels": spaces.Dict(pixels),
                "robot_state": spaces.Dict(
                    {
                        "eef": spaces.Dict({"pos": _vector((3,)), "quat": _vector((4,)), "mat": _vector((3, 3))}),
                        "gripper": spaces.Dict({"qpos": _vector((2,)), "qvel": _vector((2,))}),
                        "joints": spaces.Dict({"pos": _vector((7,)), "vel": _vector((7,))}),
                    }
                ),
            }
        )

    def _observation(self, observation: dict) -> dict:
        # LeRobot's env hands out the raw render and lets LiberoProcessorStep rotate it; undo the upright rotation.
        pixels = {CAMERA_KEYS[c]: np.ascontiguousarray(observation[c][::-1, ::-1]) for c in self.env.cameras}
        sim = self.env.simulator
        ori = sim.robosuite_env.robots[0].controller.ee_ori_mat
        return {"pixels": pixels, "robot_state": robot_state(sim.robosuite_observation, ori)}

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start the next episode of this sub-env: its next init state, with LangGap's seed rule (`langgap.gym`).
        LeRobot's own reset options (a new rollout) need nothing here."""
        init_index = self._next_init % len(self.env.simulator.init_states)
        self._next_init += self._stride
        observation, info = self.env.reset(seed=seed, options={"init_index": init_index})
        return self._observation(observation), {"is_success": False, "init_index": init_index, "seed": info["seed"]}

    def step(self, action: np.ndarray):
        observation, reward, terminated, truncated, info = self.env.step(action)
        info = {"task": self.task, "is_success": info["is_success"], "outcome": info["outcome"]}
        return self._observation(observation), reward, terminated, truncated, info


@EnvConfig.register_subclass("langgap")
@dataclass
class LangGapEnv(LiberoEnv):
    """`--env.type=langgap`: LeRobot's LIBERO env config with LangGap tasks (see the module docstring)."""

    task: str = "spatial/s0/black-bowl-1-on-plate"
    catalog: str = DEFAULT_CATALOG
    style: str = DEFAULT_STYLE
    hard_reset: bool = False

    def __post_init__(self):
        super().__post_init__()
        unsupported = {
            "task_ids": self.task_ids is not None,
            "is_libero_plus": self.is_libero_plus,
            "init_states": not self.init_states,
            "camera_name_mapping": self.camera_name_mapping is not None,
            "control_mode": self.control_mode != "relative",
            "obs_type": self.obs_type != "pixels_agent_pos",
            "fps": self.fps != FPS,
            "observation_width": self.observation_width != self.observation_height,
        }
        bad = [name for name, is_bad in unsupported.items() if is_bad]
        if bad:
            raise LangGapError(f"--env.type=langgap does not support changing {', '.join(bad)}")
        unknown = [c for c in parse_camera_names(self.camera_name) if c not in LIBERO_CAMERA_NAMES]
        if unknown:
            raise LangGapError(f"unknown camera(s) {unknown}; LIBERO has {', '.join(LIBERO_CAMERA_NAMES)}")

    def create_envs(self, n_envs: int, use_async_envs: bool = False):
        """{task id: {0: vector env of `n_envs` sub-envs}} for every task the selection names."""
        cameras = tuple(LIBERO_CAMERA_NAMES[c] for c in parse_camera_names(self.camera_name))
        envs = {}
        for task in load_catalog(self.catalog).select(self.task):
            factories = [
                partial(
                    LangGapLiberoEnv,
                    task.id,
                    catalog=self.catalog,
                    style=self.style,
                    cameras=cameras,
                    image_size=self.observation_height,
                    episode_length=self.episode_length,
                    hard_reset=self.hard_reset,
                    episode_index=index,
                    n_envs=n_envs,
                )
                for index in range(n_envs)
            ]
            if use_async_envs and n_envs > 1:
                vector = _LazyAsyncVectorEnv(factories)
            else:
                vector = gym.vector.SyncVectorEnv(
                    [freeze_after_episode_end(f) for f in factories], autoreset_mode=gym.vector.AutoresetMode.NEXT_STEP
                )
            envs[task.id] = {0: vector}
        return envs
