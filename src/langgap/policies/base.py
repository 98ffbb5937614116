"""The policy protocol: what a policy observes, how it chunks actions, and its two calls.

A policy declares a `PolicySpec` (cameras and image size, or none; proprioceptive state;
privileged simulator state; action chunking), is `reset` with a `TaskContext` at the start of
every episode, and `act`s on an `Observation`, returning one action (7,) or a chunk (k, 7) of
OSC_POSE deltas + gripper in [-1, 1]. The evaluator executes the first `replan` actions of a chunk
before it asks again, and renders only the cameras the spec names, only when it asks.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, replace
from typing import Protocol, runtime_checkable

import numpy as np

from langgap.sim.env import ACTION_DIM, CAMERAS, Observation


@dataclass(frozen=True)
class PolicySpec:
    """What a policy observes and how it chunks actions."""

    cameras: tuple[str, ...] = ()
    image_size: int = 256
    state: bool = True
    privileged: bool = False
    chunk: int = 1
    replan: int = 1

    def __post_init__(self) -> None:
        unknown = [c for c in self.cameras if c not in CAMERAS]
        if unknown:
            raise ValueError(f"unknown camera(s) {unknown}; LIBERO has {', '.join(CAMERAS)}")
        if not 1 <= self.replan <= self.chunk:
            raise ValueError(f"need 1 <= replan <= chunk, got replan={self.replan}, chunk={self.chunk}")


@dataclass(frozen=True)
class PrivilegedContext:
    """What only a privileged policy (a scripted reference such as `oracle` or `blind`) is told: the
    answer. The task id names the goal, and the condition says whether the instruction is the task's
    own, so both are privileged too."""

    task_id: str
    condition: str
    goal: tuple[str, ...]  # atoms that satisfy the goal (`Task.bddl_goal`): the whole goal for LIBERO-style tasks
    source_goal: tuple[str, ...]
    goal_expression: str  # the goal itself (`langgap.goals`), with any Or, Not and order (Then)


@dataclass(frozen=True)
class TaskContext:
    """What a policy is told at reset.

    `instruction` is the exact string the policy receives (and the one recorded). The other public
    fields name no task: the suite, the init state and seed (which select a placement shared by every
    task of the scene) and the step limit. `privileged` is None for every policy whose spec does not
    declare `privileged`: the engine removes it before `reset` (`for_policy`), so a policy under test
    cannot read the goal, however it is written. There is deliberately no free-form field: every
    field a policy is told is one of these, so none can carry the answer past `for_policy`.
    """

    instruction: str
    suite: str
    init_index: int
    seed: int
    max_steps: int
    privileged: PrivilegedContext | None = None

    def for_policy(self, spec: PolicySpec) -> TaskContext:
        """The context a policy with `spec` may see."""
        return self if spec.privileged else replace(self, privileged=None)


@runtime_checkable
class Policy(Protocol):
    """Implement `spec`, `reset` and `act`; `close` and `config` are optional (see `policy_config`)."""

    spec: PolicySpec

    def reset(self, context: TaskContext) -> None: ...

    def act(self, observation: Observation) -> np.ndarray: ...


class PolicyOutputError(ValueError):
    """A policy returned something that is not a finite (7,) or (k, 7) action array."""


def as_action_chunk(output, spec: PolicySpec) -> np.ndarray:
    """Validate a policy's output and return it as a (k, 7) float64 chunk, k <= spec.chunk."""
    try:
        actions = np.asarray(output, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise PolicyOutputError(f"policy returned a non-numeric action: {exc}") from None
    if actions.ndim == 1:
        actions = actions[None, :]
    if actions.ndim != 2 or actions.shape[1] != ACTION_DIM or actions.shape[0] < 1:
        raise PolicyOutputError(
            f"policy returned shape {tuple(np.shape(output))}; expected ({ACTION_DIM},) or (k, {ACTION_DIM})"
        )
    if not np.all(np.isfinite(actions)):
        raise PolicyOutputError("policy returned a non-finite action (NaN or inf)")
    return actions


def policy_config(policy) -> dict:
    """A JSON-able description of a policy's configuration (its `config()` if it has one, plus its spec)."""
    config = policy.config() if hasattr(policy, "config") else {}
    return {"class": f"{type(policy).__module__}.{type(policy).__qualname__}", "spec": asdict(policy.spec), **config}


def config_hash(config: dict) -> str:
    """A short stable hash of a configuration dict."""
    blob = json.dumps(config, sort_keys=True, default=str).encode()
    return hashlib.sha256(blob).hexdigest()[:16]
