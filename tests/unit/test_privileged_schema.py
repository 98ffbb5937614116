"""The privileged observation's schema (`langgap.sim.privileged_schema`) and the spec's chunk limit:
what a policy may be shown, and what it may return, fail clearly when broken."""

from __future__ import annotations

import numpy as np
import pytest

from langgap.policies import protocol
from langgap.policies.base import PolicyOutputError, PolicySpec, as_action_chunk
from langgap.sim.privileged_schema import PrivilegedState, PrivilegedStateError
from tests.support.policies import robot_only_state

ROBOT = dict(robot_only_state())
BOWL = {
    "body/bowl_1": np.zeros(7),
    "bbox/bowl_1": np.zeros(6),
    "movable/bowl_1": np.ones(1),
    "shape/bowl_1": np.zeros((3, 6)),
    "parts/bowl_1": np.zeros((3, 15)),
    "contact/bowl_1": np.zeros(2),
}
DRAWER = {
    f"art/cabinet_1/{member}": np.zeros(size)
    for member, size in {"qpos": 1, "anchor": 3, "axis": 3, "slide": 1, "limits": 2, "body": 7, "open": 2}.items()
} | {"art/cabinet_1/shape": np.zeros((0, 6)), "joint/cabinet_1_joint": np.zeros(1)}


def test_a_whole_state_is_a_read_only_mapping_of_its_arrays():
    state = PrivilegedState({**ROBOT, **BOWL, **DRAWER})
    assert state["body/bowl_1"].shape == (7,) and "art/cabinet_1/open" in state and len(state) == 4 + 6 + 9
    assert set(state.arrays) == set(state) and type(state.arrays) is dict  # what travels over a wire
    with pytest.raises(TypeError):
        state["eef_pos"] = np.ones(3)  # type: ignore[index]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"eef_pos": None}, "missing 'eef_pos'"),
        ({"contact/bowl_1": None}, "missing 'contact/bowl_1'"),
        ({"art/cabinet_1/axis": None}, "missing 'art/cabinet_1/axis'"),
        ({"pose/bowl_1": np.zeros(7)}, "unknown key 'pose/bowl_1'"),
        ({"art/cabinet_1/colour": np.zeros(3)}, "unknown key 'art/cabinet_1/colour'"),
        ({"body/bowl_1": np.zeros(3)}, r"'body/bowl_1' has shape \(3,\), expected \(7,\)"),
        ({"shape/bowl_1": np.zeros((3, 5))}, r"'shape/bowl_1' has shape \(3, 5\), expected \(n, 6\)"),
        ({"eef_mat": np.zeros(9)}, r"'eef_mat' has shape \(9,\), expected \(3, 3\)"),
        ({"base_pos": np.array(["a", "b", "c"])}, "'base_pos' is not numeric"),
    ],
)
def test_a_key_unknown_missing_or_misshapen_fails_naming_it(change, message):
    arrays = {**ROBOT, **BOWL, **DRAWER, **change}
    arrays = {key: value for key, value in arrays.items() if value is not None}
    with pytest.raises(PrivilegedStateError, match=f"^privileged state: {message}"):
        PrivilegedState(arrays)


def test_the_wire_refuses_a_simulator_state_that_breaks_the_schema():
    sent = protocol.unpack(protocol.pack(protocol.privileged_to_message(PrivilegedState({**ROBOT, **BOWL}))))
    assert np.array_equal(protocol.privileged_from_message(sent)["parts/bowl_1"], BOWL["parts/bowl_1"])
    with pytest.raises(
        protocol.ProtocolError, match="^langgap/privileged: privileged state: missing 'base_pos', 'contact/plate_1'"
    ):
        protocol.privileged_from_message({"body/plate_1": np.zeros(7)})


def test_a_chunk_longer_than_the_spec_declares_is_refused_not_cut():
    spec = PolicySpec(chunk=2, replan=1)
    assert as_action_chunk(np.zeros((2, 7)), spec).shape == (2, 7)
    with pytest.raises(PolicyOutputError, match="returned a chunk of 3 actions; its spec declares chunk=2"):
        as_action_chunk(np.zeros((3, 7)), spec)
