"""The diversity sweep's figure says how many training seeds each line pools, also while a sweep is still running
(its first K has more finished seeds than its last)."""

from __future__ import annotations

from experiments.diversity_plot import Cell, seeds_text


def _cell(seeds: int) -> Cell:
    return Cell(successes=seeds, episodes=10 * seeds, runs=tuple((1, 10) for _ in range(seeds)))


def test_a_line_of_equal_seeds_says_how_many():
    assert seeds_text([(1, _cell(3)), (24, _cell(3))]) == "3 seeds"
    assert seeds_text([(1, _cell(1))]) == "1 seed"


def test_a_line_whose_points_pool_different_seeds_gives_the_range():
    assert seeds_text([(1, _cell(3)), (3, _cell(2)), (24, _cell(2))]) == "2–3 seeds per point"
