"""Misbehaving policies for the harness's tests (loaded by workers as `tests.support.policies:Name`)."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import time
from pathlib import Path

import numpy as np

from langgap.policies.base import PolicySpec, current_instruction
from langgap.policies.oracle import OraclePolicy
from langgap.policies.oracle.policy import BlindPolicy
from langgap.policies.simple import NoopPolicy, RandomPolicy
from langgap.sim.privileged_schema import PrivilegedState


class RaisingPolicy(NoopPolicy):
    def act(self, observation):
        raise RuntimeError("model exploded")


class NanPolicy(NoopPolicy):
    def act(self, observation):
        return np.full(7, np.nan)


class WrongShapePolicy(NoopPolicy):
    def act(self, observation):
        return np.zeros(6)


class HangingPolicy(NoopPolicy):
    def act(self, observation):
        time.sleep(3600)


class FlakyPolicy(NoopPolicy):
    """Fails the first time each episode is attempted (state kept in files, so it spans worker processes)."""

    spec = PolicySpec()  # it reads its instruction (the episode's marker is named by it)

    def __init__(self, marker_dir: str = ""):
        self.marker_dir = Path(marker_dir)
        self.key = ""

    def reset(self, context):
        self.key = f"{hashlib.sha256(context.instruction.encode()).hexdigest()[:12]}-{context.init_index}"

    def act(self, observation):
        marker = self.marker_dir / self.key
        if not marker.exists():
            marker.write_text(str(os.getpid()))
            raise ConnectionError("server went away")
        return super().act(observation)


class CrashingPolicy(NoopPolicy):
    """Kills its own worker process in the middle of an episode, every time."""

    def act(self, observation):
        os._exit(17)


class CrashOncePolicy(NoopPolicy):
    """Kills the process it acts in at its first query ever (a marker file in `marker_dir` remembers it):
    shared, it takes the policy process down once."""

    def __init__(self, marker_dir: str = ""):
        self.marker = Path(marker_dir) / "crashed"

    def act(self, observation):
        if not self.marker.exists():
            self.marker.write_text(str(os.getpid()))
            os._exit(17)
        return super().act(observation)


class UnbuildablePolicy(NoopPolicy):
    """Cannot be built (as a policy whose checkpoint is missing)."""

    def __init__(self):
        raise FileNotFoundError("no checkpoint at /nowhere")


class DyingOnBuildPolicy(NoopPolicy):
    """Kills the process that builds it (as a policy whose native library aborts on load)."""

    def __init__(self):
        os._exit(17)


class BatchRecorder(RandomPolicy):
    """`random`, with a batched form that appends each batch's size to `path` (one line per batched call)."""

    def __init__(self, path: str = "", chunk: int = 1):
        super().__init__(chunk=chunk)
        self.path = Path(path)

    @staticmethod
    def act_batch(policies: list[BatchRecorder], observations: list) -> list[np.ndarray]:
        with policies[0].path.open("a") as handle:
            handle.write(f"{len(policies)}\n")
        return [p.act(o) for p, o in zip(policies, observations, strict=True)]


class ChunkPolicy:
    """Returns a 4-action chunk each call; executes 2 (replan) — to check chunking bookkeeping."""

    spec = PolicySpec(chunk=4, replan=2)

    def reset(self, context):
        self.calls = 0

    def act(self, observation):
        self.calls += 1
        return np.tile([0, 0, 0, 0, 0, 0, -1.0], (4, 1))


class ContextRecorder(NoopPolicy):
    """Holds still; appends to `path` what it was told at reset (the context's fields) and whether its
    first observation carried simulator state (`simulator_state`: the schema's type, with an end-effector
    position): one JSON line per episode. It declares neither privilege, and reads its instruction."""

    spec = PolicySpec()

    def __init__(self, path: str = ""):
        self.path = Path(path)
        self._told: dict | None = None

    def reset(self, context):
        self._told = dataclasses.asdict(context)

    def act(self, observation):
        if self._told is not None:
            with self.path.open("a") as handle:
                state = observation.privileged
                shown = isinstance(state, PrivilegedState) and state["eef_pos"].shape == (3,)
                handle.write(json.dumps({**self._told, "simulator_state": shown}) + "\n")
            self._told = None
        return super().act(observation)


class PrivilegedContextRecorder(ContextRecorder):
    """The same, declaring both privileges (as the scripted references do)."""

    spec = PolicySpec(sees_state=True, sees_goal=True)


class StateContextRecorder(ContextRecorder):
    """The same, declaring only `sees_state` (as `small-bc` does)."""

    spec = PolicySpec(sees_state=True)


class GoalContextRecorder(ContextRecorder):
    """The same, declaring only `sees_goal`."""

    spec = PolicySpec(sees_goal=True)


def robot_only_state() -> PrivilegedState:
    """The smallest valid simulator state: the robot's keys, a scene without entities."""
    return PrivilegedState(
        {"eef_pos": np.zeros(3), "eef_mat": np.eye(3), "gripper_qpos": np.zeros(2), "base_pos": np.zeros(3)}
    )


# Each recorder -> what its spec declares: (sees_state, sees_goal).
RECORDERS = {
    "ContextRecorder": (False, False),
    "StateContextRecorder": (True, False),
    "GoalContextRecorder": (False, True),
    "PrivilegedContextRecorder": (True, True),
}


class LongChunkPolicy(NoopPolicy):
    """Declares chunk 2 and returns 3 actions: misconfigured (refused as a policy error, never cut)."""

    spec = PolicySpec(chunk=2, replan=2)

    def act(self, observation):
        return np.tile(super().act(observation), (3, 1))


class ErrsOnInitsPolicy(NoopPolicy):
    """Holds still, but sends a malformed action at its 5th call on the init states in `inits` (outcome
    `policy_error`); with `once_dir`, only the first time each episode runs (state kept in files)."""

    def __init__(self, inits: str = "", once_dir: str = ""):
        self.inits = {int(i) for i in inits.split(",") if i}
        self.once_dir = Path(once_dir) if once_dir else None
        self.erring = False

    def reset(self, context):
        self.calls = 0
        self.erring = context.init_index in self.inits
        if self.erring and self.once_dir is not None:
            marker = self.once_dir / f"{context.init_index}-{context.seed}"
            self.erring = not marker.exists()
            marker.touch()

    def act(self, observation):
        self.calls += 1
        return np.full(7, np.nan) if self.erring and self.calls == 5 else super().act(observation)


class BlindFailingAt(BlindPolicy):
    """`blind`, but its call `at` raises (an infrastructure failure, not a malformed action)."""

    def __init__(self, at: int = 80):
        super().__init__()
        self.at = at

    def reset(self, context):
        super().reset(context)
        self.calls = 0

    def act(self, observation):
        self.calls += 1
        if self.calls == self.at:
            raise ConnectionError("the model server went away")
        return super().act(observation)


class OrderBlindOracle(OraclePolicy):
    """The oracle given only the goal's atoms (its witness), not their order: it reaches every part of an
    ordered goal in its own habitual order (fixtures first), as a policy that skips "first ... then" would."""

    def goal_of(self, context, instruction):
        return context.goal


class InstructionLogPolicy(NoopPolicy):
    """Holds still and appends the instruction in force at each query to a file of its own per episode in
    `log_dir`, so a test sees what reached the policy in whichever process it ran (worker, server)."""

    spec = PolicySpec()  # it reads its instruction

    def __init__(self, log_dir: str = ""):
        self.log_dir = Path(log_dir)

    def reset(self, context):
        self._context = context
        self._log = self.log_dir / f"{os.getpid()}-{time.monotonic_ns()}.txt"

    def act(self, observation):
        with self._log.open("a") as log:
            log.write(current_instruction(observation, self._context) + "\n")
        return super().act(observation)


class SentInstructionRecorder(NoopPolicy):
    """Holds still and appends one JSON line to `path` at each query: the episode's key (read from the goal it
    declares it sees), the instruction its context gave at reset and the one in force (`current_instruction`),
    so a test compares what reached the policy with what the run stored."""

    spec = PolicySpec(sees_goal=True)  # reads its instruction; the goal names the episode's task and condition

    def __init__(self, path: str = ""):
        self.path = Path(path)

    def reset(self, context):
        self._context = context

    def act(self, observation):
        context = self._context
        key = [context.privileged.task_id, context.init_index, context.seed, context.privileged.condition]
        line = {"key": key, "reset": context.instruction, "sent": current_instruction(observation, context)}
        with self.path.open("a") as handle:
            handle.write(json.dumps(line) + "\n")
        return super().act(observation)


class Reach:
    """Looks through both cameras every `replan` steps and plays a fixed reach; keeps what it was shown."""

    def __init__(self, replan: int, steps: int, image_size: int = 96):
        self.spec = PolicySpec(
            cameras=("agentview", "robot0_eye_in_hand"), image_size=image_size, chunk=replan, replan=replan
        )
        rng = np.random.default_rng(0)
        self.actions = np.concatenate([rng.uniform(-0.6, 0.6, (steps, 6)), -np.ones((steps, 1))], axis=1)
        self.shown: list[dict[str, np.ndarray]] = []

    def reset(self, context) -> None:
        self.shown.clear()

    def act(self, observation):
        start = len(self.shown) * self.spec.replan
        self.shown.append(observation.images)
        return self.actions[start : start + self.spec.chunk]


class OutOfRangePolicy(NoopPolicy):
    """Moves 2.5 along x: past the action bounds, so robosuite clips it (an action not unnormalised)."""

    def act(self, observation):
        return np.array([2.5, 0, 0, 0, 0, 0, -1.0])


class UnseededRandomPolicy(RandomPolicy):
    """`random` that never reseeds at reset: another episode on the same seed gets other actions, and it does not
    declare itself stochastic."""

    def reset(self, context):
        pass


class DeclaredStochasticPolicy(UnseededRandomPolicy):
    """The same, declaring it (`PolicySpec.stochastic`)."""

    def __init__(self):
        super().__init__()
        self.spec = dataclasses.replace(self.spec, stochastic=True)


class ClosesOncePolicy(NoopPolicy):
    """Holds still; its `close` raises the second time."""

    def __init__(self):
        self.closed = False

    def close(self):
        if self.closed:
            raise RuntimeError("already closed")
        self.closed = True


class SpeclessPolicy:
    """Acts, but declares no spec."""

    def reset(self, context):
        pass

    def act(self, observation):
        return np.zeros(7)


class UnknownCameraPolicy(NoopPolicy):
    """Asks for a camera LIBERO does not have (its spec cannot be made)."""

    def __init__(self):
        self.spec = PolicySpec(cameras=("frontview",))


class HugeImagePolicy(NoopPolicy):
    """Asks for images larger than the renderer makes."""

    spec = PolicySpec(cameras=("agentview",), image_size=2048)


class LateNanPolicy(NoopPolicy):
    """Holds still for its first 9 calls, then returns NaN: fine on a short episode, a policy error late in one."""

    def reset(self, context):
        self.calls = 0

    def act(self, observation):
        self.calls += 1
        return np.full(7, np.nan) if self.calls >= 10 else super().act(observation)


class NonePolicy(NoopPolicy):
    """Forgets to return its action."""

    def act(self, observation):
        return None


class IntegerPolicy(NoopPolicy):
    """Returns integer actions (a discrete policy's)."""

    def act(self, observation):
        return np.array([0, 0, 0, 0, 0, 0, -1], dtype=np.int64)


class UnreadCamerasPolicy(NoopPolicy):
    """Declares both cameras, small, and never looks at them."""

    spec = PolicySpec(cameras=("agentview", "robot0_eye_in_hand"), image_size=32, reads_instruction=False)


class UndeclaredCameraPolicy(NoopPolicy):
    """Declares the agentview camera and reads the wrist camera."""

    spec = PolicySpec(cameras=("agentview",), image_size=32, reads_instruction=False)

    def act(self, observation):
        observation.images["robot0_eye_in_hand"]
        return super().act(observation)
