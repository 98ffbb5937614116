"""Serving a LangGap policy over openpi's websocket protocol, with LangGap's extension (`langgap.policies.protocol`).

`ServedPolicy` adapts one LangGap policy to openpi's server-side policy interface (`infer(obs) ->
{"actions": ...}` plus `metadata`), so it can also be hosted by openpi's own `WebsocketPolicyServer`.
`serve()` is LangGap's server: each connection gets its own policy instance (built on demand, reused
by later connections), so concurrent clients never share a policy's episode state.
"""

from __future__ import annotations

import http
import logging
import sys
import threading
import time
import traceback
from collections.abc import Callable

import numpy as np
import websockets
from websockets.sync.server import Request, Response, ServerConnection
from websockets.sync.server import serve as websocket_serve

from langgap.errors import PolicyServerError
from langgap.policies import make_policy, protocol
from langgap.policies.base import Policy, policy_config
from langgap.sim.env import Observation

log = logging.getLogger("langgap.serve")


class ServedPolicy:
    """One LangGap policy behind openpi's server-side interface; resets it when the episode changes."""

    def __init__(self, policy: Policy, name: str):
        self.policy = policy
        self.name = name
        self.metadata = protocol.server_metadata(name, policy.spec, policy_config(policy))
        self._episode: str | None = None

    def infer(self, request: dict) -> dict:
        """Answer one request with `{"actions": float64 array}`; `ProtocolError` if it lacks what is needed.

        The policy's output is passed on unjudged (a NaN or a wrong shape is the client's rollout to
        classify as a policy failure, as in process); only non-numeric output fails here.
        """
        if not isinstance(request, dict):
            raise protocol.ProtocolError(f"a request must be a map, got {type(request).__name__}")
        episode = request.get(protocol.EPISODE_KEY)
        if not isinstance(episode, str):
            raise protocol.ProtocolError(
                f"request has no {protocol.EPISODE_KEY}: a LangGap server needs LangGap's `openpi` client"
            )
        if episode != self._episode:
            # Whatever a client sends, a policy that does not declare `sees_goal` never sees the goal.
            context = protocol.context_from_message(request.get(protocol.CONTEXT_KEY))
            self.policy.reset(context.for_policy(self.policy.spec))
            self._episode = episode
        spec = self.policy.spec
        try:
            state = np.asarray(request[protocol.STATE_KEY], dtype=np.float32)
            images = {camera: request[protocol.CAMERA_KEYS[camera]] for camera in spec.cameras}
            # Nor the simulator state, unless it declares `sees_state` (then it must be whole: the schema).
            privileged = protocol.privileged_from_message(request[protocol.PRIVILEGED_KEY]) if spec.sees_state else None
        except KeyError as exc:
            raise protocol.ProtocolError(f"request lacks {exc.args[0]!r}, which this policy's spec needs") from None
        prompt = request.get(protocol.PROMPT_KEY)  # the instruction in force: it can change mid-episode
        instruction = prompt if isinstance(prompt, str) else None
        observation = Observation(state=state, images=images, privileged=privileged, instruction=instruction)
        return {protocol.ACTIONS_KEY: np.asarray(self.policy.act(observation), dtype=np.float64)}

    def reset(self) -> None:
        """openpi's interface: the next request starts from a fresh episode."""
        self._episode = None

    def close(self) -> None:
        if hasattr(self.policy, "close"):
            self.policy.close()


class PolicyPool:
    """Idle `ServedPolicy` instances of one policy; a connection takes one and gives it back."""

    def __init__(self, factory: Callable[[], ServedPolicy]):
        self._factory = factory
        self._lock = threading.Lock()
        self._idle = [factory()]  # built now: bad arguments fail at startup, and the metadata is known
        self.metadata = self._idle[0].metadata

    def take(self) -> ServedPolicy:
        with self._lock:
            if self._idle:
                return self._idle.pop()
        return self._factory()

    def give_back(self, served: ServedPolicy) -> None:
        served.reset()
        with self._lock:
            self._idle.append(served)

    def close(self) -> None:
        with self._lock:
            for served in self._idle:
                served.close()
            self._idle.clear()


def health_check(connection: ServerConnection, request: Request) -> Response | None:
    """openpi's health route: `GET /healthz` answers 200; every other request proceeds to the websocket."""
    if request.path == protocol.HEALTH_PATH:
        return connection.respond(http.HTTPStatus.OK, "OK\n")
    return None


def _handler(pool: PolicyPool) -> Callable[[ServerConnection], None]:
    def handle(connection: ServerConnection) -> None:
        served = pool.take()
        try:
            connection.send(protocol.pack(served.metadata))
            while True:
                frame = connection.recv()
                started = time.monotonic()
                try:
                    if isinstance(frame, str):
                        raise protocol.ProtocolError("requests must be binary msgpack frames")
                    reply = served.infer(protocol.unpack(frame))
                except Exception:
                    # openpi's convention: the traceback as a text frame, then close as an internal error.
                    log.error("policy %s failed:\n%s", served.name, traceback.format_exc())
                    connection.send(traceback.format_exc())
                    connection.close(websockets.frames.CloseCode.INTERNAL_ERROR, "policy error; traceback sent")
                    return
                reply["server_timing"] = {"infer_ms": (time.monotonic() - started) * 1000}
                connection.send(protocol.pack(reply))
        except websockets.ConnectionClosed:
            pass
        finally:
            pool.give_back(served)

    return handle


def serve(name: str, args: dict[str, str], host: str = "127.0.0.1", port: int = 8000) -> None:
    """Serve policy `name` (built with `args`) on ws://host:port until interrupted."""
    pool = PolicyPool(lambda: ServedPolicy(make_policy(name, args), name))
    try:
        server = websocket_serve(
            _handler(pool), host, port, compression=None, max_size=None, process_request=health_check
        )
    except OSError as exc:
        pool.close()
        raise PolicyServerError(f"cannot listen on {host}:{port}: {exc.strerror or exc}") from None
    try:
        with server:
            print(f"langgap serve: {name} on ws://{host}:{port} (spec {pool.metadata['langgap']['spec']})", flush=True)
            server.serve_forever()
    finally:
        pool.close()
        print("langgap serve: stopped", file=sys.stderr, flush=True)
