"""What executes episodes wherever they run (in-process, a worker process, a Ray actor).

An `EpisodeRunner` owns one policy and at most one environment; the environment is built lazily
for the task of the next episode and kept (soft resets) while consecutive episodes share the task.
After an infrastructure failure everything is rebuilt, since a crash may leave either broken.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from langgap.catalog.catalog import load_catalog
from langgap.engine.episode import execute_episode, video_hook
from langgap.engine.filming import VIDEO_DIR, clip_name
from langgap.engine.plan import PlannedEpisode
from langgap.engine.rollout import env_options_for
from langgap.errors import one_line
from langgap.policies import make_policy
from langgap.policies.base import Policy, config_hash, policy_config
from langgap.records import EpisodeRecord
from langgap.sim.env import CAMERAS, TaskEnv
from langgap.stack import DEFAULT_STEPPING
from langgap.video import FRAME_EVERY, VIDEO_SUFFIX


class PolicyServerHandle(Protocol):
    """Where a shared policy is served (`--shared-policy`); picklable, so it can cross into a worker."""

    def connect(self, worker: int) -> Policy:
        """A `Policy` for `worker` that forwards every call to the shared policy's server."""
        ...


@dataclass(frozen=True)
class RunnerSetup:
    """Everything a runner needs, picklable so it can cross into a worker process."""

    catalog: str
    policy: str
    policy_args: dict[str, str]
    style: str
    run_dir: str | None = None  # where a filmed episode's clip goes (its `videos` folder)
    stepping: str = DEFAULT_STEPPING  # how physics substeps are computed (`RunSpec.stepping`)
    policy_server: PolicyServerHandle | None = None  # a shared policy; None: each runner builds its own


class EpisodeFailure(Exception):
    """An episode could not be run (infrastructure): its one-line message travels to the scheduler."""


class EpisodeRunner:
    def __init__(self, setup: RunnerSetup, worker: int = 0):
        self.setup = setup
        self.worker = worker
        self.catalog = load_catalog(setup.catalog)
        self._policy = None
        self._policy_hash = ""
        self._env: TaskEnv | None = None

    def run(self, planned: PlannedEpisode, attempts: int = 1) -> EpisodeRecord:
        """Run one episode; raises EpisodeFailure on any infrastructure error (after discarding env and policy)."""
        try:
            return self._run(planned, attempts)
        except Exception as exc:
            self.close()
            raise EpisodeFailure(one_line(exc)) from exc

    def _run(self, planned: PlannedEpisode, attempts: int) -> EpisodeRecord:
        task = self.catalog.get(planned.key.task_id)
        if self._policy is None:
            if self.setup.policy_server is not None:
                self._policy = self.setup.policy_server.connect(self.worker)
            else:
                self._policy = make_policy(self.setup.policy, self.setup.policy_args)
            self._policy_hash = config_hash(policy_config(self._policy))
        # An environment without the video cameras serves every episode but a filmed one (rendering
        # needs a GL context, which costs an environment build seconds and memory: only filming pays it).
        env = self._env
        if (
            env is not None
            and env.can_switch_to(task)
            and (not planned.film or set(CAMERAS) <= set(env.options.cameras))
        ):
            env.switch_task(task)
        else:
            self._close_env()
            self._env = TaskEnv(task, self._env_options(planned.film))
        frames: list = []
        hook = None
        if planned.film:
            hook = video_hook(self._env, frames, CAMERAS, every=FRAME_EVERY)
        record = execute_episode(
            planned,
            task,
            self.catalog,
            self._env,
            self._policy,
            policy_name=self.setup.policy,
            policy_hash=self._policy_hash,
            style=self.setup.style,
            worker=self.worker,
            attempts=attempts,
            on_step=hook,
        )
        if frames:
            from langgap.video import write_video

            clip = Path(VIDEO_DIR) / f"{clip_name(planned.key)}{VIDEO_SUFFIX}"
            write_video(Path(self.setup.run_dir or ".") / clip, frames)
            record.video = clip.as_posix()
        return record

    def _env_options(self, film: bool):
        filming = {}
        if film:
            # Videos show both cameras. A policy that reads no images sees none of them, so its clips skip
            # the reflection pass (~40 % of a render); a policy's own images keep the renderer settings it
            # was declared with.
            filming = {"cameras": CAMERAS}
            if not self._policy.spec.cameras:
                filming |= {"image_size": 256, "reflection": False}
        return env_options_for(self._policy, stepping=self.setup.stepping, **filming)

    def _close_env(self) -> None:
        if self._env is not None:
            self._env.close()
            self._env = None

    def close(self) -> None:
        """Release the environment and the policy."""
        self._close_env()
        if self._policy is not None and hasattr(self._policy, "close"):
            with contextlib.suppress(Exception):  # closing a broken policy must not hide the original failure
                self._policy.close()
        self._policy = None
