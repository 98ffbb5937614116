"""The statistics of reports: Wilson intervals for rates, exact McNemar tests for paired episodes, exact
permutation tests between replicate runs."""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

from langgap.report.data import FIELDS, Spec

Z_95 = 1.959964
Z_POWER_80 = 0.841621


def wilson(successes: int, n: int, z: float = Z_95) -> tuple[float, float]:
    """Wilson score 95 % interval for a binomial proportion (0, 0 for n = 0)."""
    if n == 0:
        return 0.0, 0.0
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def mcnemar_exact(only_a: int, only_b: int) -> float:
    """Two-sided exact McNemar p-value from the two discordant counts (binomial test at 1/2)."""
    n = only_a + only_b
    if n == 0:
        return 1.0
    k = min(only_a, only_b)
    tail = sum(math.comb(n, i) for i in range(k + 1)) / 2**n
    return min(1.0, 2 * tail)


# Above this many ways to split the runs, `permutation_p` is not computed (it enumerates them all).
PERMUTATION_LIMIT = 1_000_000


def permutation_p(a: Sequence[float], b: Sequence[float]) -> float | None:
    """Two-sided exact permutation test of two samples' means: the share of all ways to split the pooled
    values into groups of `len(a)` and `len(b)` whose difference of means is at least the observed one.
    None when either sample is empty or there are more than `PERMUTATION_LIMIT` splits."""
    values = [*a, *b]
    splits = math.comb(len(values), len(a))
    if not a or not b or splits > PERMUTATION_LIMIT:
        return None
    total = sum(values)

    def difference(first_sum: float) -> float:
        return abs(first_sum / len(a) - (total - first_sum) / len(b))

    observed = difference(sum(a))
    # A relative tolerance: the same split reached in another order must count as at least as extreme.
    extreme = sum(
        difference(sum(values[i] for i in chosen)) >= observed * (1 - 1e-9)
        for chosen in itertools.combinations(range(len(values)), len(a))
    )
    return extreme / splits


def permutation_floor(n_a: int, n_b: int) -> float:
    """The smallest p-value `permutation_p` can give for samples of these sizes, whatever their values: the
    observed split always counts itself, and its mirror image too when the sizes are equal (reached when the
    values are distinct and the observed split is the most extreme)."""
    return (2 if n_a == n_b else 1) / math.comb(n_a + n_b, n_a)


def cohen_kappa(both: int, only_a: int, only_b: int, neither: int) -> float | None:
    """Cohen's κ of two binary ratings of the same items: their agreement beyond what their own success
    rates give by chance. None when chance alone agrees on every item (both rate every item alike)."""
    n = both + only_a + only_b + neither
    if n == 0:
        return None
    a, b = (both + only_a) / n, (both + only_b) / n
    chance = a * b + (1 - a) * (1 - b)
    return None if chance == 1 else ((both + neither) / n - chance) / (1 - chance)


def minimum_detectable_effect(rate: float, n: int, z_alpha: float = Z_95, z_power: float = Z_POWER_80) -> float:
    """The smallest change in success rate (towards 1/2) that a second run of `n` episodes would detect
    against a rate of `rate` over `n` episodes, with 80 % power at α = 0.05 (two-sided z-test for two
    proportions, normal approximation); 1.0 for n = 0."""
    if n == 0:
        return 1.0
    direction = 1.0 if rate <= 0.5 else -1.0
    room = 1.0 - rate if direction > 0 else rate

    def detectable(delta: float) -> bool:
        other = rate + direction * delta
        mean = (rate + other) / 2
        null = z_alpha * math.sqrt(2 * mean * (1 - mean) / n)
        alternative = z_power * math.sqrt((rate * (1 - rate) + other * (1 - other)) / n)
        return null + alternative <= delta

    if not detectable(room):
        return room
    low, high = 0.0, room
    for _ in range(50):  # bisection to well below a rounding step of the tables
        middle = (low + high) / 2
        low, high = (low, middle) if detectable(middle) else (middle, high)
    return high


@dataclass(frozen=True)
class Rate:
    """A group of episodes and its success rate; gaps are counted beside, never as failures."""

    group: str
    episodes: int  # judged episodes (the rate's denominator)
    successes: int
    gaps: int
    tasks: int
    # The scripted oracle on the same tasks and init states (from the catalog's recorded verdicts);
    # oracle_episodes 0: no verdict covers these tasks.
    oracle_successes: int = 0
    oracle_episodes: int = 0

    @property
    def rate(self) -> float:
        return self.successes / self.episodes if self.episodes else 0.0

    @property
    def oracle_rate(self) -> float | None:
        """The oracle's success rate on the same tasks and init states (None: not known)."""
        return self.oracle_successes / self.oracle_episodes if self.oracle_episodes else None

    @property
    def relative(self) -> float | None:
        """The rate as a share of the oracle's (None when the oracle's is unknown or 0)."""
        return self.rate / self.oracle_rate if self.oracle_rate else None

    @property
    def ci(self) -> tuple[float, float]:
        return wilson(self.successes, self.episodes)

    @property
    def mde(self) -> float:
        """The minimum detectable effect at this group's size (see `minimum_detectable_effect`)."""
        return minimum_detectable_effect(self.rate, self.episodes)

    # The JSON report's row (`langgap.report.data.to_data`): the fields, then the figures derived from them.
    DATA: ClassVar[Spec] = (
        FIELDS,
        "rate",
        ("ci_low", lambda r: r.ci[0]),
        ("ci_high", lambda r: r.ci[1]),
        "mde",
        "oracle_rate",
        ("relative_to_oracle", "relative"),
    )


@dataclass(frozen=True)
class PairedTest:
    """Two sets of episodes matched one to one, compared with the exact McNemar test."""

    name: str
    pairs: int
    successes_a: int
    successes_b: int
    only_a: int  # pairs where only the first succeeded
    only_b: int
    changed: int  # pairs whose achieved task differs
    # The two sides are one run spec run twice: only then are `agreement` and `kappa` a test-retest, and reported.
    retest: bool = False

    @property
    def p_value(self) -> float:
        return mcnemar_exact(self.only_a, self.only_b)

    @property
    def agreement(self) -> float:
        """The share of pairs with the same outcome (a test-retest's first figure)."""
        return 1 - (self.only_a + self.only_b) / self.pairs

    @property
    def kappa(self) -> float | None:
        """Cohen's κ of the pairs' outcomes (`cohen_kappa`)."""
        both = self.successes_a - self.only_a
        return cohen_kappa(both, self.only_a, self.only_b, self.pairs - both - self.only_a - self.only_b)

    @property
    def rate_a(self) -> float:
        """The first side's success rate over the pairs."""
        return self.successes_a / self.pairs

    @property
    def rate_b(self) -> float:
        """The second side's success rate over the pairs."""
        return self.successes_b / self.pairs

    @property
    def changed_behaviour(self) -> float:
        """The share of pairs whose achieved task differs."""
        return self.changed / self.pairs

    # The JSON report's row: the fields, then the figures derived from them (a test-retest's only for a retest).
    DATA: ClassVar[Spec] = (
        FIELDS,
        "rate_a",
        "rate_b",
        "p_value",
        ("agreement", lambda t: t.agreement if t.retest else None),
        ("kappa", lambda t: t.kappa if t.retest else None),
        "changed_behaviour",
    )
