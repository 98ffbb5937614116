"""A policy whose 'server' is down while a switch file exists: the harness's fail-fast tests."""

from __future__ import annotations

from pathlib import Path

from langgap.policies.simple import NoopPolicy


class OutagePolicy(NoopPolicy):
    """Holds still; raises the same infrastructure error on every call while `switch` exists."""

    def __init__(self, switch: str = ""):
        self.switch = Path(switch)

    def act(self, observation):
        if self.switch.exists():
            raise ConnectionError("policy server unreachable")
        return super().act(observation)
