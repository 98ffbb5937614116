"""The oracle's choice of hand yaw against the wrist's range (pure geometry, no simulator)."""

from __future__ import annotations

import math

from langgap.policies.oracle.geometry import WRIST_LIMIT, sweeping_yaw, wrist_angle, wrist_yaw

# libero10/s9, init state 11: the microwave door stands open at -1.33 rad; the hand that pushes it
# shut closes along -1.50 or (the same grip turned half round) 1.64, at azimuth 0.151 from the base,
# and turns with the door by +1.33 on the way.
YAW, AZIMUTH, SWEEP = -1.50, 0.151, 1.33


def test_wrist_yaw_alone_keeps_the_nearer_yaw_whose_start_is_within_range():
    assert abs(wrist_angle(YAW, AZIMUTH)) < WRIST_LIMIT
    assert wrist_yaw(YAW, 0.0, AZIMUTH) == YAW


def test_a_sweeping_hand_takes_the_yaw_whose_wrist_has_room_for_the_whole_turn():
    chosen = sweeping_yaw(YAW, AZIMUTH, SWEEP)
    assert math.isclose(chosen, YAW + math.pi)
    start = wrist_angle(chosen, AZIMUTH)
    assert max(abs(start), abs(start - SWEEP)) < WRIST_LIMIT
    # The other yaw ends the push past the joint's limit.
    other = wrist_angle(YAW, AZIMUTH)
    assert abs(other - SWEEP) > WRIST_LIMIT


def test_the_sweep_direction_decides():
    # Wrist at +1.50 for this yaw, -1.64 for its half-turned twin: the push turning the wrist down
    # keeps the first, the one turning it up the twin.
    yaw = 0.85
    assert math.isclose(wrist_angle(yaw, 0.0), 1.50)
    assert sweeping_yaw(yaw, 0.0, SWEEP) == yaw
    assert math.isclose(sweeping_yaw(yaw, 0.0, -SWEEP), yaw + math.pi)
