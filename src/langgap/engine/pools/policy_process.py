"""The local pool's shared policy: one spawned process serving a `PolicyServer` over a Unix socket.

With `--backend local --shared-policy` the pool starts this process before any worker. It builds
the policy, listens on a Unix socket in a private temporary directory (mode 0700: nothing listens
on a network interface, and no other user can connect) and serves every worker's connection with
the batching `PolicyServer` (`langgap.engine.shared_policy`). A connection is a slot: its own
policy instance, dropped when the connection closes (a worker that rebuilds its policy after a
failure reconnects and starts afresh). Messages are length-prefixed pickles; both ends are this
module, run by the same user. The process exits on its own when the process that started it dies.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import multiprocessing as mp
import os
import pickle
import shutil
import socket
import struct
import tempfile
from dataclasses import dataclass
from typing import Any

from langgap.engine.pools.lifetime import exit_with_parent
from langgap.engine.shared_policy import PolicyServer
from langgap.errors import LangGapError, PolicyServerError, one_line
from langgap.policies.base import TaskContext
from langgap.sim.env import Observation

_HEADER = struct.Struct("!Q")  # the length of the pickle that follows
# One message for every way the process can be lost (mid-reply, refused, socket removed), so the
# scheduler's fail-fast sees one cause and stops the run.
GONE = "the shared policy process is gone"


def _frame(message: Any) -> bytes:
    body = pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL)
    return _HEADER.pack(len(body)) + body


class SocketPolicyClient:
    """The `Policy` a worker uses when the local pool shares the policy: each call is one request."""

    def __init__(self, path: str, timeout: float | None = None):
        self._socket = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self._socket.settimeout(timeout)  # None: a policy may take as long as it needs (`--timeout` bounds episodes)
        try:
            self._socket.connect(path)
        except OSError:
            self._socket.close()
            raise PolicyServerError(GONE) from None
        self._replies = self._socket.makefile("rb")
        self.spec = self.request("spec")

    def config(self) -> dict:
        return self.request("config")

    def reset(self, context: TaskContext) -> None:
        self.request("reset", context)

    def act(self, observation: Observation):
        return self.request("act", observation)

    def request(self, method: str, argument: Any = None) -> Any:
        """Send one request and wait for its reply; a failure in the policy process raises `PolicyServerError`."""
        try:
            self._socket.sendall(_frame((method, argument)))
            header = self._replies.read(_HEADER.size)
            body = self._replies.read(_HEADER.unpack(header)[0]) if len(header) == _HEADER.size else b""
            status, value = pickle.loads(body)
        except (OSError, EOFError, pickle.UnpicklingError, struct.error):
            raise PolicyServerError(GONE) from None
        if status == "error":
            raise PolicyServerError(f"shared policy failed: {value}")
        return value

    def close(self) -> None:
        self._replies.close()
        self._socket.close()


@dataclass(frozen=True)
class SocketAddress:
    """The policy process's socket as the runners see it (`RunnerSetup.policy_server`)."""

    path: str

    def connect(self, worker: int) -> SocketPolicyClient:
        # The process gives each connection its own slot: a worker's id is not needed, and a
        # reconnecting worker can never meet its previous connection's policy instance.
        return SocketPolicyClient(self.path)


async def _answer(server: PolicyServer, slot: int, method: str, argument: Any) -> Any:
    if method == "act":
        return await server.act(slot, argument)
    if method == "reset":
        return await server.reset(slot, argument)
    if method == "spec":
        return server.spec()
    if method == "config":
        return server.config()
    if method == "stats":
        return server.stats()
    raise ValueError(f"unknown request {method!r}")


async def _serve_connection(server: PolicyServer, slot: int, reader, writer) -> None:
    try:
        while True:
            try:
                header = await reader.readexactly(_HEADER.size)
                method, argument = pickle.loads(await reader.readexactly(_HEADER.unpack(header)[0]))
            except asyncio.IncompleteReadError:
                return  # the worker closed its policy
            try:
                reply = ("ok", await _answer(server, slot, method, argument))
            except Exception as exc:  # the policy failed: the worker's episode is an infrastructure failure
                reply = ("error", one_line(exc))
            writer.write(_frame(reply))
            await writer.drain()
    except ConnectionError:
        pass  # the worker died or was killed (an episode past its timeout)
    finally:
        server.release(slot)
        writer.close()


async def _serve(server: PolicyServer, path: str, ready) -> None:
    slots = itertools.count()

    async def connected(reader, writer) -> None:
        await _serve_connection(server, next(slots), reader, writer)

    listener = await asyncio.start_unix_server(connected, path=path)
    ready.send(None)
    async with listener:
        await listener.serve_forever()


def policy_process_main(
    name: str, args: dict[str, str], max_batch: int, max_wait_ms: float, path: str, ready, parent_pid: int
) -> None:
    """Entry point of the policy process: build the policy, tell `ready` (None or the error), serve until stopped."""
    exit_with_parent(parent_pid, cleanup=lambda: shutil.rmtree(os.path.dirname(path), ignore_errors=True))
    try:
        server = PolicyServer(name, args, max_batch, max_wait_ms)
    except Exception as exc:
        ready.send(one_line(exc))
        return
    asyncio.run(_serve(server, path, ready))


class PolicyProcess:
    """The shared policy process, seen from the pool: started at once, read and stopped by `close`."""

    def __init__(self, name: str, args: dict[str, str], *, max_batch: int, max_wait_ms: float):
        self._dir = tempfile.mkdtemp(prefix="langgap-policy-")  # private to this user (0700)
        self.address = SocketAddress(os.path.join(self._dir, "policy.sock"))
        context = mp.get_context("spawn")
        ready, tell = context.Pipe(duplex=False)
        self._process = context.Process(
            target=policy_process_main,
            args=(name, dict(args), max_batch, max_wait_ms, self.address.path, tell, os.getpid()),
            daemon=True,
            name="langgap-policy",
        )
        try:
            self._process.start()
            tell.close()
            # Building a policy (a checkpoint on a GPU) may take minutes: wait for its word or its death.
            while not ready.poll(0.5) and self._process.is_alive():
                pass
            try:
                error = ready.recv()
            except EOFError:
                self._process.join(timeout=10)
                error = f"it exited with code {self._process.exitcode}"
        except BaseException:
            self.close()
            raise
        if error is not None:
            self.close()
            raise LangGapError(f"the shared policy process could not start: {error}")

    @property
    def pid(self) -> int | None:
        """The policy process's id."""
        return self._process.pid

    def close(self) -> dict:
        """Stop the process and remove its socket; returns its counters (calls, queries), if it was still up."""
        stats: dict = {}
        if self._process.is_alive():
            with contextlib.suppress(PolicyServerError):  # a process stuck in a policy call has no counters to give
                client = SocketPolicyClient(self.address.path, timeout=5)
                stats = client.request("stats")
                client.close()
            self._process.terminate()
            self._process.join(timeout=10)
            if self._process.is_alive():
                self._process.kill()
                self._process.join(timeout=10)
        shutil.rmtree(self._dir, ignore_errors=True)
        return stats
