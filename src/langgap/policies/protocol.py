"""The openpi policy-server protocol, and LangGap's small extension of it.

openpi's protocol (its `WebsocketPolicyServer` / `WebsocketClientPolicy`):

* A websocket server; `GET /healthz` answers 200 once it is up.
* On connect the server sends its metadata: one binary msgpack frame holding a map.
* Then each request is one binary frame (an observation map) answered by one binary frame (a map
  with `actions`, an array (k, 7)). A text frame is an error report (a traceback), after which the
  server closes the connection.
* NumPy arrays travel as maps `{b"__ndarray__": True, b"data": raw bytes, b"dtype": "<f4", b"shape": [...]}`,
  NumPy scalars as `{b"__npgeneric__": True, b"data": value, b"dtype": ...}`.
* LIBERO observation keys: `observation/image` (agentview), `observation/wrist_image`,
  `observation/state` (8-D) and `prompt`.

LangGap's extension, used only when the server's metadata has a `langgap` entry (a plain openpi
server never sees it):

* metadata `langgap` = `{"protocol": 2, "policy": <name>, "spec": <PolicySpec fields>, "config": ...}`:
  the client then renders exactly the served spec's cameras at its image size (no resizing) and
  executes `spec.replan` actions of each chunk, so the served policy sees what it would see in process.
* every request adds `langgap/episode` (a string that changes at each new episode; the server
  resets its policy when it changes) and `langgap/context` (the `TaskContext` fields; its
  `privileged` part, with the task id and the goal, is null unless the served spec `sees_goal`);
  `langgap/privileged` (the simulator state: a flat map of arrays following
  `langgap.sim.privileged_schema`) is added only when the spec `sees_state`. The server enforces the
  same rules on what it receives, whatever the client sends, and refuses a simulator state that does
  not follow the schema.

Protocol 2 split protocol 1's one `privileged` flag of the spec into `sees_state` and `sees_goal`
(and dropped `state`); the two versions do not talk to each other.
"""

from __future__ import annotations

import dataclasses
import json
from typing import Any

import msgpack
import numpy as np

from langgap.policies.base import PolicySpec, PrivilegedContext, TaskContext
from langgap.sim.privileged_schema import PrivilegedState, PrivilegedStateError

PROTOCOL_VERSION = 2
HEALTH_PATH = "/healthz"
METADATA_KEY = "langgap"
EPISODE_KEY = "langgap/episode"
CONTEXT_KEY = "langgap/context"
PRIVILEGED_KEY = "langgap/privileged"
STATE_KEY = "observation/state"
PROMPT_KEY = "prompt"
ACTIONS_KEY = "actions"
# LangGap camera name -> openpi LIBERO observation key.
CAMERA_KEYS = {"agentview": "observation/image", "robot0_eye_in_hand": "observation/wrist_image"}


class ProtocolError(ValueError):
    """A message does not follow the protocol."""


def _encode_numpy(obj: Any) -> Any:
    if isinstance(obj, np.ndarray | np.generic) and obj.dtype.kind in ("V", "O", "c"):
        raise TypeError(f"cannot send a NumPy array of dtype {obj.dtype}")
    if isinstance(obj, np.ndarray):
        return {b"__ndarray__": True, b"data": obj.tobytes(), b"dtype": obj.dtype.str, b"shape": list(obj.shape)}
    if isinstance(obj, np.generic):
        return {b"__npgeneric__": True, b"data": obj.item(), b"dtype": obj.dtype.str}
    raise TypeError(f"cannot send an object of type {type(obj).__name__}")


def _decode_numpy(obj: dict) -> Any:
    if b"__ndarray__" in obj:
        # A copy, so receivers get an ordinary writable array, as in process.
        return np.frombuffer(obj[b"data"], dtype=np.dtype(obj[b"dtype"])).reshape(obj[b"shape"]).copy()
    if b"__npgeneric__" in obj:
        return np.dtype(obj[b"dtype"]).type(obj[b"data"])
    return obj


def pack(message: Any) -> bytes:
    """Serialize a message (maps, lists, scalars, strings, NumPy arrays) to one binary frame."""
    return msgpack.packb(message, default=_encode_numpy)


def unpack(frame: bytes) -> Any:
    """Parse one binary frame; raises `ProtocolError` if it is not valid msgpack."""
    try:
        return msgpack.unpackb(frame, object_hook=_decode_numpy)
    except (ValueError, TypeError, msgpack.UnpackException) as exc:
        raise ProtocolError(f"not a msgpack message ({type(exc).__name__}: {exc})") from None


def jsonable(value: Any) -> Any:
    """`value` as plain JSON data: arrays become lists, bytes hex, anything else unknown its `str`."""

    def fallback(item: Any) -> Any:
        if isinstance(item, np.ndarray | np.generic):
            return item.tolist()
        return item.hex() if isinstance(item, bytes) else str(item)

    return json.loads(json.dumps(value, default=fallback))


def server_metadata(name: str, spec: PolicySpec, config: dict) -> dict:
    """The metadata a LangGap server announces for a policy named `name` (`config` as in `policy_config`)."""
    entry = {"protocol": PROTOCOL_VERSION, "policy": name, "spec": dataclasses.asdict(spec), "config": config}
    return {METADATA_KEY: jsonable(entry)}


def served_spec(metadata: Any) -> PolicySpec | None:
    """The served policy's spec if `metadata` announces the LangGap extension, else None (plain openpi)."""
    entry = metadata.get(METADATA_KEY) if isinstance(metadata, dict) else None
    if entry is None:
        return None
    if not isinstance(entry, dict) or entry.get("protocol") != PROTOCOL_VERSION:
        raise ProtocolError(f"unsupported LangGap protocol in server metadata: {entry!r:.200}")
    try:
        spec = dict(entry["spec"])
        return PolicySpec(**{**spec, "cameras": tuple(spec["cameras"])})
    except (KeyError, TypeError, ValueError) as exc:
        raise ProtocolError(f"malformed policy spec in server metadata: {exc}") from None


def context_to_message(context: TaskContext) -> dict:
    """A `TaskContext` as a msgpack-able map."""
    return dataclasses.asdict(context)


def context_from_message(message: Any) -> TaskContext:
    """The `TaskContext` sent by `context_to_message`."""
    if not isinstance(message, dict):
        raise ProtocolError(f"{CONTEXT_KEY} must be a map, got {type(message).__name__}")
    try:
        privileged = message.get("privileged")
        if privileged is not None:
            goals = {
                "goal": tuple(privileged["goal"]),
                "source_goal": tuple(privileged["source_goal"]),
                "instruction_goals": tuple(tuple(pair) for pair in privileged.get("instruction_goals", ())),
            }
            privileged = PrivilegedContext(**{**privileged, **goals})
        return TaskContext(**{**message, "privileged": privileged})
    except (KeyError, TypeError) as exc:
        raise ProtocolError(f"malformed {CONTEXT_KEY}: {exc}") from None


def privileged_to_message(state: PrivilegedState | None) -> dict | None:
    """The simulator state as a msgpack-able map (its arrays)."""
    return None if state is None else dict(state.arrays)


def privileged_from_message(message: Any) -> PrivilegedState:
    """The `PrivilegedState` sent by `privileged_to_message`; `ProtocolError` if it breaks the schema."""
    if not isinstance(message, dict):
        raise ProtocolError(f"{PRIVILEGED_KEY} must be a map, got {type(message).__name__}")
    try:
        return PrivilegedState(message)
    except PrivilegedStateError as exc:
        raise ProtocolError(f"{PRIVILEGED_KEY}: {exc}") from None


def actions_from_reply(reply: Any) -> np.ndarray:
    """The action chunk of a reply as a float64 (k, n) array; `ProtocolError` if the reply has none.

    Only the message is checked here. What the values are (7 per action, finite) is the policy's
    business, checked by the rollout as for a policy in process, so a NaN is a policy failure either way.
    """
    if not isinstance(reply, dict) or ACTIONS_KEY not in reply:
        keys = sorted(map(str, reply)) if isinstance(reply, dict) else type(reply).__name__
        raise ProtocolError(f"reply has no '{ACTIONS_KEY}' (got {keys})")
    actions = reply[ACTIONS_KEY]
    if not isinstance(actions, np.ndarray) or actions.dtype.kind not in "fiub" or actions.ndim not in (1, 2):
        described = f"shape {actions.shape}" if isinstance(actions, np.ndarray) else type(actions).__name__
        raise ProtocolError(f"'{ACTIONS_KEY}' is not a 1-D or 2-D numeric array (got {described})")
    return np.atleast_2d(actions).astype(np.float64)
