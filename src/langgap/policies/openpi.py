"""`openpi`: a policy served over openpi's websocket protocol (π0, π0-FAST, π0.5 via `serve_policy.py`,
or any LangGap policy via `langgap serve`).

Against a plain openpi server it sends exactly what openpi's LIBERO example sends: both cameras
rendered at 256x256, upright (LIBERO's raw render rotated 180 degrees, which `TaskEnv` images
already are), resized with padding to 224x224; the 8-D state; the instruction as `prompt`. It
executes the first `replan_steps` actions of each chunk. Against a LangGap server (see
`langgap.policies.protocol`) it follows the served policy's spec instead and sends the episode context.

Every failure (no server within `connect_timeout`, no reply within `timeout`, a closed connection,
an error report or a malformed reply) raises `PolicyServerError` with a one-line message. After a
failure the connection is dropped; the next `reset` reconnects.
"""

from __future__ import annotations

import http.client
import itertools
import secrets
import sys
import time

import numpy as np
import websockets
from websockets.sync.client import ClientConnection, connect

from langgap.errors import PolicyServerError
from langgap.imaging import resize_with_pad
from langgap.policies import protocol
from langgap.policies.base import PolicySpec, TaskContext, current_instruction
from langgap.sim.env import CAMERAS, Observation

# openpi's LIBERO example renders at 256 (the training data's resolution) and sends 224.
RENDER_SIZE = 256
WAIT_NOTE_S = 2.0  # a server that has not answered by then is waited for out loud
WAIT_NOTE_EVERY_S = 30.0


def wait_for_health(host: str, port: int, deadline: float) -> None:
    """Poll `GET /healthz` until the server answers over HTTP or the monotonic `deadline` passes.

    Any HTTP answer counts: a server without a health route still proves it is listening. A wait longer than
    `WAIT_NOTE_S` says so on stderr, and again every `WAIT_NOTE_EVERY_S`, so a run whose progress bar stands at
    0 is seen waiting for its server (a server loading a model takes minutes), with the time left.
    """
    last = "no answer"
    start = time.monotonic()
    next_note = start + WAIT_NOTE_S
    while True:
        now = time.monotonic()
        remaining = deadline - now
        if remaining <= 0:
            raise PolicyServerError(f"no policy server at {host}:{port}: {protocol.HEALTH_PATH} failed ({last})")
        if now >= next_note:
            print(
                f"note: waiting for the policy server at {host}:{port} ({now - start:.0f} s so far; "
                f"giving up in {remaining:.0f} s; {protocol.HEALTH_PATH}: {last})",
                file=sys.stderr,
                flush=True,
            )
            next_note = now + WAIT_NOTE_EVERY_S
        connection = http.client.HTTPConnection(host, port, timeout=min(remaining, 5.0))
        try:
            connection.request("GET", protocol.HEALTH_PATH)
            connection.getresponse().read()
            return
        except (OSError, http.client.HTTPException) as exc:
            last = f"{type(exc).__name__}: {exc}"
        finally:
            connection.close()
        time.sleep(min(0.2, max(0.0, deadline - time.monotonic())))


class ServerConnection:
    """One websocket to a policy server: bounded connect, one request/reply at a time with a timeout."""

    def __init__(self, host: str, port: int, connect_timeout: float, timeout: float):
        self.address = f"ws://{host}:{port}"
        self.host, self.port = host, port
        self.connect_timeout = connect_timeout
        self.timeout = timeout
        self._ws: ClientConnection | None = None

    @property
    def is_open(self) -> bool:
        return self._ws is not None

    def open(self) -> dict:
        """Connect (waiting up to `connect_timeout` for the server) and return its metadata."""
        self.close()
        deadline = time.monotonic() + self.connect_timeout
        wait_for_health(self.host, self.port, deadline)
        try:
            self._ws = connect(
                self.address,
                open_timeout=max(0.1, deadline - time.monotonic()),
                compression=None,
                max_size=None,
                proxy=None,
                # Liveness is the per-call timeout's job; pings would also fail during a long inference.
                ping_interval=None,
                close_timeout=1,
                legacy=True,  # a plain connection, not websockets' reconnecting iterator
            )
        except (OSError, TimeoutError, websockets.WebSocketException) as exc:
            raise PolicyServerError(f"cannot connect to policy server {self.address}: {exc}") from None
        metadata = self._receive(max(0.1, deadline - time.monotonic()), "metadata")
        if not isinstance(metadata, dict):
            self.close()
            raise PolicyServerError(f"policy server {self.address} sent metadata that is not a map")
        return metadata

    def call(self, request: dict) -> object:
        """Send one request and return the decoded reply."""
        if self._ws is None:
            raise PolicyServerError(f"not connected to policy server {self.address}")
        try:
            self._ws.send(protocol.pack(request))
        except websockets.ConnectionClosed as exc:
            self.close()
            raise self._closed(exc) from None
        return self._receive(self.timeout, "reply")

    def _receive(self, timeout: float, what: str) -> object:
        try:
            frame = self._ws.recv(timeout=timeout)
        except TimeoutError:
            # A late reply would be read as the answer to the next request: drop the connection.
            self.close()
            raise PolicyServerError(f"policy server {self.address} sent no {what} within {timeout:g} s") from None
        except websockets.ConnectionClosed as exc:
            self.close()
            raise self._closed(exc) from None
        if isinstance(frame, str):
            self.close()
            lines = [line for line in frame.strip().splitlines() if line.strip()]
            raise PolicyServerError(f"policy server {self.address} failed: {lines[-1] if lines else 'no detail'}")
        try:
            return protocol.unpack(frame)
        except protocol.ProtocolError as exc:
            self.close()
            raise PolicyServerError(f"policy server {self.address} sent a {what} that is {exc}") from None

    def _closed(self, exc: websockets.ConnectionClosed) -> PolicyServerError:
        if exc.rcvd is None:
            reason = "no close frame; the server process may have died"
        else:
            reason = f"code {exc.rcvd.code}" + (f": {exc.rcvd.reason}" if exc.rcvd.reason else "")
        return PolicyServerError(f"policy server {self.address} closed the connection ({reason})")

    def close(self) -> None:
        if self._ws is not None:
            self._ws.close()
            self._ws = None


class OpenpiPolicy:
    """A policy behind an openpi-protocol websocket server (see the module docstring)."""

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = 8000,
        replan_steps: int = 5,
        resize_size: int = 224,
        connect_timeout: float = 60.0,
        timeout: float = 60.0,
    ):
        if replan_steps < 1 or resize_size < 16 or connect_timeout <= 0 or timeout <= 0:
            raise PolicyServerError("openpi: need replan_steps >= 1, resize_size >= 16 and positive timeouts")
        self.resize_size = resize_size
        self._connection = ServerConnection(host, port, connect_timeout, timeout)
        self.metadata, self.served = self._connect()
        self.spec = self.served or PolicySpec(
            cameras=CAMERAS, image_size=RENDER_SIZE, chunk=replan_steps, replan=replan_steps
        )
        self._client_token = secrets.token_hex(4)
        self._episodes = itertools.count()
        self._episode = ""
        self._context: TaskContext | None = None

    def config(self) -> dict:
        """What is recorded with results: the server, the preprocessing and what the server announced."""
        return {
            "server": self._connection.address,
            "resize_size": None if self.served else self.resize_size,
            "server_metadata": protocol.jsonable(self.metadata),
        }

    def reset(self, context: TaskContext) -> None:
        """Start an episode; reconnects first if an earlier failure dropped the connection."""
        if not self._connection.is_open and self._connect()[1] != self.served:
            self.close()
            raise PolicyServerError(f"policy server {self._connection.address} now serves a different policy")
        self._context = context
        self._episode = f"{self._client_token}-{next(self._episodes)}"

    def _connect(self) -> tuple[dict, PolicySpec | None]:
        """Open the connection; return the server's metadata and its served spec (None: plain openpi)."""
        metadata = self._connection.open()
        try:
            return metadata, protocol.served_spec(metadata)
        except protocol.ProtocolError as exc:
            self.close()
            raise PolicyServerError(f"policy server {self._connection.address}: {exc}") from None

    def act(self, observation: Observation) -> np.ndarray:
        """Ask the server for an action chunk; returns at least `spec.replan` actions (a served policy's
        chunk whole, for the rollout to check against its spec; a plain openpi server's cut to `replan`,
        the chunk this client declares for it)."""
        if self._context is None:
            raise PolicyServerError("openpi: act() before reset()")
        reply = self._connection.call(self.model_inputs(observation))
        try:
            actions = protocol.actions_from_reply(reply)
        except protocol.ProtocolError as exc:
            self._connection.close()
            raise PolicyServerError(f"policy server {self._connection.address} sent a malformed reply: {exc}") from None
        if len(actions) < self.spec.replan:
            raise PolicyServerError(
                f"policy server {self._connection.address} returned {len(actions)} action(s); "
                f"replan_steps={self.spec.replan} needs at least that many"
            )
        return actions if self.served else actions[: self.spec.replan]

    def close(self) -> None:
        self._connection.close()

    def model_inputs(self, observation: Observation) -> dict:
        """The request sent to the server for `observation` (after `reset`): the openpi LIBERO keys, and
        LangGap's extension keys for a LangGap server."""
        # The prompt is the instruction in force at this step: it can change mid-episode.
        prompt = current_instruction(observation, self._context)
        request: dict = {protocol.STATE_KEY: observation.state, protocol.PROMPT_KEY: prompt}
        for camera, image in observation.images.items():
            if self.served is None:
                image = resize_with_pad(image, self.resize_size, self.resize_size)
            request[protocol.CAMERA_KEYS[camera]] = image
        if self.served is not None:
            request[protocol.EPISODE_KEY] = self._episode
            # Only what the served spec may see goes on the wire (the rollout already removed the rest).
            request[protocol.CONTEXT_KEY] = protocol.context_to_message(self._context.for_policy(self.spec))
            if self.spec.sees_state:
                request[protocol.PRIVILEGED_KEY] = protocol.privileged_to_message(observation.privileged)
        return request
