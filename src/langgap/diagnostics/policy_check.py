"""`langgap check-policy`: what a long `langgap eval` run would hit late, checked on one short episode first.

The policy is built as a worker builds it and run through the engine's own code (`execute_episode`: the
rollout, its action check `as_action_chunk`, the policy-error record) on the first episode eval would plan for
the selection (its first task, init state 0, the run's seed). That episode runs twice cut to `CHECK_CALLS`
policy calls, the policy reset once more in between, which shows the spec, what the policy receives and sends,
its actions, its lifecycle, whether the same seed gives the same actions, and its latency, from which the
run's wall time is computed (`langgap.diagnostics.policy_timing`). Then it is played whole, to its step limit
or its goal, within `budget_s` at the measured speed (the page says how much of it ran): a policy that fails
only late in an episode (a NaN from its tenth step) fails here, not in the run. A check that runs for more than
a few seconds says on stderr what it is doing.
"""

from __future__ import annotations

import contextlib
import sys
import time
import traceback
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from langgap.catalog.catalog import DEFAULT_CATALOG, Catalog, load_catalog
from langgap.catalog.task import DEFAULT_STYLE
from langgap.diagnostics.checks import Check, check_lines
from langgap.diagnostics.policy_timing import (
    RETRIED,
    WHOLE_EPISODE_BUDGET_S,
    EpisodeTimes,
    StepLimits,
    Timing,
    duration,
    latency_check,
    wall_time_check,
)
from langgap.engine.context import planned_context
from langgap.engine.episode import EpisodeSettings, execute_episode
from langgap.engine.plan import PlannedEpisode, build_plan
from langgap.engine.rollout import env_options_for
from langgap.engine.spec import DEFAULT_TIMEOUT_S, PAPER_EPISODES, SpecParameterError
from langgap.errors import LangGapError, SimulationError
from langgap.policies import policy_class, policy_kwargs
from langgap.policies.base import Policy, PolicyOutputError, PolicySpec, PolicySpecError, as_action_chunk
from langgap.records import EpisodeRecord
from langgap.sim.env import ACTION_LIMIT, CAMERAS, CameraImages, CameraNotDeclared, EnvOptions, Observation, TaskEnv
from langgap.vocabulary import Outcome

CHECK_CALLS = 4  # policy calls per check episode: the first (often a warm-up) and three more to time
NOTE_EVERY_S = 10.0  # a check still running says so on stderr this often
UPRIGHT = (
    "images upright: LIBERO's render rotated 180°, the orientation of openpi's LIBERO example and of LeRobot's "
    "LIBERO pipeline"
)
CAMERA_REMEDY = "declare every camera act reads in PolicySpec(cameras=...), and only those: each is rendered every call"
SPEC_REMEDY = (
    f"declare cameras LIBERO has ({', '.join(CAMERAS)}), each once, an image_size in 16..1024, 1 <= replan <= chunk"
)
LIFECYCLE_REMEDY = "make reset start every episode afresh: clear what the last episode left in the policy"
# The checks after the spec's, in the order shown; each needs the ones before it to have run.
EPISODE_CHECKS = ("inputs", "actions", "lifecycle", "determinism", "whole episode", "latency", "wall time")


@dataclass
class PolicyCheck:
    """What `check_policy` found: a heading, the checks in the order shown, and how long it took."""

    heading: list[str]
    checks: list[Check]
    seconds: float = 0.0

    @property
    def failed(self) -> list[Check]:
        """The checks that failed."""
        return [c for c in self.checks if c.ok is False]

    @property
    def exit_code(self) -> int:
        """`langgap check-policy`'s exit status: 0 when no check failed, else 1."""
        return 1 if self.failed else 0

    def page(self) -> str:
        """The one page `langgap check-policy` prints."""
        skipped = sum(c.ok is None for c in self.checks)
        warned = sum(bool(c.ok and c.warning) for c in self.checks)
        ran = len(self.checks) - skipped
        verdict = f"{len(self.failed)} of {ran} checks failed" if self.failed else f"all {ran} checks passed"
        if warned:
            verdict += f", {warned} with a warning"
        if skipped:
            verdict += f", {skipped} not run"
        lines = [*self.heading, *(line for check in self.checks for line in check_lines(check))]
        return "\n".join([*lines, f"check-policy: {verdict} ({duration(self.seconds)})"])


def check_policy(
    name: str,
    policy_args: dict[str, str] | None = None,
    *,
    catalog: str = DEFAULT_CATALOG,
    tasks: str | None = None,
    style: str = DEFAULT_STYLE,
    episodes: int = PAPER_EPISODES,
    timeout_s: float = DEFAULT_TIMEOUT_S,
    budget_s: float = WHOLE_EPISODE_BUDGET_S,
    env: TaskEnv | None = None,
    say: Callable[[str], None] | None = None,
) -> PolicyCheck:
    """Check policy `name`, built with `policy_args`, for `langgap eval --catalog catalog --tasks tasks
    --episodes episodes --timeout timeout_s` (see the module docstring); the whole episode may take `budget_s`
    at the measured speed. `say` gets the lines of a check that takes a while (default: stderr).

    Bad input raises a `LangGapError`: an unknown policy or argument, a selection or episode count eval
    refuses, a timeout that is not positive, a constructor that raises one (no checkpoint, no server).
    `env` is an environment to run on instead of building one, used when it has the options the policy
    needs and the scene of the check's task (a caller checking several policies shares one); it is left
    open. An exception the engine raises outside the policy propagates.
    """
    began = time.perf_counter()
    for parameter, value in (("timeout_s", timeout_s), ("budget_s", budget_s)):
        if value <= 0:
            raise SpecParameterError(f"{{{parameter}}} must be positive, got {{got:g}}", got=value)
    loaded = load_catalog(catalog)
    plan = build_plan(loaded.select(tasks), loaded, episodes=episodes, style=style)
    heading = [f"langgap check-policy {name}"]
    try:
        policy = policy_class(name)(**policy_kwargs(name, policy_args))
    except LangGapError:
        raise
    except PolicySpecError as exc:
        checks = [Check("spec", False, str(exc), SPEC_REMEDY)]
        return PolicyCheck(heading, checks, time.perf_counter() - began)
    except Exception as exc:  # a bug in the policy's code: the check's finding, not bad input
        checks = [Check("build", False, raised_at("the constructor", exc), "fix the exception in the constructor")]
        return PolicyCheck(heading, checks, time.perf_counter() - began)
    heading[0] += f": {_class_name(policy)}, built in {duration(time.perf_counter() - began)}"
    checker = _Checker(policy, name, loaded, plan, style, timeout_s, budget_s, say or _to_stderr)
    try:
        checks = checker.run(env)
    finally:
        if not checker.closed and callable(close := getattr(policy, "close", None)):
            with contextlib.suppress(Exception):  # a check that failed says what is wrong; this is clean-up
                close()
    if checker.ran:
        heading.append(checker.episode_line())
    return PolicyCheck(heading, checks, time.perf_counter() - began)


def _to_stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def raised_at(where: str, exc: BaseException) -> str:
    """`where` raised `exc`: its type and message, and the line of the policy's code it came from."""
    frames = traceback.extract_tb(exc.__traceback__)
    origin = ""
    if frames:
        frame = frames[-1]
        path = Path(frame.filename)
        shown = path.relative_to(Path.cwd()) if path.is_relative_to(Path.cwd()) else path
        origin = f" ({shown}:{frame.lineno}, in {frame.name})"
    lines = str(exc).strip().splitlines()
    return f"{where} raised {type(exc).__name__}: {lines[-1] if lines else ''}{origin}"


def _class_name(policy) -> str:
    return f"{type(policy).__module__}.{type(policy).__qualname__}"


@dataclass
class _Call:
    started: float
    seconds: float
    output: Any


class _ReadImages(CameraImages):
    """An observation's images that remember which cameras the policy read."""

    def __init__(self, images: dict, read: set[str]):
        super().__init__(images)
        self._read = read

    def __getitem__(self, camera):
        self._read.add(camera)
        return super().__getitem__(camera)

    def get(self, camera, default=None):
        self._read.add(camera)
        return super().get(camera, default)

    def __iter__(self):
        self._read.update(self.keys())
        return super().__iter__()

    def values(self):
        self._read.update(self.keys())
        return super().values()

    def items(self):
        self._read.update(self.keys())
        return super().items()


class _Watched:
    """A policy as the engine sees it, each call timed and each output kept, the cameras it reads noted, and an
    exception it raised remembered with the method that raised it (so the check tells the policy's failures
    from the engine's). A call that ends more than `NOTE_EVERY_S` after the last line `say` got says so."""

    def __init__(self, policy: Policy, say: Callable[[str], None]):
        self.policy = policy
        self.spec: PolicySpec = policy.spec
        self.calls: list[_Call] = []
        self.first_observation: Observation | None = None
        self.raised: tuple[str, Exception] | None = None
        self.cameras_read: set[str] = set()
        self.total_calls = 0  # over every episode of the check
        self.activity = ""  # what the check is running, for its notes
        self._say = say
        self.quiet_since = time.perf_counter()  # the last note, or the start of what is running

    def note(self, line: str) -> None:
        """Say `line` (on stderr) and start counting the silence again."""
        self._say(f"note: check-policy: {line}")
        self.quiet_since = time.perf_counter()

    def reset(self, context) -> None:
        self._guarded("reset", self.policy.reset, context)

    def act(self, observation: Observation):
        observation = replace(observation, images=_ReadImages(observation.images, self.cameras_read))
        if self.first_observation is None:
            self.first_observation = observation
        started = time.perf_counter()
        output = self._guarded("act", self.policy.act, observation)
        self.calls.append(_Call(started, time.perf_counter() - started, output))
        self.total_calls += 1
        if time.perf_counter() - self.quiet_since > NOTE_EVERY_S:
            self.note(f"{self.activity}: {len(self.calls)} calls so far, the last {duration(self.calls[-1].seconds)}")
        return output

    def _guarded(self, method: str, call: Callable, argument):
        try:
            return call(argument)
        except Exception as exc:
            self.raised = (method, exc)
            raise


@dataclass
class _Episode:
    record: EpisodeRecord
    calls: list[_Call]
    began: float
    ended: float

    def times(self) -> EpisodeTimes:
        """The episode's calls, its start (up to the first call) and its steps (the rest, calls left out)."""
        calls = tuple(c.seconds for c in self.calls)
        start = (self.calls[0].started if self.calls else self.ended) - self.began
        simulator = self.ended - self.began - start - sum(calls)
        return EpisodeTimes(calls=calls, steps=self.record.steps, start_s=start, simulator_s=simulator)

    def policy_error(self, spec: PolicySpec) -> PolicyOutputError | None:
        """The engine's verdict on the output that ended the episode as a policy error (None: none did)."""
        if self.record.outcome != Outcome.POLICY_ERROR:
            return None
        try:
            as_action_chunk(self.calls[-1].output, spec)
        except PolicyOutputError as exc:
            return exc
        raise AssertionError(f"the engine refused an output its own check accepts: {self.record.error}")


class _Failed(Exception):
    """The policy failed a check episode: `check` says how."""

    def __init__(self, check: Check):
        super().__init__(check.detail)
        self.check = check


class _Checker:
    """One policy's checks, in the order `run` shows them."""

    def __init__(
        self,
        policy: Policy,
        name: str,
        catalog: Catalog,
        plan: list[PlannedEpisode],
        style: str,
        timeout_s: float,
        budget_s: float,
        say: Callable[[str], None],
    ):
        self.policy, self.catalog, self.plan = policy, catalog, plan
        # As eval's first worker runs it, but with no config hash: no record of the check is stored.
        self.settings = EpisodeSettings(policy_name=name, policy_hash="", style=style)
        self.timeout_s, self.budget_s, self.say = timeout_s, budget_s, say
        self.planned = plan[0]
        self.task = catalog.get(self.planned.key.task_id)
        self.watched: _Watched  # once the policy is known to have a spec (`run`)
        self.ran = False  # whether the check episodes started
        self.closed = False  # whether the lifecycle check closed the policy

    def run(self, env: TaskEnv | None) -> list[Check]:
        """Every check; those that need what failed before them are shown as not run."""
        interface = self._interface()
        if not interface.ok:
            return [interface]
        self.watched = _Watched(self.policy, self.say)
        spec, options = self._spec()
        checks = [interface, spec, self._privileges()]
        if options is None:
            return [*checks, *(Check(name, None, "not run: spec failed") for name in EPISODE_CHECKS)]
        short = replace(self.task, max_steps=short_steps(self.task.max_steps, self.policy.spec))
        own = env is None or env.options != options or not env.can_switch_to(short)
        if own:
            env = TaskEnv(short, options)
        else:
            env.switch_task(short)
        self.ran = True
        try:
            return checks + self._episodes(env)
        finally:
            if own:
                env.close()

    def episode_line(self) -> str:
        """What the check ran, for the heading."""
        key, steps = self.planned.key, self.task.max_steps
        return (
            f"eval's first episode, twice: {key.task_id} ({self.catalog.name}), init state {key.init_index}, "
            f"seed {key.seed}, cut to {short_steps(steps, self.policy.spec)} of its {steps} steps"
        )

    def _interface(self) -> Check:
        missing = [m for m in ("spec", "reset", "act") if not hasattr(self.policy, m)]
        spec = getattr(self.policy, "spec", None)
        if missing or not isinstance(spec, PolicySpec):
            detail = f"no {', '.join(missing)}" if missing else f"spec is a {type(spec).__name__}, not a PolicySpec"
            remedy = "give the class spec = PolicySpec(...), reset(context) and act(observation): see Policy"
            return Check("interface", False, detail, remedy)
        return Check("interface", True, "spec, reset and act" + (", close" if hasattr(self.policy, "close") else ""))

    def _spec(self) -> tuple[Check, EnvOptions | None]:
        spec = self.policy.spec
        try:
            options = env_options_for(self.policy)
        except SimulationError as exc:
            return Check("spec", False, str(exc), SPEC_REMEDY), None
        size = f"{spec.image_size}×{spec.image_size}"
        seen = f"cameras {', '.join(spec.cameras)} at {size}" if spec.cameras else "no camera"
        chunking = f"chunk {spec.chunk}, replan {spec.replan}: " + (
            "one action per call"
            if spec.chunk == 1
            else f"up to {spec.chunk} actions per call, the first {spec.replan} executed"
        )
        return Check("spec", True, f"{seen}; {chunking}"), options

    def _privileges(self) -> Check:
        spec = self.policy.spec
        said = []
        if spec.sees_goal:
            said.append(
                "sees_goal: told the task id and the goal at reset, so a scripted reference (marked †), never a "
                "policy under test: its runs show what is possible, not whether a policy reads"
            )
        if spec.sees_state:
            said.append(
                "sees_state: observations carry the simulator state (object poses, contacts, joints)"
                + (
                    ""
                    if spec.sees_goal
                    else "; still a policy under test (marked ‡), but not comparable with one that sees only images"
                )
            )
        if not said:
            said.append("neither privilege: a policy under test, told only what a real robot's policy is")
        if not spec.reads_instruction:
            said.append(
                "instruction-blind (reads_instruction=False): told no instruction, so episodes that start alike "
                "may share one rollout (--share-rollouts)"
            )
        return Check("privileges", True, "\n".join(said))

    def _episodes(self, env: TaskEnv) -> list[Check]:
        try:
            first = self._episode(env, "the episode", "actions")
        except _Failed as failed:
            found = {failed.check.name: failed.check}
            if self.watched.first_observation is not None:
                found["inputs"] = self._inputs()
            reason = f"not run: {failed.check.name} failed"
            return [found.get(name) or Check(name, None, reason) for name in EPISODE_CHECKS]
        actions = self._actions(first)
        lifecycle, second = self._lifecycle(env)
        determinism = self._determinism(first, second)
        episodes = [first] if second is None else [first, second]
        timing = Timing.measured([episode.times() for episode in episodes])
        whole = self._whole_episode(env, timing) if second is not None else Check("whole episode", None, "not run")
        limits: StepLimits = Counter()
        for planned in self.plan:
            task = self.catalog.get(planned.key.task_id)
            limits[task.suite, task.max_steps] += 1
        tasks = len({planned.key.task_id for planned in self.plan})
        return [
            self._inputs(timing),
            actions,
            lifecycle,
            determinism,
            whole,
            latency_check(timing, limits, self.timeout_s),
            wall_time_check(timing, limits, tasks, self.catalog.name),
        ]

    def _whole_episode(self, env: TaskEnv, timing: Timing) -> Check:
        """Play the episode to its step limit or its goal, or as far as `budget_s` allows at the measured speed."""
        limit = self.task.max_steps
        steps = max((n for n in range(1, limit + 1) if timing.episode_s(n) <= self.budget_s), default=1)
        expected = f"about {duration(timing.episode_s(steps))} at the measured speed"
        self.watched.note(f"playing the episode whole: {steps} of its {limit} steps ({expected})")
        env.switch_task(replace(self.task, max_steps=steps))
        try:
            episode = self._episode(env, "the whole episode", "whole episode")
        except _Failed as failed:
            return failed.check
        record = episode.record
        seconds = duration(episode.ended - episode.began)
        played = f"{record.steps} of its {limit} steps, {len(episode.calls)} calls, in {seconds}"
        if record.success:
            return Check("whole episode", True, f"played to the goal: {played}")
        if steps == limit:
            return Check("whole episode", True, f"played to its step limit, no goal reached: {played}")
        return Check(
            "whole episode",
            True,
            f"played {played}: as many as --budget {self.budget_s:g} s allows at the measured speed",
            warning=f"the steps after {record.steps} are not checked: give check-policy a larger --budget to play "
            "the whole episode",
        )

    def _episode(self, env: TaskEnv, which: str, check: str) -> _Episode:
        """Run the planned episode through the engine; raises `_Failed` (named `check`) when the policy failed it:
        a lifecycle failure when the check is the lifecycle's, or when a reset raised."""
        self.watched.calls = []
        self.watched.activity = which
        self.watched.quiet_since = time.perf_counter()
        began = time.perf_counter()
        try:
            record = execute_episode(self.planned, self.task, self.catalog, env, self.watched, self.settings)
        except Exception as exc:
            raised = self.watched.raised
            if raised is None or raised[1] is not exc:
                raise  # the engine's failure, not the policy's
            method = raised[0]
            name = check if method == "act" else "lifecycle"
            detail = raised_at(f"{which}: {method}" if which != "the episode" else method, exc)
            remedy = CAMERA_REMEDY if isinstance(exc, CameraNotDeclared) else f"fix the exception: {RETRIED}"
            raise _Failed(Check(name, False, detail, remedy)) from None
        episode = _Episode(record, self.watched.calls, began, time.perf_counter())
        error = episode.policy_error(self.policy.spec)
        if error is not None:
            where = f"call {len(episode.calls)}" if which == "the episode" else f"{which}, call {len(episode.calls)}"
            where += f" (step {record.steps + 1})" if check == "whole episode" else ""
            remedy = LIFECYCLE_REMEDY if check == "lifecycle" else error.remedy
            raise _Failed(Check(check, False, f"{where}: {error} (eval records a policy_error)", remedy))
        return episode

    def _inputs(self, timing: Timing | None = None) -> Check:
        """What the policy receives (and, for a policy that shows it, sends); with the episodes' `timing`, a warning
        for declared cameras that act never read, since each is rendered every call."""
        unread = [c for c in self.policy.spec.cameras if c not in self.watched.cameras_read]
        observation = self.watched.first_observation
        received = [f"state {_described(observation.state)}"]
        received += [f"{camera} {_described(image)}" for camera, image in dict.items(observation.images)]
        received.append(
            f"instruction {_quoted(observation.instruction)}" if observation.instruction else "no instruction"
        )
        if observation.privileged is not None:
            received.append(f"the simulator state ({len(observation.privileged)} arrays)")
        lines = ["receives " + ", ".join(received)]
        if observation.images:
            lines.append(UPRIGHT)
        model_inputs = getattr(self.policy, "model_inputs", None)
        if callable(model_inputs):
            sent = model_inputs(observation)
            lines.append("sends " + ", ".join(f"{key} {_described(value)}" for key, value in sent.items()))
        warning = ""
        if unread and timing is not None:
            warning = (
                f"act never read {', '.join(unread)} in {self.watched.total_calls} calls, yet every call renders "
                f"the declared cameras (a simulator step here takes {duration(timing.step_s)}, renders included): "
                f"{CAMERA_REMEDY}"
            )
        return Check("inputs", True, "\n".join(lines), warning=warning)

    def _actions(self, episode: _Episode) -> Check:
        spec = self.policy.spec
        chunks = [as_action_chunk(call.output, spec) for call in episode.calls]
        dtypes = [np.asarray(c.output).dtype for c in episode.calls]
        shapes = Counter(f"{np.shape(c.output)} {dtype}" for c, dtype in zip(episode.calls, dtypes, strict=True))
        values = np.concatenate(chunks)
        largest = float(np.abs(values).max())
        outside = int((np.abs(values) > ACTION_LIMIT).sum())
        shown = ", ".join(f"{shape} ×{n}" if len(shapes) > 1 else shape for shape, n in shapes.items())
        detail = f"{len(chunks)} calls returned {shown}: finite, largest |value| {largest:.3g}"
        if any(dtype.kind in "iub" for dtype in dtypes):
            detail += "; integers are taken as the same numbers in float64, as eval takes them"
        fewest = min(len(chunk) for chunk in chunks)
        if fewest < spec.replan:
            detail += f"; {fewest} action(s) in a call, fewer than replan={spec.replan}: it is asked again sooner"
        if outside:
            detail += (
                f"\n{outside} of {values.size} values outside [-{ACTION_LIMIT:g}, {ACTION_LIMIT:g}]: robosuite "
                "clips them, so the robot does not move as the policy asked"
            )
            remedy = (
                f"return actions in [-{ACTION_LIMIT:g}, {ACTION_LIMIT:g}] (OSC_POSE deltas, gripper -1 open / +1 "
                "closed): unnormalise a model's output with its training data's statistics"
            )
            return Check("actions", False, detail, remedy)
        return Check("actions", True, detail)

    def _lifecycle(self, env: TaskEnv) -> tuple[Check, _Episode | None]:
        done = ["reset", "reset again", "a second episode"]
        try:
            context = planned_context(self.planned, self.task, self.catalog, self.settings.style)
            self.watched.reset(context.for_policy(self.policy.spec))  # twice in a row: the episode resets again
            second = self._episode(env, "the second episode", "lifecycle")
        except _Failed as failed:
            return failed.check, None
        except Exception as exc:
            if self.watched.raised is None or self.watched.raised[1] is not exc:
                raise
            return Check("lifecycle", False, raised_at("reset again", exc), LIFECYCLE_REMEDY), None
        close = getattr(self.policy, "close", None)
        if callable(close):
            self.closed = True
            for attempt in ("close", "close again"):
                try:
                    close()
                except Exception as exc:
                    remedy = "make close() safe to call twice: the second call does nothing, as a file's"
                    return Check("lifecycle", False, raised_at(attempt, exc), remedy), second
                done.append(attempt)
        else:
            done.append("no close() (optional)")
        return Check("lifecycle", True, ", ".join(done)), second

    def _determinism(self, first: _Episode, second: _Episode | None) -> Check:
        if second is None:
            return Check("determinism", None, "not run: the second episode failed")
        spec = self.policy.spec
        differs = _first_difference(first.calls, second.calls, spec)
        key = self.planned.key
        same = f"the same episode twice (init state {key.init_index}, seed {key.seed})"
        if differs is None:
            declared = "; declared stochastic, but reproducible on this seed" if spec.stochastic else ""
            return Check("determinism", True, f"{same} gave the same actions ({len(first.calls)} calls){declared}")
        if spec.stochastic:
            return Check(
                "determinism",
                True,
                f"declared stochastic: {same} gave other actions from {differs}; a re-run is a new sample, and "
                "--video's replays may not match the episodes they film",
            )
        remedy = (
            "draw randomness from a generator seeded in reset from context.seed and context.init_index (as "
            "`random` does), or declare PolicySpec(stochastic=True)"
        )
        return Check("determinism", False, f"{same} gave other actions from {differs}", remedy)


def short_steps(max_steps: int, spec: PolicySpec) -> int:
    """The step limit of a check episode for a task of `max_steps` steps."""
    return min(max_steps, CHECK_CALLS * spec.replan)


def _first_difference(first: list[_Call], second: list[_Call], spec: PolicySpec) -> str | None:
    """Where the second episode's action chunks first differ from the first's (None: nowhere)."""
    for index, (a, b) in enumerate(zip(first, second, strict=False), start=1):
        chunk_a, chunk_b = as_action_chunk(a.output, spec), as_action_chunk(b.output, spec)
        if chunk_a.shape != chunk_b.shape:
            return f"call {index} on ({chunk_a.shape[0]} then {chunk_b.shape[0]} actions)"
        if not np.array_equal(chunk_a, chunk_b):
            return f"call {index} on (largest difference {np.abs(chunk_a - chunk_b).max():.3g})"
    if len(first) != len(second):
        return f"call {min(len(first), len(second)) + 1} on ({len(first)} then {len(second)} calls)"
    return None


def _described(value) -> str:
    """An input as shown on the page: an array's dtype and shape, a string quoted, a map's size."""
    shape, dtype = getattr(value, "shape", None), getattr(value, "dtype", None)
    if shape is not None and dtype is not None:
        return f"{str(dtype).removeprefix('torch.')} {tuple(shape)}"
    if isinstance(value, str):
        return _quoted(value)
    if isinstance(value, dict):
        return f"(a map of {len(value)})"
    if isinstance(value, list | tuple):
        return f"[{', '.join(_described(v) for v in value)}]"
    return type(value).__name__


def _quoted(text: str, width: int = 90) -> str:
    return repr(text if len(text) <= width else text[: width - 1] + "…")
