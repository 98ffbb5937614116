"""Report statistics against values computed independently (R's binom/prop tests, exact binomial sums)."""

from __future__ import annotations

import pytest

from langgap.report.stats import PairedTest, Rate, mcnemar_exact, wilson


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
    row = r.as_dict()
    assert row["rate"] == 0.5 and (row["ci_low"], row["ci_high"]) == pytest.approx((0.2366, 0.7634), abs=1e-4)
    assert row["gaps"] == 3 and Rate("empty", 0, 0, 4, 1).rate == 0.0


def test_a_paired_test_reports_rates_and_p_value():
    t = PairedTest("a vs b", pairs=20, successes_a=12, successes_b=3, only_a=9, only_b=0, changed=10)
    row = t.as_dict()
    assert (row["rate_a"], row["rate_b"], row["changed_behaviour"]) == (0.6, 0.15, 0.5)
    assert row["p_value"] == pytest.approx(0.00390625)
