"""The pool of Ray actors: one `WorkRunner` per actor, results back to the driver (and its store).

An actor may run on another machine, so it never writes into the driver's directories: its runner
writes into a directory of the actor's own, and every file a work item wrote there (a clip, a
demonstration) travels back with the item's result and is written by the driver where a local worker
would have written it (`RunnerSetup.run_dir`).

Without `--ray-address` a local Ray instance is started that listens on 127.0.0.1 only (Ray has no
authentication). With `--shared-policy` one policy actor (a `PolicyServer`, given `--policy-gpus`)
serves every environment actor, batching their queries (`langgap.engine.shared_policy`).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import socket
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from langgap.atomic import write_bytes_atomically
from langgap.engine.pools import Event, ItemDone, ItemFailed, WorkerLost
from langgap.engine.runner import RunnerSetup, WorkFailure, WorkRunner
from langgap.engine.shared_policy import PolicyServer
from langgap.engine.work import WorkItem
from langgap.errors import DependencyNotInstalled, LangGapError, ParameterError
from langgap.policies.base import TaskContext
from langgap.sim.env import Observation

if TYPE_CHECKING:
    from langgap.engine.spec import ExecutionOptions


def import_ray():
    try:
        import ray
    except ImportError:
        raise DependencyNotInstalled("the Ray backend needs Ray: pip install 'langgap[ray]'") from None
    return ray


class SharedPolicyClient:
    """The `Policy` an environment actor uses when the policy is shared: calls on the policy actor."""

    def __init__(self, server, slot: int):
        self._ray = import_ray()
        self.server = server
        self.slot = slot
        self.spec = self._ray.get(server.spec.remote())

    def config(self) -> dict:
        return self._ray.get(self.server.config.remote())

    def reset(self, context: TaskContext) -> None:
        self._ray.get(self.server.reset.remote(self.slot, context))

    def act(self, observation: Observation):
        return self._ray.get(self.server.act.remote(self.slot, observation))


@dataclass(frozen=True)
class RayPolicyServer:
    """The shared policy actor as the runners see it (`RunnerSetup.policy_server`): one slot per worker."""

    actor: Any

    def connect(self, worker: int) -> SharedPolicyClient:
        return SharedPolicyClient(self.actor, slot=worker)


class RunnerActor:
    """The body of a Ray actor: a `WorkRunner` that lives as long as the actor, writing into a directory
    of its own whose files go back with each result."""

    def __init__(self, setup: RunnerSetup, worker: int):
        self.output = Path(tempfile.mkdtemp(prefix=f"langgap-actor-{worker}-"))
        self.runner = WorkRunner(replace(setup, run_dir=str(self.output)), worker=worker)

    def pid(self) -> int:
        return os.getpid()

    def run(self, item: WorkItem, attempt: int) -> tuple[Any, dict[str, bytes]]:
        """The item's result, and the files it wrote (path relative to the output directory -> bytes)."""
        try:
            return self.runner.run(item, attempt), self._take_files()
        except BaseException:
            self._take_files()  # a failed attempt's files are not the result's
            raise

    def _take_files(self) -> dict[str, bytes]:
        files = {}
        for path in sorted(p for p in self.output.rglob("*") if p.is_file()):
            files[path.relative_to(self.output).as_posix()] = path.read_bytes()
        shutil.rmtree(self.output)
        self.output.mkdir()
        return files


# Ray takes a node address of 127.0.0.1 as a request to find the machine's network address, and then
# binds its servers (GCS, raylet, workers, runtime-env agent) to every interface. With its
# single-machine switch set, it keeps the loopback address and every server binds 127.0.0.1. The
# variable reaches the processes Ray starts during `init` (which keep it); the constant is what this
# process reads. Both are restored afterwards, so a later connection to a real cluster still works.
_SINGLE_MACHINE = "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"


def start_loopback_instance(ray, num_cpus: int, **init_options) -> None:
    """Start a local Ray instance whose every server listens on 127.0.0.1 only."""
    from ray._private import ray_constants

    saved = os.environ.get(_SINGLE_MACHINE), ray_constants.ENABLE_RAY_CLUSTER
    os.environ[_SINGLE_MACHINE], ray_constants.ENABLE_RAY_CLUSTER = "0", False
    try:
        ray.init(num_cpus=num_cpus, _node_ip_address="127.0.0.1", **init_options)
    finally:
        if saved[0] is None:
            os.environ.pop(_SINGLE_MACHINE, None)
        else:
            os.environ[_SINGLE_MACHINE] = saved[0]
        ray_constants.ENABLE_RAY_CLUSTER = saved[1]


HEAD_TIMEOUT_S = 10.0


def check_reachable(address: str, timeout_s: float = HEAD_TIMEOUT_S) -> None:
    """Raise `LangGapError` unless the head at `address` (`host:port`, or `ray://host:port`) accepts a connection:
    Ray's own connect to a dead or misspelled address waits for many minutes before it gives up."""
    if address == "auto":
        return
    host, _, port = address.removeprefix("ray://").rpartition(":")
    try:
        with socket.create_connection((host, int(port)), timeout=timeout_s):
            return
    except ValueError:
        raise ParameterError("{ray_address} takes HOST:PORT, got {got!r}", got=address) from None
    except OSError as exc:
        raise LangGapError(f"cannot reach the Ray cluster at {address}: {exc}") from None


def connect(ray, options: ExecutionOptions) -> bool:
    """Connect to the cluster at `options.ray_address` (or start a local instance) unless this process is
    connected already; returns whether it connected now (and so is the one to shut Ray down)."""
    if ray.is_initialized():
        return False
    common = dict(include_dashboard=False, log_to_driver=False, configure_logging=False)
    try:
        if options.ray_address:
            check_reachable(options.ray_address)
            ray.init(address=options.ray_address, **common)
        else:
            start_loopback_instance(ray, options.workers, **common)
    except ConnectionError as exc:
        raise LangGapError(f"cannot reach the Ray cluster at {options.ray_address}: {exc}") from None
    return True


@contextlib.contextmanager
def ray_session(options: ExecutionOptions) -> Iterator[None]:
    """One Ray connection for every pool made inside (`connect`): pools find it and leave it open."""
    ray = import_ray()
    started = connect(ray, options)
    try:
        yield
    finally:
        if started:
            ray.shutdown()


class RayPool:
    """Environment actors on a Ray cluster (a local one when no address is given)."""

    def __init__(self, setup: RunnerSetup, options: ExecutionOptions):
        ray = import_ray()
        self._ray = ray
        self._started = connect(ray, options)
        self.server = None
        self.server_stats: dict = {}
        try:
            if options.shared_policy:
                gpus = options.policy_gpus or 0.0
                self._check_gpus(gpus)
                # Async methods and a high concurrency: queries wait together in the actor's event loop.
                actor = ray.remote(num_cpus=0, num_gpus=gpus, max_concurrency=1024, max_restarts=0)(PolicyServer)
                self.server = actor.remote(setup.policy, setup.policy_args, options.batch_limit, options.batch_wait_ms)
                setup = replace(setup, policy_server=RayPolicyServer(self.server))
        except BaseException:
            self.close()
            raise
        self.setup = setup
        self._output = setup.output_dir  # where the actors' files are written, on this machine
        self._remote = ray.remote(num_cpus=1, max_restarts=0, max_task_retries=0)(RunnerActor)
        self._actors: dict[int, object] = {}
        self._running: dict[object, int] = {}  # object ref -> worker
        self._next_id = 0

    def _check_gpus(self, gpus: float) -> None:
        available = self._ray.cluster_resources().get("GPU", 0)
        if gpus > available:
            raise ParameterError(
                "{policy_gpus} {gpus:g}: the Ray cluster has {available:g} GPU(s)", gpus=gpus, available=available
            )

    def spawn(self) -> int:
        worker, self._next_id = self._next_id, self._next_id + 1
        self._actors[worker] = self._remote.remote(self.setup, worker)
        return worker

    def submit(self, worker: int, item: WorkItem, attempt: int) -> None:
        self._running[self._actors[worker].run.remote(item, attempt)] = worker

    def poll(self, timeout: float) -> list[Event]:
        from ray.exceptions import GetTimeoutError, RayActorError, RayTaskError

        if not self._running:
            return []
        ready, _ = self._ray.wait(list(self._running), num_returns=1, timeout=timeout)
        events: list[Event] = []
        for ref in ready:
            worker = self._running.pop(ref)
            try:
                result, files = self._ray.get(ref, timeout=60)
                for name, data in files.items():
                    write_bytes_atomically(self._output / name, data)
                events.append(ItemDone(worker, result))
            except RayTaskError as exc:
                cause = exc.cause if isinstance(exc.cause, WorkFailure) else exc
                events.append(ItemFailed(worker, str(cause).strip().splitlines()[-1]))
            except (RayActorError, GetTimeoutError) as exc:
                self._drop(worker)
                events.append(WorkerLost(worker, f"Ray actor died: {type(exc).__name__}"))
        return events

    def _drop(self, worker: int) -> None:
        actor = self._actors.pop(worker)
        self._running = {ref: w for ref, w in self._running.items() if w != worker}
        self._ray.kill(actor, no_restart=True)

    def kill(self, worker: int) -> None:
        self._drop(worker)

    def close(self) -> None:
        for worker in list(getattr(self, "_actors", {})):
            self._drop(worker)
        if self.server is not None:
            self.server_stats = self._ray.get(self.server.stats.remote())
            self._ray.kill(self.server, no_restart=True)
            self.server = None
        if self._started:
            self._ray.shutdown()
            self._started = False
