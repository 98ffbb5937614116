"""One policy for many environment workers, batching their queries: the logic every transport shares.

A GPU policy should not be loaded once per environment worker. With `--shared-policy`, one
`PolicyServer` serves every worker: in a Ray actor (`langgap.engine.pools.ray`) or, on the local
backend, in one policy process behind a Unix socket (`langgap.engine.pools.policy_process`). Each
worker talks to it through a client that follows the ordinary `Policy` protocol. The server keeps
one policy instance per slot (policies are stateful within an episode) and answers concurrent `act`
calls together: it waits up to `max_wait_ms` for up to `max_batch` queries, then calls the policy
class's optional `act_batch(policies, observations)` once — or each policy's `act` if the class has
no batched form.

Privileges are enforced here, whatever a client sends: a policy is reset with the goal only if its
spec `sees_goal`, and shown the simulator state only if it `sees_state`. The served policy's config
(what its runs' `policy_config_hash` is computed from) is the policy's own: batching is an execution
option, stored with the run's spec, and must not make the same policy look like another.
"""

from __future__ import annotations

import asyncio
import contextlib

from langgap.policies import make_policy
from langgap.policies.base import PolicySpec, TaskContext, observation_for, policy_config
from langgap.sim.env import Observation


class PolicyServer:
    """The shared policy's server: one instance per slot, `act` batched (run inside an asyncio loop)."""

    def __init__(self, name: str, args: dict[str, str], max_batch: int, max_wait_ms: float):
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
        """The served policy's spec (what every client's environment must show it)."""
        return self._spec

    def config(self) -> dict:
        """The served policy's configuration (`policy_config` of the policy itself, batching left out)."""
        return self._config

    def stats(self) -> dict:
        """How many batched calls answered how many queries."""
        return {"calls": self.calls, "queries": self.queries}

    async def reset(self, slot: int, context: TaskContext) -> None:
        """Start an episode on `slot`'s policy instance (built on its first episode)."""
        if slot not in self.policies:
            self.policies[slot] = make_policy(self.name, self.args)
        self.policies[slot].reset(context.for_policy(self._spec))

    def release(self, slot: int) -> None:
        """Drop `slot`'s policy instance (its worker is gone, or rebuilds its policy after a failure)."""
        policy = self.policies.pop(slot, None)
        if policy is not None and hasattr(policy, "close"):
            with contextlib.suppress(Exception):  # a broken policy's close must not stop the server
                policy.close()

    async def act(self, slot: int, observation: Observation):
        """`slot`'s policy's action for `observation`, computed in a batch with other slots' queries."""
        observation = observation_for(observation, self._spec)
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
