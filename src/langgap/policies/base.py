"""The policy protocol: what a policy observes, how it chunks actions, and its two calls.

A policy declares a `PolicySpec` (cameras and image size, or none; whether it reads simulator state;
whether it is told the goal; action chunking), is `reset` with a `TaskContext` at the start of
every episode, and `act`s on an `Observation`, returning one action (7,) or a chunk (k, 7) of
OSC_POSE deltas + gripper in [-1, 1], k <= `chunk`. The evaluator executes the first `replan` actions
of a chunk before it asks again, and renders only the cameras the spec names, only when it asks.
Every policy sees the 8-D robot state (proprioception, as on a real robot; it names no task), and
every observation carries the instruction in force: it can change mid-episode (condition `switch:K`),
so a policy reads it from each observation (`current_instruction`), not once at reset.

The two privileges are separate. `sees_state`: observations carry the simulator state
(`langgap.sim.privileged_schema.PrivilegedState`: object poses, contacts, joints), which a learned
policy such as `small-bc` may read and still be a policy under test of whether it reads its
instruction. `sees_goal`: the context carries the answer (`PrivilegedContext`: task id, goal, the
source task's goal), which makes a policy a scripted reference (`oracle`, `blind`), never a policy under test.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, replace
from typing import Protocol, runtime_checkable

import numpy as np

from langgap.errors import LangGapError
from langgap.sim.env import ACTION_DIM, CAMERAS, Observation
from langgap.sim.privileged_schema import PrivilegedState


class PolicySpecError(ValueError):
    """A `PolicySpec` declares what LIBERO or the engine cannot give: an unknown camera, replan outside 1..chunk."""


@dataclass(frozen=True)
class PolicySpec:
    """What a policy observes and how it chunks actions.

    `sees_state`: observations carry the simulator state; `sees_goal`: the reset context carries the
    task id and the goal (see the module docstring). `chunk`: the most actions one `act` returns
    (returning more is a policy error); `replan`: how many of them are executed before the next `act`.
    `reads_instruction=False` declares an instruction-blind policy (`noop`, `random`, `blind`): it is
    told no instruction, no condition and, of the answer, only the source task's goal (`for_policy`),
    so every task of one scene that shares an init state, seed and source gets the same actions from
    it, and those tasks may share one rollout (`--share-rollouts`).
    `stochastic=True` declares a policy whose actions may differ between two runs of the same episode (same
    init state and seed), e.g. one that samples without reseeding per episode; by default a policy is taken
    to act the same given the episode's seed (`langgap check-policy` checks it), as re-runs and the replays
    that film `--video` clips assume.

    Args:
        cameras: The cameras rendered for the policy (`langgap.sim.env.CAMERAS`); none: no images.
        image_size: Their height and width in pixels.
        sees_state: Observations carry the simulator state.
        sees_goal: The reset context carries the task id and the goal: a scripted reference, never a policy
            under test.
        chunk: The most actions one `act` returns.
        replan: How many of them are executed before the next `act` (1..chunk).
        reads_instruction: False for an instruction-blind policy.
        stochastic: True for a policy whose actions may differ between two runs of the same episode.

    Raises:
        PolicySpecError: An unknown camera, or `replan` outside 1..`chunk`.
    """

    cameras: tuple[str, ...] = ()
    image_size: int = 256
    sees_state: bool = False
    sees_goal: bool = False
    chunk: int = 1
    replan: int = 1
    reads_instruction: bool = True
    stochastic: bool = False

    def __post_init__(self) -> None:
        unknown = [c for c in self.cameras if c not in CAMERAS]
        if unknown:
            raise PolicySpecError(f"unknown camera(s) {unknown}; LIBERO has {', '.join(CAMERAS)}")
        if not 1 <= self.replan <= self.chunk:
            raise PolicySpecError(f"need 1 <= replan <= chunk, got replan={self.replan}, chunk={self.chunk}")


@dataclass(frozen=True)
class PrivilegedContext:
    """What only a policy whose spec `sees_goal` (a scripted reference such as `oracle` or `blind`) is
    told: the answer. The task id names the goal, and the condition says whether the instruction is the task's
    own, so both are privileged too."""

    task_id: str
    condition: str
    goal: tuple[str, ...]  # atoms that satisfy the goal (`Task.bddl_goal`): the whole goal for LIBERO-style tasks
    source_goal: tuple[str, ...]
    goal_expression: str  # the goal itself (`langgap.goals`), with any Or, Not and order (Then)
    # (instruction, goal expression) for the instructions of this episode that ask for another task's goal
    # (a switch's first instruction): a reference that follows its instruction pursues that goal while it
    # is in force (`goal_for`), and the task's own under every other instruction.
    instruction_goals: tuple[tuple[str, str], ...] = ()

    def goal_for(self, instruction: str) -> str:
        """The goal expression `instruction` asks for in this episode."""
        return dict(self.instruction_goals).get(instruction, self.goal_expression)


@dataclass(frozen=True)
class TaskContext:
    """What a policy is told at reset.

    `instruction` is the exact string the policy receives first (and the one recorded); when it changes
    mid-episode, each `Observation.instruction` carries the one in force (`current_instruction`). The other public
    fields name no task: the suite, the init state and seed (which select a placement shared by every
    task of the scene) and the step limit. `privileged` is None for every policy whose spec does not
    declare `sees_goal`: the engine removes it before `reset` (`for_policy`), so a policy under test
    cannot read the goal, however it is written. There is deliberately no free-form field: every
    field a policy is told is one of these, so none can carry the answer past `for_policy`.

    Attributes:
        instruction: The instruction the episode starts with.
        suite: The task's LIBERO suite (`libero_spatial`, ...).
        init_index: The init state the episode starts from.
        seed: The episode's environment seed.
        max_steps: The episode's step limit.
        privileged: The answer, for a policy whose spec `sees_goal` (None for every other).
    """

    instruction: str
    suite: str
    init_index: int
    seed: int
    max_steps: int
    privileged: PrivilegedContext | None = None

    def for_policy(self, spec: PolicySpec) -> TaskContext:
        """The context a policy with `spec` may see; an instruction-blind one (`reads_instruction=False`) is
        told nothing that tells sibling tasks of one source apart, so it acts the same on all of them."""
        context = self if spec.sees_goal else replace(self, privileged=None)
        if spec.reads_instruction:
            return context
        privileged = context.privileged
        if privileged is not None:
            privileged = PrivilegedContext(
                task_id="", condition="", goal=(), source_goal=privileged.source_goal, goal_expression=""
            )
        return replace(context, instruction="", privileged=privileged)


def current_instruction(observation: Observation, context: TaskContext) -> str:
    """The instruction in force at `observation`: the observation's (it may change mid-episode), else the
    one the episode started with.

    Args:
        observation: The observation the policy acts on.
        context: The context the policy was reset with.

    Returns:
        The instruction in force.
    """
    return context.instruction if observation.instruction is None else observation.instruction


def observation_for(observation: Observation, spec: PolicySpec) -> Observation:
    """The observation a policy with `spec` may see: the simulator state only if it `sees_state`, the
    instruction only if it `reads_instruction`."""
    if not spec.reads_instruction:
        observation = replace(observation, instruction="")
    if spec.sees_state or observation.privileged is None:
        return observation
    return replace(observation, privileged=None)


class PrivilegeError(LangGapError):
    """A policy was not given what it needs: its spec does not declare it, or the caller withheld it."""


def simulator_state(observation: Observation, policy: str) -> PrivilegedState:
    """`observation`'s simulator state, for a policy named `policy` that cannot act without it."""
    if observation.privileged is None:
        raise PrivilegeError(f"{policy} needs the simulator state in its observations (PolicySpec.sees_state)")
    return observation.privileged


@runtime_checkable
class Policy(Protocol):
    """Implement `spec`, `reset` and `act`; `close` and `config` are optional (see `policy_config`). A `close`
    must be safe to call twice (the second call does nothing), as a file's is.

    Attributes:
        spec: What the policy observes and how it chunks actions.
    """

    spec: PolicySpec

    def reset(self, context: TaskContext) -> None:
        """Start an episode.

        Args:
            context: What the policy is told about the episode.
        """

    def act(self, observation: Observation) -> np.ndarray:
        """Choose the next action(s).

        Args:
            observation: What the environment shows at this step.

        Returns:
            One action (7,) or a chunk (k, 7), k <= `spec.chunk`, of OSC_POSE deltas and the gripper in [-1, 1].
        """


class PolicyOutputError(ValueError):
    """A policy returned something that is not a finite (7,) or (k, 7) action array; `remedy` says how to fix it."""

    def __init__(self, message: str, remedy: str = ""):
        super().__init__(message)
        self.remedy = remedy


def regressed_chunk(actions: np.ndarray) -> np.ndarray:
    """A regression model's (k, 7) output as actions: within [-1, 1], the gripper either open (-1) or closed (+1)."""
    actions = np.clip(np.asarray(actions, dtype=np.float64), -1.0, 1.0)
    actions[:, 6] = np.where(actions[:, 6] >= 0, 1.0, -1.0)
    return actions


def as_action_chunk(output, spec: PolicySpec) -> np.ndarray:
    """Validate a policy's output and return it as a (k, 7) float64 chunk, 1 <= k <= spec.chunk.

    A longer chunk is refused, not cut: a policy that returns more actions than it declared is
    misconfigured (its chunk or replan was meant otherwise), and executing a silently chosen prefix
    would evaluate a policy other than the one described by its stored spec.
    """
    if output is None:
        raise PolicyOutputError(
            "policy returned None, not an action",
            f"return the action from act: a NumPy array of shape ({ACTION_DIM},) or (k, {ACTION_DIM})",
        )
    try:
        actions = np.asarray(output, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise PolicyOutputError(
            f"policy returned a non-numeric action: {exc}", "return a NumPy float array (or nested lists of numbers)"
        ) from None
    if actions.ndim == 1:
        actions = actions[None, :]
    if actions.ndim != 2 or actions.shape[1] != ACTION_DIM or actions.shape[0] < 1:
        raise PolicyOutputError(
            f"policy returned shape {tuple(np.shape(output))}; expected ({ACTION_DIM},) or (k, {ACTION_DIM})",
            f"return one action of {ACTION_DIM} numbers (3 position deltas, 3 rotation deltas, the gripper) "
            f"as ({ACTION_DIM},), or a chunk of them as (k, {ACTION_DIM})",
        )
    if actions.shape[0] > spec.chunk:
        raise PolicyOutputError(
            f"policy returned a chunk of {actions.shape[0]} actions; its spec declares chunk={spec.chunk}",
            f"return at most {spec.chunk} actions per call, or declare PolicySpec(chunk={actions.shape[0]}) "
            "with the replan you mean",
        )
    if not np.all(np.isfinite(actions)):
        raise PolicyOutputError(
            "policy returned a non-finite action (NaN or inf)",
            "find where the model makes NaN or inf (a division by a zero std when unnormalising, diverged weights, "
            "an uninitialised buffer)",
        )
    return actions


# Spec fields that say how the engine may run a policy (share rollouts, replay an episode), not how it acts: a
# truthful declaration changes no action, so they are left out of `policy_config` and stored runs keep their hash.
ENGINE_DECLARATIONS = ("reads_instruction", "stochastic")


def policy_config(policy) -> dict:
    """A JSON-able description of a policy's configuration (its `config()` if it has one, plus its spec)."""
    config = policy.config() if hasattr(policy, "config") else {}
    spec = {k: v for k, v in asdict(policy.spec).items() if k not in ENGINE_DECLARATIONS}
    return {"class": f"{type(policy).__module__}.{type(policy).__qualname__}", "spec": spec, **config}


def config_hash(config: dict) -> str:
    """A short stable hash of a configuration dict."""
    blob = json.dumps(config, sort_keys=True, default=str).encode()
    return hashlib.sha256(blob).hexdigest()[:16]
