"""What executes work items wherever they run (in-process, a worker process, a Ray actor).

A `WorkRunner` dispatches on the item's kind: a planned episode (`PlannedEpisode`) and a shared rollout
of several (`SharedRollout`) run here, with the runner's policy; any other work item is a `Job` that does
its own work (`Job.perform`) with what the runner lends it (the catalog, a kept environment, the output
directory). A runner owns at most one
policy and one environment; the environment is built lazily for the task of the next item and kept
(soft resets) while consecutive items share the task; a task's files (`TaskFiles`) are resolved the first
time it comes. After an infrastructure failure everything is rebuilt (and the files resolved again), since a
crash may leave any of it broken.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from langgap.catalog.catalog import Catalog, load_catalog
from langgap.catalog.files import TaskFiles, task_files
from langgap.catalog.task import DEFAULT_STYLE, Task
from langgap.engine.episode import EpisodeSettings, execute_episode, execute_shared, video_hook
from langgap.engine.filming import VIDEO_DIR, clip_name
from langgap.engine.plan import PlannedEpisode
from langgap.engine.rollout import env_options_for
from langgap.engine.sharing import SharedRollout
from langgap.engine.work import Job, WorkItem
from langgap.errors import one_line
from langgap.policies import make_policy
from langgap.policies.base import Policy, config_hash, policy_config
from langgap.records import EpisodeRecord
from langgap.sim.env import CAMERAS, EnvOptions, TaskEnv
from langgap.stack import DEFAULT_SEED_SCHEME, DEFAULT_STEPPING
from langgap.video import FRAME_EVERY, VIDEO_SUFFIX


class PolicyServerHandle(Protocol):
    """Where a shared policy is served (`--shared-policy`); picklable, so it can cross into a worker."""

    def connect(self, worker: int) -> Policy:
        """A `Policy` for `worker` that forwards every call to the shared policy's server."""
        ...


@dataclass(frozen=True)
class RunnerSetup:
    """Everything a runner needs, picklable so it can cross into a worker process. Only episodes use a policy."""

    catalog: str
    policy: str = ""
    policy_args: dict[str, str] = field(default_factory=dict)
    style: str = DEFAULT_STYLE
    run_dir: str | None = None  # where work writes its files (a filmed episode's clip: its `videos` folder)
    stepping: str = DEFAULT_STEPPING  # how physics substeps are computed (`RunSpec.stepping`)
    seed_scheme: str = DEFAULT_SEED_SCHEME  # how a seed selects the placement (`RunSpec.seed_scheme`)
    policy_server: PolicyServerHandle | None = None  # a shared policy; None: each runner builds its own

    @property
    def output_dir(self) -> Path:
        """Where work writes its files: `run_dir`, or the working directory when none is given."""
        return Path(self.run_dir or ".")


class WorkFailure(Exception):
    """One attempt at a work item failed (infrastructure): its one-line message travels to the scheduler, which
    retries the item (`langgap.engine.work.AttemptsExhausted`: no attempt left)."""


class WorkRunner:
    """Does work items on one worker; see the module's docstring. `catalog`: `setup.catalog` as this process
    loaded it already (None: loaded here)."""

    def __init__(self, setup: RunnerSetup, worker: int = 0, catalog: Catalog | None = None):
        self.setup = setup
        self.worker = worker
        self.catalog = load_catalog(setup.catalog) if catalog is None else catalog
        self._files: dict[str, TaskFiles] = {}  # by task id: each task's, resolved the first time it comes
        self._policy = None
        self._settings: EpisodeSettings | None = None  # built with the policy (its config hash is the policy's)
        self._env: TaskEnv | None = None

    @property
    def output_dir(self) -> Path:
        """Where work writes its files (`RunnerSetup.output_dir`; a Ray actor's are sent to the driver's)."""
        return self.setup.output_dir

    def run(self, item: WorkItem, attempts: int = 1) -> Any:
        """Do one work item; raises WorkFailure on any infrastructure error (after discarding env and policy)."""
        try:
            if isinstance(item, PlannedEpisode):
                return self._run_episode(item, attempts)
            if isinstance(item, SharedRollout):
                return self._run_shared(item, attempts)
            if isinstance(item, Job):
                return item.perform(self)
            raise TypeError(f"not a work item: {type(item).__name__}")
        except Exception as exc:
            self.close()
            raise WorkFailure(one_line(exc)) from exc

    def kept_env(self, task: Task, options: EnvOptions) -> TaskEnv:
        """An environment of `task` built with `options`: the runner's own, kept while consecutive work
        asks for the same task and options (and closed with the runner)."""
        env = self._env
        if env is None or env.task.id != task.id or env.options != options:
            self._close_env()
            self._env = TaskEnv(task, options, self._files_of(task))
        return self._env

    def _files_of(self, task: Task) -> TaskFiles:
        """The files of `task` (`langgap.catalog.files.task_files`), resolved once by this runner."""
        files = self._files.get(task.id)
        if files is None:
            files = self._files[task.id] = task_files(task)
        return files

    def _run_episode(self, planned: PlannedEpisode, attempts: int) -> EpisodeRecord:
        task = self.catalog.get(planned.key.task_id)
        self._prepare(task, film=planned.film)
        frames: list = []
        hook = None
        if planned.film:
            hook = video_hook(self._env, frames, CAMERAS, every=FRAME_EVERY)
        record = execute_episode(
            planned, task, self.catalog, self._env, self._policy, self._settings, attempts=attempts, on_step=hook
        )
        if frames:
            from langgap.video import write_video

            clip = Path(VIDEO_DIR) / f"{clip_name(planned.key)}{VIDEO_SUFFIX}"
            write_video(self.output_dir / clip, frames)
            record.video = clip.as_posix()
        return record

    def _run_shared(self, item: SharedRollout, attempts: int) -> list[EpisodeRecord]:
        self._prepare(self.catalog.get(item.task_id), film=False)
        return execute_shared(item.members, self.catalog, self._env, self._policy, self._settings, attempts=attempts)

    def _prepare(self, task: Task, *, film: bool) -> None:
        """Build the policy (once) and an environment of `task` (filming's cameras when `film`)."""
        if self._policy is None:
            if self.setup.policy_server is not None:
                self._policy = self.setup.policy_server.connect(self.worker)
            else:
                self._policy = make_policy(self.setup.policy, self.setup.policy_args)
            policy_hash = config_hash(policy_config(self._policy))
            self._settings = EpisodeSettings(self.setup.policy, policy_hash, self.setup.style, self.worker)
        # An environment without the video cameras serves every episode but a filmed one (rendering
        # needs a GL context, which costs an environment build seconds and memory: only filming pays it).
        env, files = self._env, self._files_of(task)
        serves = env is not None and (not film or set(CAMERAS) <= set(env.options.cameras))
        if serves and env.can_switch_to(task, files):
            env.switch_task(task, files)
        else:
            self._close_env()
            self._env = TaskEnv(task, self._env_options(film), files)

    def _env_options(self, film: bool):
        filming = {}
        if film:
            # Videos show both cameras. A policy that reads no images sees none of them, so its clips skip
            # the reflection pass (~40 % of a render); a policy's own images keep the renderer settings it
            # was declared with.
            filming = {"cameras": CAMERAS}
            if not self._policy.spec.cameras:
                filming |= {"image_size": 256, "reflection": False}
        return env_options_for(
            self._policy, stepping=self.setup.stepping, seed_scheme=self.setup.seed_scheme, **filming
        )

    def _close_env(self) -> None:
        if self._env is not None:
            self._env.close()
            self._env = None

    def close(self) -> None:
        """Release the environment and the policy, and forget the tasks' files."""
        self._close_env()
        self._files.clear()
        if self._policy is not None and hasattr(self._policy, "close"):
            with contextlib.suppress(Exception):  # closing a broken policy must not hide the original failure
                self._policy.close()
        self._policy = None
