"""One shared policy for many environment workers, batching their queries (Ray backend).

A GPU policy should not be loaded once per environment worker. With `--shared-policy`, the Ray pool
starts one `PolicyServer` actor (given the GPUs); every environment actor talks to it through a
`SharedPolicyClient`, which follows the ordinary `Policy` protocol. The server keeps one policy
instance per worker slot (policies are stateful within an episode) and answers concurrent `act`
calls together: it waits up to `max_wait_ms` for up to `max_batch` queries, then calls the policy
class's optional `act_batch(policies, observations)` once — or each policy's `act` if the class has
no batched form.
"""

from __future__ import annotations

import asyncio

from langgap.policies import make_policy
from langgap.policies.base import PolicySpec, TaskContext, policy_config
from langgap.sim.env import Observation


class PolicyServer:
    """The body of the shared policy actor (created with `ray.remote(...)`, async methods)."""

    def __init__(self, name: str, args: dict[str, str], max_batch: int = 8, max_wait_ms: float = 5.0):
        self.name, self.args = name, dict(args)
        self.max_batch = max(1, max_batch)
        self.max_wait_s = max_wait_ms / 1000
        self.policies: dict[int, object] = {}
        template = make_policy(name, args)
        self._spec, self._config = template.spec, policy_config(template)
        self._pending: list[tuple[int, Observation, asyncio.Future]] = []
        self._timer: asyncio.TimerHandle | None = None
        self.calls = 0  # batched calls made
        self.queries = 0  # act() requests answered: queries / calls is the mean batch

    def spec(self) -> PolicySpec:
        return self._spec

    def config(self) -> dict:
        return {**self._config, "shared": {"max_batch": self.max_batch, "max_wait_ms": self.max_wait_s * 1000}}

    def stats(self) -> dict:
        return {"calls": self.calls, "queries": self.queries}

    async def reset(self, slot: int, context: TaskContext) -> None:
        if slot not in self.policies:
            self.policies[slot] = make_policy(self.name, self.args)
        self.policies[slot].reset(context)

    async def act(self, slot: int, observation: Observation):
        self.queries += 1
        future = asyncio.get_running_loop().create_future()
        self._pending.append((slot, observation, future))
        if len(self._pending) >= self.max_batch:
            self._flush()
        elif self._timer is None:
            self._timer = asyncio.get_running_loop().call_later(self.max_wait_s, self._flush)
        return await future

    def _flush(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        batch, self._pending = self._pending, []
        if not batch:
            return
        policies = [self.policies[slot] for slot, _, _ in batch]
        observations = [obs for _, obs, _ in batch]
        self.calls += 1
        try:
            batched = getattr(type(policies[0]), "act_batch", None)
            if batched is not None:
                actions = batched(policies, observations)
            else:
                actions = [p.act(o) for p, o in zip(policies, observations, strict=True)]
        except Exception as exc:  # every waiting episode gets the error (an infrastructure failure)
            for _, _, future in batch:
                future.set_exception(exc)
            return
        for (_, _, future), action in zip(batch, actions, strict=True):
            future.set_result(action)


class SharedPolicyClient:
    """The `Policy` an environment actor uses when the policy is shared."""

    def __init__(self, server, slot: int):
        import ray

        self._ray = ray
        self.server = server
        self.slot = slot
        self.spec = ray.get(server.spec.remote())

    def config(self) -> dict:
        return self._ray.get(self.server.config.remote())

    def reset(self, context: TaskContext) -> None:
        self._ray.get(self.server.reset.remote(self.slot, context))

    def act(self, observation: Observation):
        return self._ray.get(self.server.act.remote(self.slot, observation))


def start_server(ray, name: str, args: dict[str, str], *, max_batch: int, max_wait_ms: float, num_gpus: float):
    """Start the shared policy actor (on a GPU if `num_gpus` > 0); its handle goes into the runner setup."""
    actor = ray.remote(num_cpus=0, num_gpus=num_gpus, max_concurrency=1024, max_restarts=0)(PolicyServer)
    return actor.remote(name, args, max_batch, max_wait_ms)
