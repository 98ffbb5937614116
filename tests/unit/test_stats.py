"""Report statistics against values computed independently (R's binom/prop tests, exact binomial sums)."""

from __future__ import annotations

import dataclasses
import math

import pytest

from langgap.report.data import to_data
from langgap.report.stats import (
    PairedTest,
    Rate,
    cohen_kappa,
    mcnemar_exact,
    minimum_detectable_effect,
    permutation_floor,
    permutation_p,
    wilson,
)


@pytest.mark.parametrize(
    ("successes", "n", "low", "high"),
    [(0, 10, 0.0, 0.2775), (5, 10, 0.2366, 0.7634), (10, 10, 0.7225, 1.0), (1, 20, 0.0089, 0.2361), (0, 0, 0.0, 0.0)],
)
def test_wilson_interval(successes, n, low, high):
    assert wilson(successes, n) == pytest.approx((low, high), abs=1e-4)


@pytest.mark.parametrize(
    ("only_a", "only_b", "p"),
    [(0, 0, 1.0), (0, 5, 0.0625), (5, 0, 0.0625), (1, 9, 0.021484375), (3, 3, 1.0), (0, 10, 0.001953125)],
)
def test_exact_mcnemar(only_a, only_b, p):
    assert mcnemar_exact(only_a, only_b) == pytest.approx(p)


def test_a_rate_is_over_judged_episodes_and_carries_its_interval():
    r = Rate("g", episodes=10, successes=5, gaps=3, tasks=2)
    row = to_data(r)
    assert row["rate"] == 0.5 and (row["ci_low"], row["ci_high"]) == pytest.approx((0.2366, 0.7634), abs=1e-4)
    assert row["gaps"] == 3 and Rate("empty", 0, 0, 4, 1).rate == 0.0


def test_a_paired_test_reports_rates_and_p_value():
    t = PairedTest("a vs b", pairs=20, successes_a=12, successes_b=3, only_a=9, only_b=0, changed=10)
    row = to_data(t)
    assert (row["rate_a"], row["rate_b"], row["changed_behaviour"]) == (0.6, 0.15, 0.5)
    assert row["p_value"] == pytest.approx(0.00390625)


def _power(p1: float, p2: float, n: int) -> float:
    """R's power.prop.test (two-sided, α = 0.05), written out independently."""
    from statistics import NormalDist

    q1, q2, z = 1 - p1, 1 - p2, NormalDist().inv_cdf(0.975)
    return NormalDist().cdf(
        (math.sqrt(n * (p1 - p2) ** 2) - z * math.sqrt((p1 + p2) * (q1 + q2) / 2)) / math.sqrt(p1 * q1 + p2 * q2)
    )


@pytest.mark.parametrize(("rate", "n"), [(0.0, 20), (0.3, 760), (0.95, 800), (0.5, 100), (0.1, 260)])
def test_the_minimum_detectable_effect_has_80_percent_power(rate, n):
    mde = minimum_detectable_effect(rate, n)
    other = rate + mde if rate <= 0.5 else rate - mde
    assert _power(rate, other, n) == pytest.approx(0.8, abs=0.002)
    assert to_data(Rate("g", n, round(rate * n), 0, 1))["mde"] == pytest.approx(mde)


def test_more_episodes_detect_smaller_effects():
    assert (
        minimum_detectable_effect(0.3, 20) > minimum_detectable_effect(0.3, 200) > minimum_detectable_effect(0.3, 2000)
    )


@pytest.mark.parametrize(
    ("both", "only_a", "only_b", "neither", "kappa"),
    [
        (20, 5, 10, 15, 0.4),  # agreement 0.7, chance 0.6 x 0.5 + 0.4 x 0.5 = 0.5
        (10, 0, 0, 10, 1.0),  # every pair agrees, rates of 1/2
        (0, 10, 10, 0, -1.0),  # every pair disagrees
        (25, 25, 25, 25, 0.0),  # agreement 1/2 is what chance gives
        (12, 0, 0, 0, None),  # one outcome everywhere: chance agrees on all, κ is undefined
    ],
)
def test_cohen_kappa(both, only_a, only_b, neither, kappa):
    assert cohen_kappa(both, only_a, only_b, neither) == pytest.approx(kappa)


def test_paired_agreement_and_kappa_come_from_the_pairs_and_are_reported_for_a_retest_only():
    test = PairedTest("a vs b", pairs=50, successes_a=25, successes_b=30, only_a=5, only_b=10, changed=0, retest=True)
    assert test.agreement == pytest.approx(0.7) and test.kappa == pytest.approx(0.4)
    assert to_data(test)["agreement"] == pytest.approx(0.7) and to_data(test)["kappa"] == pytest.approx(0.4)
    other = dataclasses.replace(test, retest=False)  # two different runs: agreement is no test-retest figure
    assert to_data(other)["agreement"] is None and to_data(other)["kappa"] is None


@pytest.mark.parametrize(
    ("a", "b", "p"),
    [
        ([1, 2, 3], [4, 5, 6], 0.1),  # the two most extreme of C(6, 3) = 20 splits
        ([0, 0, 1], [1, 1, 1], 0.4),  # ties: 8 of 20 splits (both zeros on one side) are as far apart
        ([0.9, 0.4, 0.9], [0.8, 1.0, 1.0], 0.5),
        ([0, 0], [0, 0], 1.0),
        ([0.2, 0.4, 0.6], [0.5], 0.75),  # 3 of the 4 splits: all but the one that sets 0.4 apart
    ],
)
def test_the_permutation_test_counts_the_splits_at_least_as_extreme(a, b, p):
    assert permutation_p(a, b) == pytest.approx(p)
    assert permutation_p(b, a) == pytest.approx(p)  # two-sided: the order of the samples does not matter


def test_the_permutation_test_has_a_floor_and_a_limit():
    assert permutation_floor(3, 3) == pytest.approx(0.1) and permutation_floor(3, 2) == pytest.approx(0.1)
    assert permutation_floor(5, 5) == pytest.approx(2 / 252)
    assert permutation_p([0.1, 0.2, 0.3, 0.4, 0.5], [0.6, 0.7, 0.8, 0.9, 1.0]) == pytest.approx(2 / 252)
    assert permutation_p([0.0] * 13, [1.0] * 13) is None  # C(26, 13) splits: more than it enumerates
    assert permutation_p([], [1.0]) is None


def test_a_wilson_interval_never_leaves_zero_to_one():
    # unclamped, 20 of 20 reaches 1.0000000000000002 in floating point
    assert wilson(20, 20)[1] == 1.0 and wilson(0, 20)[0] == 0.0


def test_kappa_of_a_single_item_rated_apart_is_zero():
    assert cohen_kappa(0, 1, 0, 0) == 0.0
    assert cohen_kappa(1, 0, 0, 0) is None  # both rate it alike: chance agrees already


def test_no_episode_detects_nothing_but_the_whole_range():
    assert minimum_detectable_effect(0.3, 0) == 1.0
