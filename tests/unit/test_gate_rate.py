"""The gate's admission rule at its boundary: the oracle's successes plus the init states a searched
demonstration did must reach `FEASIBLE_RATE` (90 %) of the init states the gate ran."""

from __future__ import annotations

import pytest

from langgap.gate.rows import shown_doable
from langgap.vocabulary import FEASIBLE_RATE


def test_the_rate_is_ninety_percent():
    assert FEASIBLE_RATE == 0.90


@pytest.mark.parametrize(
    ("successes", "demonstrated", "episodes", "doable"),
    [
        (9, 0, 10, True),  # exactly at the rate
        (18, 0, 20, True),
        (45, 0, 50, True),
        (17, 0, 20, False),  # 85 %: below
        (44, 0, 50, False),  # 88 %
        (8, 1, 10, True),  # successes plus demonstrated, exactly at the rate
        (16, 2, 20, True),
        (16, 1, 20, False),
        (0, 5, 5, True),  # every init state by a searched demonstration
        (0, 0, 0, False),  # no episode shows nothing
    ],
)
def test_successes_plus_demonstrated_must_reach_the_rate(successes, demonstrated, episodes, doable):
    assert shown_doable(successes, demonstrated, episodes) is doable
