"""How the demonstration search draws its candidates (no simulator: the sampler alone)."""

from __future__ import annotations

import numpy as np
import pytest

from langgap.gate.demonstrations import DemonstrationError
from langgap.gate.search import EXPLORE, PRESS_DEPTH_M, TILT_DEG, TURN_DEG, Candidate, Sampler


def _press(candidate) -> tuple[float, float, float]:
    return tuple(float(x) for x in candidate.policy_args["drawer"].split(":")[1:])


def test_where_no_drawer_moves_a_candidate_varies_only_the_noise():
    sampler = Sampler(False, np.random.default_rng(0))
    drawn = [sampler.draw().policy_args for _ in range(8)]
    assert all(set(args) == {"noise", "noise_seed"} for args in drawn)
    assert len({args["noise_seed"] for args in drawn}) == 8  # each its own draw


def test_the_first_candidates_cover_the_primitives_whole_ranges():
    sampler = Sampler(True, np.random.default_rng(1))
    drawn = [sampler.draw() for _ in range(EXPLORE)]
    assert all("drawer" in c.policy_args for c in drawn)
    for tilt, turn, depth in (_press(c) for c in drawn if c.policy_args["drawer"] != "grasp"):
        assert TILT_DEG[0] <= tilt <= TILT_DEG[1] and TURN_DEG[0] <= turn <= TURN_DEG[1]
        assert PRESS_DEPTH_M[0] <= depth <= PRESS_DEPTH_M[1]


def test_later_candidates_centre_on_the_press_that_moved_the_drawer_furthest():
    sampler = Sampler(True, np.random.default_rng(2))
    for _ in range(EXPLORE):
        sampler.draw()
    far, near = "press:40.0:2.0:0.020", "press:10.0:-35.0:0.045"
    sampler.draw()  # the draws these stand for
    sampler.tell(Candidate({"drawer": near}), 0.2)
    sampler.tell(Candidate({"drawer": far}), 0.7)
    sampler.tell(Candidate({"drawer": "grasp"}), 0.9)  # a grasp is no centre for presses
    sampler.tell(Candidate({"drawer": near}), 0.0)
    later = np.array([_press(sampler.draw()) for _ in range(30)])
    assert np.all(np.abs(later[:, :2] - [40.0, 2.0]) < 40.0)  # around the best, never near the other's turn
    assert abs(np.median(later[:, 0]) - 40.0) < 6 and abs(np.median(later[:, 1]) - 2.0) < 6
    assert abs(np.median(later[:, 2]) - 0.02) < 0.005


def test_a_candidate_is_read_back_from_the_found_by_it_wrote():
    candidate = Candidate({"drawer": "press:30.0,-5.0,0.020", "noise": "0.110", "noise_seed": "12"})
    assert Candidate.parse(str(candidate)) == candidate and Candidate.parse("oracle") == Candidate({})
    for written in ("small-bc noise=0.1", "oracle noise"):
        with pytest.raises(DemonstrationError, match="not an oracle with key=value arguments"):
            Candidate.parse(written)
