"""One episode: reset to a fixed init state, settle, then the policy acts until success or the step limit."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from langgap.engine.watch import OrderWatch, SceneWatch
from langgap.goals import Goal, GoalProgress
from langgap.policies.base import Policy, TaskContext, as_action_chunk, observation_for
from langgap.sim.env import SETTLE_STEPS, EnvOptions, TaskEnv

# Called after every policy step with (env, step_index, action); used for videos and demonstrations.
# A hook that reads images has a `cameras_at(step)` method naming the cameras it reads after that step:
# they are rendered inside the step, where robosuite samples its observables (`TaskEnv.step`).
StepHook = Callable[[TaskEnv, int, np.ndarray], None]


@dataclass
class RolloutResult:
    success: bool
    steps: int
    t0_hash: str
    policy_calls: int
    reached: dict[str, int] = field(default_factory=dict)  # watched goal -> first step it became true
    at_start: list[str] = field(default_factory=list)  # watched goals already true after settling
    at_end: list[str] = field(default_factory=list)  # watched goals true when the episode ended
    wrong_order: bool = False  # an ordered goal's parts all held at some step, but not in the order asked
    instructions: list[tuple[int, str]] = field(default_factory=list)  # (policy step, instruction) sent


def env_options_for(policy: Policy, **overrides) -> EnvOptions:
    """The cheapest environment that shows `policy` everything it declared, and nothing else."""
    spec = policy.spec
    options = {"cameras": tuple(spec.cameras), "image_size": spec.image_size, "privileged": spec.sees_state}
    options.update(overrides)
    return EnvOptions(**options)


def _cameras_read_after(env: TaskEnv, query: tuple[str, ...], on_step: StepHook | None) -> tuple[str, ...]:
    """The cameras read after the coming step: the policy's (`query`, when it is asked next; never after
    the episode's last step) and the hook's."""
    step = env.steps + 1
    hook = getattr(on_step, "cameras_at", None)
    wanted = (*(query if step < env.task.max_steps else ()), *(hook(step) if hook is not None else ()))
    return tuple(dict.fromkeys(wanted))


def run_episode(
    env: TaskEnv,
    policy: Policy,
    context: TaskContext,
    *,
    watch: Mapping[str, Goal] | None = None,
    on_step: StepHook | None = None,
    on_start: Callable[[TaskEnv], None] | None = None,
    settle_steps: int = SETTLE_STEPS,
    sampled_start: bool = False,
    changes: Sequence[tuple[int, str]] = (),
) -> RolloutResult:
    """Run one episode of `policy` on `env` and return its outcome.

    `watch` maps names to goals (`langgap.goals` expressions) evaluated after every step, each with its
    own history (ordered goals); the first step at which each becomes true is returned in `reached` (a
    goal already true after settling, order ignored, is reported in `at_start` instead, never as
    reached). The episode stops at the first step the task's own goal holds (LIBERO's success
    criterion) or at the task's step limit. For an ordered task goal, `wrong_order` says whether its
    parts all held at some step without the goal being met (right goals, wrong order).
    `on_start` sees the environment after settling, before the first action. `sampled_start` starts
    from the placement LIBERO samples with the context's seed instead of init state `init_index`
    (demonstrations; see `TaskEnv.reset`).
    The policy is told the goal only if its spec `sees_goal`, and shown the simulator state only if it
    `sees_state`, whatever `context` and `env` hold. Exceptions from the policy propagate; a malformed
    action (or a chunk longer than the spec's) raises `PolicyOutputError`.
    Every observation carries the instruction in force: the context's, until policy step K of each
    (K, instruction) in `changes`, when the new one takes effect and the rest of an action chunk is
    dropped (the policy is asked again at once, as a person who changed their mind would expect).
    """
    _begin(env, policy, context, settle_steps=settle_steps, sampled_start=sampled_start, on_start=on_start)
    scene = SceneWatch(env, watch or {})

    def observed(success: bool, _calls: int, _sent: list[tuple[int, str]]) -> bool:
        scene.observe()
        return success

    calls, instructions = _act(env, policy, context, observed, on_step=on_step, changes=changes)
    success = env.success()
    return _result(env, scene, success, calls, instructions, scene.wrong_order(success))


def _result(
    env: TaskEnv,
    scene: SceneWatch,
    success: bool,
    calls: int,
    instructions: list[tuple[int, str]],
    wrong_order: bool,
) -> RolloutResult:
    """An episode's result as it stands at `env`'s current step, its scene goals judged by `scene`."""
    return RolloutResult(
        success=success,
        steps=env.steps,
        t0_hash=env.t0_hash or "",
        policy_calls=calls,
        reached=dict(scene.reached),
        at_start=scene.at_start,
        at_end=scene.holding(),
        wrong_order=wrong_order,
        instructions=instructions,
    )


def _begin(
    env: TaskEnv,
    policy: Policy,
    context: TaskContext,
    *,
    settle_steps: int,
    sampled_start: bool,
    on_start: Callable[[TaskEnv], None] | None,
) -> None:
    """Reset `env` to the context's start, reset the policy with what its spec lets it see, settle."""
    spec = policy.spec
    # The policy first looks after settling: an image of the unsettled start would be thrown away.
    env.reset(None if sampled_start else context.init_index, seed=context.seed, render=False)
    policy.reset(context.for_policy(spec))  # the goal reaches only policies that declare `sees_goal`
    env.settle(settle_steps, capture=tuple(spec.cameras))
    if on_start is not None:
        on_start(env)


def _act(
    env: TaskEnv,
    policy: Policy,
    context: TaskContext,
    stop: Callable[[bool, int, list[tuple[int, str]]], bool],
    *,
    on_step: StepHook | None = None,
    changes: Sequence[tuple[int, str]] = (),
) -> tuple[int, list[tuple[int, str]]]:
    """The policy acts, step by step, until `stop(success, policy calls so far, instructions sent so far)`
    (called after every step, before `on_step`; `success`: the env's task goal) says so or the step limit is
    reached. Returns (policy calls, the (policy step, instruction) of every instruction sent)."""
    spec = policy.spec
    queue: list[np.ndarray] = []
    calls = 0
    instructions = [(0, context.instruction)]
    pending = sorted(changes)
    while not env.truncated:
        while pending and pending[0][0] <= env.steps:
            instructions.append((env.steps, pending.pop(0)[1]))
            queue = []
        if not queue:
            observation = replace(env.observe(spec.cameras), instruction=instructions[-1][1])
            chunk = as_action_chunk(policy.act(observation_for(observation, spec)), spec)
            calls += 1
            queue = list(chunk[: spec.replan])
        action = queue.pop(0)
        # The policy is asked after this step when its chunk runs out or the instruction switches there.
        asked_next = not queue or bool(pending and pending[0][0] <= env.steps + 1)
        success = env.step(action, capture=_cameras_read_after(env, spec.cameras if asked_next else (), on_step))
        stopping = stop(success, calls, instructions)
        if on_step is not None:
            on_step(env, env.steps, action)
        if stopping:
            break
    return calls, instructions


@dataclass
class SharedRollout:
    """One rollout judged as the episode of each of several goals (`run_shared_episode`): `results` holds
    the result of every goal decided so far; `error` the exception that ended the rollout early, if any."""

    results: dict[str, RolloutResult] = field(default_factory=dict)
    ended_after_s: dict[str, float] = field(default_factory=dict)  # seconds from the reset to each goal's end
    error: Exception | None = None


def run_shared_episode(
    env: TaskEnv,
    policy: Policy,
    context: TaskContext,
    goals: Mapping[str, Goal],
    *,
    watch: Mapping[str, Goal],
    change_steps: Sequence[int] = (),
) -> SharedRollout:
    """One rollout of an instruction-blind policy judged as the episode of every goal in `goals` (name ->
    task goal; every task set in `env`'s scene, with `env`'s step limit): the policy acts until each goal
    has held or the step limit is reached, and each goal's result is the one `run_episode` would return
    for it: cut at the step its own episode would end (its first success, or the limit), with its scene
    goals (`watch`), policy calls and wrong order as of that step.

    The policy must act the same whatever the episode's goal: its spec's `reads_instruction` is False and
    `context` is the one every goal's episode would give it (`TaskContext.for_policy` of each is equal), and
    every episode's instruction changes at `change_steps` (the policy is asked again there). Each result's
    `instructions` holds the steps of the instructions sent up to its end, with the context's first instruction
    and empty changes: what they changed to is each member's (the caller's). Exceptions are caught into
    `error`: the results decided before stay exact.
    """
    rollout = SharedRollout()
    started = time.perf_counter()
    try:
        _begin(env, policy, context, settle_steps=SETTLE_STEPS, sampled_start=False, on_start=None)
        # Every member's episode watches the same scene goals from the same states: one watch serves them all,
        # its `reached` read when each member ends. Each goal is judged as its own episode's task goal: success
        # from step 0, as `TaskEnv` judges its task, and its own order.
        scene = SceneWatch(env, watch)
        progress = {name: GoalProgress(goal) for name, goal in goals.items()}
        orders = {name: OrderWatch(env, goal) for name, goal in goals.items()}
        for judged in progress.values():
            judged.observe(0, env.predicate_holds)

        def decided(_success: bool, calls: int, sent: list[tuple[int, str]]) -> bool:
            scene.observe()
            for name in [n for n in goals if n not in rollout.results]:
                orders[name].observe()
                success = progress[name].observe(env.steps, env.predicate_holds)
                if success or env.truncated:
                    wrong = orders[name].wrong(success)
                    rollout.results[name] = _result(env, scene, success, calls, list(sent), wrong)
                    rollout.ended_after_s[name] = time.perf_counter() - started
            return len(rollout.results) == len(goals)

        # The policy never sees the instruction (`observation_for`): the text a change carries does not matter.
        _act(env, policy, context, decided, changes=[(step, "") for step in change_steps])
    except Exception as exc:  # the caller decides what an early end means for the goals still undecided
        rollout.error = exc
    return rollout
