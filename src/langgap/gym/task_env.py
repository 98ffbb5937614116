"""`LangGap/Task-v0`: one LangGap task as a Gymnasium environment, episode for episode the harness's.

An episode is the one `langgap eval` runs for the plan entry (task, init index k, run seed s):
`reset(seed=s, options={"init_index": k})` resets the simulator to init state k with env seed
`episode_seed(s, k)` (= s + k), settles it (LangGap's 10 no-op steps) and shows the settled state;
the goal is judged after every step; the episode terminates on the first step the goal holds
(reward 1.0) and is truncated at the task's step limit. Without `init_index` the init state is drawn
from the env's `np_random`; without a seed the last one given is kept (drawn from `np_random` if
none was). LIBERO reseeds NumPy's global generator; the env restores it, so the caller's global
random state is the same after every call as before.
"""

from __future__ import annotations

import contextlib
import dataclasses
import string
from collections.abc import Iterator
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.error import ResetNeeded

from langgap.catalog.catalog import DEFAULT_CATALOG, load_catalog
from langgap.catalog.task import DEFAULT_STYLE
from langgap.engine.context import planned_context
from langgap.engine.episode import scene_goals
from langgap.engine.plan import (
    CONDITION_HELP,
    PlannedEpisode,
    condition_instruction,
    episode_seed,
    switch_episode,
    unknown_conditions,
)
from langgap.engine.watch import SceneWatch
from langgap.errors import LangGapError
from langgap.policies.base import PolicySpec
from langgap.records import EpisodeKey, classify
from langgap.sim.env import ACTION_DIM, EnvOptions, Observation, TaskEnv
from langgap.sim.privileged_schema import PrivilegedState
from langgap.stack import DEFAULT_STEPPING
from langgap.vocabulary import Condition, switch_step

STATE_DIM = 8
RENDER_CAMERA = "agentview"
RENDER_FPS = 20  # robosuite's control frequency
MAX_INSTRUCTION = 512
INSTRUCTION_CHARSET = string.printable
# Run seeds drawn when none is given stay where `episode_seed` (+ any init index) fits NumPy's 32-bit seeds.
_DRAWN_SEEDS = 2**31
_OPTIONS = ("init_index", "condition")


@contextlib.contextmanager
def global_rng_kept() -> Iterator[None]:
    """Restore NumPy's global random state on exit: LIBERO seeds and draws from it (placements)."""
    state = np.random.get_state()
    try:
        yield
    finally:
        np.random.set_state(state)


def run_seed(seed: int | None, current: int | None, rng: np.random.Generator) -> int:
    """The run seed of the next episode: the one given, else the last one, else one drawn from `rng`."""
    if seed is not None:
        return int(seed)
    return current if current is not None else int(rng.integers(_DRAWN_SEEDS))


def policy_observation(observation: dict) -> Observation:
    """A LangGap `Observation` (what `Policy.act` takes) from one env's observation dict."""
    images = {key: value for key, value in observation.items() if key not in ("state", "instruction", "privileged")}
    privileged = observation.get("privileged")
    state = None if privileged is None else PrivilegedState(privileged)
    return Observation(state=observation["state"], images=images, privileged=state)


class LangGapTaskEnv(gym.Env):
    """One LangGap task; see the module docstring for the episode and seeding rules.

    Observation: a `Dict` of each camera in `cameras` (uint8, H x W x 3, upright), `state` (8-D
    float32: eef position, eef axis-angle, gripper joints), `instruction` (`Text`) and, only with
    `privileged=True`, `privileged` (the simulator facts scripted policies read,
    `langgap.sim.privileged`). Action: `Box(-1, 1, (7,))`, OSC_POSE delta + gripper.
    `max_steps` shortens the task's step limit (tests, quick looks).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": RENDER_FPS}

    def __init__(
        self,
        task: str,
        catalog: str = DEFAULT_CATALOG,
        cameras: tuple[str, ...] = (),
        image_size: int = 256,
        style: str = DEFAULT_STYLE,
        stepping: str = DEFAULT_STEPPING,
        render_mode: str | None = None,
        privileged: bool = False,
        max_steps: int | None = None,
        hard_reset: bool = False,
    ):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise LangGapError(f"unknown render mode {render_mode!r} (known: rgb_array)")
        if max_steps is not None and max_steps < 1:
            raise LangGapError(f"max_steps must be at least 1, got {max_steps}")
        self._catalog = load_catalog(catalog)
        found = self._catalog.get(task)
        self.task = found if max_steps is None else dataclasses.replace(found, max_steps=max_steps)
        self.style = style
        self.task.instruction(style)  # an unknown style fails here, not at the first reset
        self.cameras = tuple(cameras)
        self.render_mode = render_mode
        self.privileged = privileged
        # The simulator renders the observed cameras, and agentview for render() where asked.
        rendered = self.cameras + ((RENDER_CAMERA,) if render_mode and RENDER_CAMERA not in self.cameras else ())
        self._options = EnvOptions(
            cameras=rendered, image_size=image_size, privileged=privileged, stepping=stepping, hard_reset=hard_reset
        )
        self._goals = scene_goals(self.task, self._catalog)
        self._sim: TaskEnv | None = None  # built at the first reset (cheap to construct, e.g. in a vector's parent)
        self._run_seed: int | None = None
        self._watch: SceneWatch | None = None
        self._context = None
        self._planned: PlannedEpisode | None = None
        self._instructions: list[tuple[int, str]] = []  # the episode's instruction timeline so far
        self._done = False
        self.action_space = spaces.Box(-1.0, 1.0, shape=(ACTION_DIM,), dtype=np.float32)
        self.observation_space = self._observation_space(image_size)

    # -- spaces --------------------------------------------------------------------------------

    def _observation_space(self, image_size: int) -> spaces.Dict:
        entries: dict[str, spaces.Space] = {
            camera: spaces.Box(0, 255, shape=(image_size, image_size, 3), dtype=np.uint8) for camera in self.cameras
        }
        entries["state"] = spaces.Box(-np.inf, np.inf, shape=(STATE_DIM,), dtype=np.float32)
        entries["instruction"] = spaces.Text(max_length=MAX_INSTRUCTION, min_length=0, charset=INSTRUCTION_CHARSET)
        if self.privileged:
            # Its keys and shapes are the scene's (its objects, sites and joints): read from the simulator.
            from langgap.sim.privileged import privileged_state

            facts = privileged_state(self._simulator())
            boxes = {key: spaces.Box(-np.inf, np.inf, shape=np.shape(v), dtype=np.float64) for key, v in facts.items()}
            entries["privileged"] = spaces.Dict(boxes)
        return spaces.Dict(entries)

    def _simulator(self) -> TaskEnv:
        if self._sim is None:
            with global_rng_kept():
                self._sim = TaskEnv(self.task, self._options)
        return self._sim

    # -- episode -------------------------------------------------------------------------------

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Start an episode. `options`: `init_index` (default: drawn from `np_random`) and `condition`
        (the harness's language conditions: given, empty, shuffled, source, nonsense, switch:K; default given).
        Under `switch:K` the observation's instruction is the first task's until policy step K (the
        observation after the K-th step carries the task's own), as in `langgap eval`."""
        super().reset(seed=seed)
        options = dict(options or {})
        unknown = sorted(set(options) - set(_OPTIONS))
        if unknown:
            raise LangGapError(f"unknown reset option(s) {unknown} (known: {', '.join(_OPTIONS)})")
        sim = self._simulator()
        init_index = options.get("init_index")
        if init_index is None:
            init_index = int(self.np_random.integers(len(sim.init_states)))
        elif not isinstance(init_index, int | np.integer) or not 0 <= init_index < len(sim.init_states):
            raise LangGapError(
                f"init_index must be an integer in 0..{len(sim.init_states) - 1} for {self.task.id}, got {init_index!r}"
            )
        condition = options.get("condition", Condition.GIVEN.value)
        if not isinstance(condition, str) or unknown_conditions((condition,)):
            raise LangGapError(f"unknown condition {condition!r} ({CONDITION_HELP})")
        self._run_seed = run_seed(seed, self._run_seed, self.np_random)
        init_index = int(init_index)
        key = EpisodeKey(self.task.id, init_index, episode_seed(self._run_seed, init_index), condition)
        # The harness's plan entry for this episode (what `langgap eval` would run and record).
        watched = tuple(self._goals)
        if switch_step(condition) is not None:
            self._planned = switch_episode(key, self.task, self._catalog, self.style, sim.files.scene, watched)
        else:
            instruction = condition_instruction(self.task, self._catalog, condition, self.style, init_index)
            self._planned = PlannedEpisode(key, instruction, sim.files.scene, watched)
        self._context = planned_context(self._planned, self.task, self._catalog, self.style)
        self._instructions = [(0, self._planned.instruction)]
        with global_rng_kept():
            sim.reset(init_index, seed=key.seed, render=False)  # shown after settling, as in the harness
            sim.settle(capture=self.cameras)  # the observation's images, taken where robosuite samples
            self._watch = SceneWatch(sim, self._goals)
        self._done = False
        info = self._info(success=False)
        # What a LangGap policy is reset with; the goal only where the env was made privileged.
        seen = PolicySpec(sees_state=self.privileged, sees_goal=self.privileged)
        info["context"] = self._context.for_policy(seen)
        return self._observation(), info

    def step(self, action):
        """One policy step; reward 1.0 on the step the goal first holds (the episode then terminates)."""
        if self._watch is None:
            raise ResetNeeded("call reset() before step()")
        if self._done:
            raise ResetNeeded("the episode is over (terminated or truncated); call reset() to start another")
        sim = self._sim
        with global_rng_kept():
            success = sim.step(np.asarray(action, dtype=np.float64), capture=self.cameras)
            self._watch.observe()
        truncated = sim.truncated and not success
        self._done = success or truncated
        # The instruction the next observation carries: a switch takes effect at its policy step.
        self._instructions += [(k, text) for k, text in self._planned.changes if k == sim.steps]
        return self._observation(), 1.0 if success else 0.0, success, truncated, self._info(success)

    def _observation(self) -> dict[str, Any]:
        seen = self._sim.observe(self.cameras)
        observation: dict[str, Any] = dict(seen.images)
        observation["state"] = seen.state
        observation["instruction"] = self._instructions[-1][1]
        if self.privileged:
            observation["privileged"] = {key: np.array(v, dtype=np.float64) for key, v in seen.privileged.items()}
        return observation

    def _info(self, success: bool) -> dict[str, Any]:
        watch, task = self._watch, self.task
        switched = (self._planned.started_as, self._instructions[1][0]) if len(self._instructions) > 1 else None
        outcome = classify(
            task.id,
            task.kind,
            task.source,
            success,
            watch.reached,
            wrong_order=watch.wrong_order(success),
            switched=switched,
        )
        return {
            "task_id": task.id,
            "init_index": self._context.init_index,
            "seed": self._context.seed,
            "t0_hash": self._sim.t0_hash,
            "instruction_sha256": self._planned.instruction_sha256,
            "steps": self._sim.steps,
            "is_success": success,
            "outcome": str(outcome),
            "goals_holding": watch.holding(),  # the scene's task goals (its own included) true now
            "reached": dict(watch.reached),
            "instructions": list(self._instructions),  # (policy step, instruction) of each one sent so far
        }

    # -- rendering and lifetime ----------------------------------------------------------------

    def render(self) -> np.ndarray | None:
        """The upright agentview frame (`render_mode="rgb_array"`); None without a render mode. Where agentview
        is one of `cameras`, the frame is the observation's (taken where robosuite samples its observables);
        otherwise it is rendered on demand, one physics substep after that."""
        if self.render_mode is None:
            return None
        if self._watch is None:
            raise ResetNeeded("call reset() before render()")
        return self._sim.render(RENDER_CAMERA)

    def close(self) -> None:
        """Free the simulator (and its GL context)."""
        if self._sim is not None:
            self._sim.close()
            self._sim = None
            self._watch = None

    @property
    def simulator(self) -> TaskEnv:
        """The underlying `TaskEnv` (built on first use): privileged access for adapters and diagnostics."""
        return self._simulator()
