"""The oracle's planning helpers on hand-made scenes (pure geometry, no simulator)."""

from __future__ import annotations

import math

import numpy as np

from langgap.policies.oracle import hand
from langgap.policies.oracle.drawers import _exit_distance
from langgap.policies.oracle.geometry import Boxes, depth, depth_across, top_down
from langgap.policies.oracle.hooking import PRESSED_DEPTHS, plan_hook
from langgap.policies.oracle.motion import TURNING_REACH, Agent, reorient
from langgap.policies.oracle.placement import flight_path
from langgap.policies.oracle.scene import Scene

BASE = np.array([-0.66, 0.0, 0.912])
IDENTITY_POSE = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0])


def _scene(eef: np.ndarray) -> Scene:
    """A scene with a robot and one drawer, listed (as LIBERO's privileged state does) both under its
    fixture's name and under its region's."""
    drawer = {
        "qpos": np.array([0.0]),
        "anchor": np.zeros(3),
        "axis": np.array([0.0, -1.0, 0.0]),
        "slide": np.array([1.0]),
        "limits": np.array([-0.16, 0.01]),
        "body": np.array([0.0, -0.25, 1.0, 1.0, 0.0, 0.0, 0.0]),
        "shape": np.array([[-0.1, -0.1, -0.03, 0.1, 0.1, 0.03]]),
        "bbox": np.array([-0.1, -0.35, 0.97, 0.1, -0.15, 1.03]),
        "handle": np.array([0.0, -0.14, 1.0]),
        "open": np.array([-0.16, -0.14]),
        "close": np.array([0.0, 0.01]),
    }
    raw = {
        "eef_pos": eef,
        "eef_mat": top_down(0.0),
        "gripper_qpos": np.array([0.04, -0.04]),
        "base_pos": BASE,
        "body/bowl": np.concatenate([[-0.08, 0.0, 0.9], IDENTITY_POSE[3:]]),
        "shape/bowl": np.array([[-0.05, -0.05, 0.0, 0.05, 0.05, 0.05]]),
        "movable/bowl": np.array([1.0]),
    }
    for name in ("cabinet", "cabinet_top_region"):
        raw.update({f"art/{name}/{key}": value for key, value in drawer.items()})
    return Scene(raw)


def test_a_drawer_moved_in_a_what_if_scene_moves_under_every_name_and_only_there():
    scene = _scene(np.array([-0.2, 0.0, 1.2]))
    opened = scene.with_part_moved("cabinet_top_region", np.array([0.0, 0.14, 0.0]))
    for name in ("cabinet", "cabinet_top_region"):
        assert np.allclose(opened.articulation(name).boxes.centre[0], [0.0, -0.11, 1.0])
        assert np.allclose(opened.articulation(name).handle, [0.0, 0.0, 1.0])
        assert np.allclose(scene.articulation(name).boxes.centre[0], [0.0, -0.25, 1.0])
    # Seen once among the obstacles, where it will stand.
    assert len(opened.obstacles()) == 2
    assert np.allclose(opened.obstacles(exclude=("bowl",)).centre, [[0.0, -0.11, 1.0]])


def test_the_way_out_of_a_drawers_footprint_is_the_shorter_of_its_two_sides():
    box = np.array([-0.15, -0.07, 0.9, -0.04, 0.04, 0.95])  # a bowl; the open drawer covers x >= -0.09
    keep_clear = np.array([-0.09, -0.2, 0.13, 0.0])
    assert math.isclose(_exit_distance(box, keep_clear, np.array([-1.0, 0.0])), 0.05)  # its right side out
    assert math.isclose(_exit_distance(box, keep_clear, np.array([0.0, 1.0])), 0.07)  # its back out
    diagonal = np.array([-1.0, 1.0]) / math.sqrt(2)
    assert math.isclose(_exit_distance(box, keep_clear, diagonal), 0.05 * math.sqrt(2))


def test_a_flat_object_runs_into_a_box_by_its_width_not_by_their_shared_height():
    plate = Boxes.from_local(np.array([[-0.07, -0.07, 0.0, 0.07, 0.07, 0.02]]), np.eye(3), np.zeros(3))
    cheese = Boxes.from_local(np.array([[0.03, -0.02, 0.0, 0.11, 0.02, 0.018]]), np.eye(3), np.zeros(3))
    assert math.isclose(depth(plate, cheese), 0.018)  # the heights overlap least
    assert math.isclose(depth_across(plate, cheese), 0.04)


def _first_action(scene: Scene, rot: np.ndarray, toward: np.ndarray) -> np.ndarray | None:
    agent = Agent()
    agent.scene = scene
    try:
        return next(reorient(agent, rot, toward=toward))
    except StopIteration:
        return None


def test_a_hand_within_turning_reach_turns_on_its_way():
    scene = _scene(BASE + np.array([TURNING_REACH - 0.1, 0.0, 0.3]))
    assert _first_action(scene, top_down(math.pi / 2), np.zeros(3)) is None


def test_a_stretched_hand_draws_in_toward_where_it_goes_and_turns_meanwhile():
    scene = _scene(BASE + np.array([0.7, 0.0, 0.3]))
    toward = BASE + np.array([0.5, 0.4, 0.0])
    action = _first_action(scene, top_down(math.pi / 2), toward)
    assert action is not None
    move, turn = action[:3], action[3:6]
    # Toward the point at TURNING_REACH on the way to `toward`: in and to its side, not straight back.
    staging = BASE[:2] + (toward - BASE)[:2] / np.linalg.norm((toward - BASE)[:2]) * TURNING_REACH
    expected = staging - scene.eef_pos[:2]
    assert np.dot(move[:2], expected) / (np.linalg.norm(move[:2]) * np.linalg.norm(expected)) > 0.99
    assert abs(turn[2]) > 0.5  # the turn about the vertical starts at once


def test_a_load_beside_a_fixture_flies_away_from_it_without_climbing_over_it():
    # The drawer spans y -0.35..-0.15 up to z 1.03; a bowl-sized load stands 2 cm from its side.
    scene = _scene(np.array([-0.2, 0.0, 1.2]))
    start = np.array([0.0, -0.08, 0.95])
    fly = dict(exclude=("bowl",), hang=0.03, reach=0.03, extent=np.array([-0.05, -0.05, 0.05, 0.05]))
    away = flight_path(scene, start, np.array([0.0, 0.2, 0.95]), **fly)
    along = flight_path(scene, start, np.array([0.3, -0.08, 0.95]), **fly)
    assert away[:, 2].max() == along[:, 2].max() == 0.95
    # An empty hand (no load held as it will be carried) turns on its way: it is flown over.
    empty = flight_path(scene, start, np.array([0.0, 0.2, 0.95]), exclude=("bowl",), hang=0.03, reach=0.08)
    assert empty[:, 2].max() > 1.06
    # Nearer to it than at the start, or across it, the load is flown over it.
    toward = flight_path(scene, start, np.array([-0.3, -0.15, 0.95]), **fly)
    across = flight_path(scene, start, np.array([0.0, -0.45, 0.95]), **fly)
    assert toward[:, 2].max() > 1.06 and across[:, 2].max() > 1.06


def _plate_scene(cheese_at: np.ndarray) -> Scene:
    """A plate 14 cm across at the origin of the table (its floor 6 mm thick, walls 16 mm high) and a
    1.8 cm box: the plate's hollow is too shallow for the fingers' usual depths."""
    walls = [
        (0.065, 0.0, 0.005, 0.07),
        (-0.065, 0.0, 0.005, 0.07),
        (0.0, 0.065, 0.07, 0.005),
        (0.0, -0.065, 0.07, 0.005),
    ]
    floor = [0.0, 0.0, 0.003, 0.07, 0.07, 0.003]
    parts = [floor, *([x, y, 0.008, hx, hy, 0.008] for x, y, hx, hy in walls)]
    identity = np.eye(3).ravel()
    return Scene(
        {
            "eef_pos": np.array([-0.2, 0.0, 1.1]),
            "eef_mat": top_down(0.0),
            "gripper_qpos": np.array([0.0, 0.0]),
            "base_pos": BASE,
            "body/plate": np.concatenate([[0.0, 0.0, 0.9], IDENTITY_POSE[3:]]),
            "shape/plate": np.array(
                [
                    [c - h for c, h in zip(p[:3], p[3:], strict=True)]
                    + [c + h for c, h in zip(p[:3], p[3:], strict=True)]
                    for p in parts
                ]
            ),
            "parts/plate": np.concatenate([np.concatenate([p, identity]) for p in parts]),
            "movable/plate": np.array([1.0]),
            "body/cheese": np.concatenate([[*cheese_at, 0.9], IDENTITY_POSE[3:]]),
            "shape/cheese": np.array([[-0.02, -0.03, 0.0, 0.02, 0.03, 0.018]]),
            "movable/cheese": np.array([1.0]),
        }
    )


def test_a_plate_is_hooked_only_by_a_pressed_drag_which_pushes_what_is_in_its_way_ahead():
    shift = np.array([0.0, 0.2])
    clear = _plate_scene(cheese_at=np.array([0.4, 0.4]))
    # The usual depths put the fingertips into the plate's floor: no hook for a plain drag.
    assert plan_hook(clear, "plate", shift) is None
    hook = plan_hook(clear, "plate", shift, pressed=True)
    assert hook is not None and hook.pressed
    assert math.isclose(hook.start[2] - hand.TIP, 0.916 - PRESSED_DEPTHS[-1])  # 1 cm into the hollow
    assert hook.end[1] - hook.start[1] > shift[1]  # to the wall, then the whole way
    # Held down, the plate shoves a box in its way ahead: the drag is planned as if it were not there.
    blocked = plan_hook(_plate_scene(cheese_at=np.array([0.0, 0.12])), "plate", shift, pressed=True)
    assert blocked is not None and np.allclose(blocked.end, hook.end)
