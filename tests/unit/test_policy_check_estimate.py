"""`langgap check-policy`'s arithmetic: an episode's wall time from measured calls and steps, durations as shown,
and the `stochastic` declaration leaving a policy's config hash as it was."""

from __future__ import annotations

import dataclasses

import pytest

from langgap.diagnostics.policy_timing import EpisodeTimes, Timing, duration
from langgap.policies.base import config_hash, policy_config
from langgap.policies.simple import NoopPolicy

TIMING = Timing(
    warmup_s=2.0, opening_s=0.5, call_s=0.1, slowest_s=0.2, others=6, step_s=0.01, start_s=0.3, actions_per_call=5
)


def test_an_episode_is_its_start_its_calls_and_its_steps():
    # 220 steps at 5 actions per call: 44 calls, the first an episode's opening one (the warm-up is once per run).
    assert TIMING.calls(220) == 44 and TIMING.calls(221) == 45
    assert TIMING.episode_s(220) == pytest.approx(0.3 + 0.5 + 43 * 0.1 + 220 * 0.01)
    one_per_call = dataclasses.replace(TIMING, actions_per_call=1)
    assert one_per_call.episode_s(520) == pytest.approx(0.3 + 0.5 + 519 * 0.1 + 520 * 0.01)


def test_the_first_call_of_all_is_a_warm_up_and_each_episode_s_first_its_opening():
    first = EpisodeTimes(calls=(3.0, 0.1, 0.2, 0.1), steps=20, start_s=0.4, simulator_s=0.2)
    second = EpisodeTimes(calls=(0.5, 0.1, 0.3, 0.1), steps=20, start_s=0.2, simulator_s=0.6)
    timing = Timing.measured([first, second])
    assert (timing.warmup_s, timing.opening_s, timing.call_s, timing.slowest_s, timing.others) == (3, 0.5, 0.1, 0.3, 6)
    assert timing.step_s == pytest.approx(0.02) and timing.start_s == pytest.approx(0.3)
    assert timing.actions_per_call == 5


@pytest.mark.parametrize(
    ("seconds", "shown"),
    [
        (0.00042, "0.42 ms"),
        (0.0123, "12 ms"),
        (3.21, "3.2 s"),
        (45.4, "45 s"),
        (719, "12 min"),
        (3600, "1 h"),
        (18_610, "5 h 10 min"),
        (183_600, "2 d 3 h"),
        (172_800, "2 d"),
    ],
)
def test_durations_read_as_a_person_says_them(seconds, shown):
    assert duration(seconds) == shown


def test_declaring_a_policy_stochastic_leaves_its_config_hash_as_it_was():
    """Stored runs keep their `policy_config_hash`: the declaration says how the engine may replay, not how it acts."""
    declared = NoopPolicy()
    declared.spec = dataclasses.replace(NoopPolicy.spec, stochastic=True)
    assert config_hash(policy_config(declared)) == config_hash(policy_config(NoopPolicy())) == "bcf1029da64c98fb"


def test_a_run_of_days_on_every_core_here_passes_with_a_warning_not_an_ok():
    """The wall time is no verdict on the policy, but "[ok]" beside 131 days misled: past LONG_RUN_S on every core
    of this machine it warns, and says what would shorten it."""
    from collections import Counter

    from langgap.diagnostics.checks import check_lines
    from langgap.diagnostics.policy_timing import LONG_RUN_S, wall_time_check

    limits = Counter({("libero_spatial", 220): 1_000})
    quick = wall_time_check(TIMING, limits, 50, "langgap99")
    assert quick.ok and not quick.warning and check_lines(quick)[0].startswith("[ok  ] wall time")
    slow = wall_time_check(dataclasses.replace(TIMING, call_s=20.0), limits, 50, "langgap99")
    assert TIMING.episode_s(220) * 1_000 < LONG_RUN_S < dataclasses.replace(TIMING, call_s=20.0).episode_s(220) * 500
    assert slow.ok and "even with --workers" in slow.warning and "select fewer tasks or episodes" in slow.warning
    lines = check_lines(slow)
    assert lines[0].startswith("[warn] wall time") and lines[-1].strip().startswith("warning: the run would take")
