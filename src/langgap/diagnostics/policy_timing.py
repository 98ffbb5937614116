"""What a policy's measured speed means for a run (`langgap check-policy`): the latency check against eval's
per-episode `--timeout`, and the run's wall time.

Latency fails when the run's longest episode, at the measured per-call and per-step times, would take more
than 1/`TIMEOUT_MARGIN` of eval's `--timeout`: eval kills such an episode as an infrastructure failure, retries
it, stores a gap and stops the run after a few in a row. The margin is there because the check times one
episode in an otherwise idle process, while eval's workers share cores (and a policy's device), and a call's
latency varies from call to call.
"""

from __future__ import annotations

import math
import os
import statistics
from collections import Counter
from dataclasses import dataclass

from langgap.diagnostics.checks import Check
from langgap.engine.spec import DEFAULT_FAILURE_STREAK, DEFAULT_MAX_ATTEMPTS

TIMEOUT_MARGIN = 2.0  # the run's longest episode must fit this many times into eval's --timeout
# What eval does with an episode whose policy raises or that runs past its timeout (an infrastructure failure).
RETRIED = (
    f"eval attempts such an episode {DEFAULT_MAX_ATTEMPTS} times, then stores a gap, and stops the run after "
    f"{DEFAULT_FAILURE_STREAK} in a row"
)
# (suite, step limit) -> how many of a run's episodes have it
StepLimits = Counter[tuple[str, int]]


LONG_RUN_S = 3 * 24 * 3600  # a run longer than this on every core here is worth a warning
WHOLE_EPISODE_BUDGET_S = 45.0  # what check-policy's whole episode may take at the measured speed: about a minute


@dataclass(frozen=True)
class EpisodeTimes:
    """One check episode, measured."""

    calls: tuple[float, ...]  # each policy call's seconds, in order
    steps: int
    start_s: float  # reset, settle and the policy's reset: up to the first call
    simulator_s: float  # the steps: from the first call to the end, the policy's calls left out


@dataclass(frozen=True)
class Timing:
    """What the check's episodes measured, and what it makes of an episode."""

    warmup_s: float  # the policy's very first call (loading, compiling)
    opening_s: float  # an episode's first call after that (the second episode's): a policy's per-episode set-up
    call_s: float  # every other call: the median
    slowest_s: float  # every other call: the slowest
    others: int  # how many other calls there were
    step_s: float  # one simulator step, its cameras' rendering included
    start_s: float  # an episode's start: reset, settle, the policy's reset
    actions_per_call: float  # actions executed per policy call

    @classmethod
    def measured(cls, episodes: list[EpisodeTimes]) -> Timing:
        """The timing of `episodes` (in the order they ran; each made at least one call)."""
        warmup = episodes[0].calls[0]
        others = [seconds for episode in episodes for seconds in episode.calls[1:]] or [warmup]
        steps = sum(episode.steps for episode in episodes)
        return cls(
            warmup_s=warmup,
            opening_s=episodes[-1].calls[0],
            call_s=statistics.median(others),
            slowest_s=max(others),
            others=len(others),
            step_s=sum(episode.simulator_s for episode in episodes) / steps,
            start_s=statistics.fmean(episode.start_s for episode in episodes),
            actions_per_call=steps / sum(len(episode.calls) for episode in episodes),
        )

    def calls(self, max_steps: int) -> int:
        """The policy calls of an episode played to a step limit of `max_steps`."""
        return math.ceil(max_steps / self.actions_per_call)

    def episode_s(self, max_steps: int) -> float:
        """The wall time of an episode played to a step limit of `max_steps` (after the policy's warm-up)."""
        calls = self.opening_s + (self.calls(max_steps) - 1) * self.call_s
        return self.start_s + calls + max_steps * self.step_s


def duration(seconds: float) -> str:
    """`seconds` for a person: 0.42 ms, 12 ms, 3.2 s, 45 s, 12 min, 5 h 10 min, 2 d 3 h."""
    if seconds < 0.01:
        return f"{seconds * 1000:.2g} ms"
    if seconds < 1:
        return f"{seconds * 1000:.0f} ms"
    if seconds < 60:
        return f"{seconds:.2g} s" if seconds < 10 else f"{seconds:.0f} s"
    hours, minutes = divmod(round(seconds / 60), 60)
    if not hours:
        return f"{minutes} min"
    if hours < 24:
        return f"{hours} h {minutes} min" if minutes else f"{hours} h"
    days, hours = divmod(hours + (minutes >= 30), 24)
    return f"{days} d {hours} h" if hours else f"{days} d"


def latency_check(timing: Timing, limits: StepLimits, timeout_s: float) -> Check:
    """Whether the run's longest episode fits, with the margin, into eval's `timeout_s` per episode."""
    suite, steps = max(limits, key=lambda limit: limit[1])
    longest = timing.episode_s(steps)
    detail = (
        f"a call takes {duration(timing.call_s)} (median of {timing.others}, the slowest "
        f"{duration(timing.slowest_s)}), an episode's first {duration(timing.opening_s)}, the very first "
        f"{duration(timing.warmup_s)}; a simulator step {duration(timing.step_s)}\n"
        f"the run's longest episode ({suite}, {steps} steps, {timing.calls(steps)} calls) takes about "
        f"{duration(longest)}"
    )
    timeout = f"eval's --timeout {timeout_s:g} s per episode"
    if longest <= timeout_s / TIMEOUT_MARGIN:
        return Check("latency", True, f"{detail}: within half of {timeout}")
    remedy = (
        f"make act faster (a GPU, a smaller model), execute more actions per call (replan), or give eval "
        f"--timeout {60 * math.ceil(longest * TIMEOUT_MARGIN / 60)} or more"
    )
    return Check("latency", False, f"{detail}, more than half of {timeout}: {RETRIED}", remedy)


def wall_time_check(timing: Timing, limits: StepLimits, tasks: int, catalog: str) -> Check:
    """The run's wall time at `timing`: its episodes (`limits`, over `tasks` tasks of `catalog`) to their step limits,
    with 1 worker and with N."""
    episodes = sum(limits.values())
    total = sum(n * timing.episode_s(steps) for (_, steps), n in limits.items())
    per_suite = ", ".join(
        f"{suite} {steps} steps ({timing.calls(steps)} calls) ≈ {duration(timing.episode_s(steps))}"
        for suite, steps in sorted(limits, key=lambda limit: limit[1])
    )
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    lines = [
        f"eval's plan: {episodes:,} episodes ({tasks} task{'s' * (tasks > 1)} × {episodes // tasks} init states of "
        f"{catalog}); an episode to its step limit: {per_suite}",
        f"about {duration(total)} with 1 worker if every episode runs to its step limit (one that succeeds ends "
        "sooner); N workers take about 1/N of it while each has a core and the policy's device keeps up (here "
        f"{cores} core(s): --workers {cores} ≈ {duration(total / cores)})",
    ]
    warning = ""
    if total / cores > LONG_RUN_S:
        warning = (
            f"the run would take {duration(total / cores)} even with --workers {cores}: select fewer tasks or "
            "episodes, run on more cores or a faster device, or make act faster"
        )
    return Check("wall time", True, "\n".join(lines), warning=warning)
