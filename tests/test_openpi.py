"""The `openpi` adapter and `langgap serve`, against real server processes on 127.0.0.1 and real LIBERO episodes."""

from __future__ import annotations

import dataclasses
import re
import time

import numpy as np
import pytest
from openpi_client import image_tools, msgpack_numpy

from langgap.engine.context import task_context
from langgap.engine.rollout import env_options_for, run_episode
from langgap.errors import PolicyServerError
from langgap.imaging import resize_with_pad
from langgap.policies import make_policy, protocol
from langgap.policies.base import PolicyOutputError
from langgap.policies.openpi import OpenpiPolicy
from langgap.sim.env import Observation, TaskEnv
from tests.support.servers import free_port, helper_server, langgap_serve, running, subprocess_env

TASK_ID = "spatial/s0/black-bowl-1-on-plate"
STEPS = 12  # short episodes: the plumbing, not the policy, is under test


def short_task(catalog, task_id: str = TASK_ID):
    return dataclasses.replace(catalog.get(task_id), max_steps=STEPS)


def episodes(policy, catalog, plan, task_id: str = TASK_ID):
    """Run (init_index, seed) episodes; return per episode (success, steps, calls, executed actions)."""
    task = short_task(catalog, task_id)
    outcomes = []
    with TaskEnv(task, env_options_for(policy)) as env:
        for init_index, seed in plan:
            actions: list[np.ndarray] = []
            context = task_context(task, catalog, init_index=init_index, seed=seed)
            result = run_episode(env, policy, context, on_step=lambda _env, _i, action, out=actions: out.append(action))
            outcomes.append((result.success, result.steps, result.policy_calls, np.array(actions)))
    return outcomes


def assert_same_episodes(remote, local):
    assert len(remote) == len(local)
    for (*r_outcome, r_actions), (*l_outcome, l_actions) in zip(remote, local, strict=True):
        assert r_outcome == l_outcome
        np.testing.assert_array_equal(r_actions, l_actions)


# -- wire format and preprocessing, pinned against the openpi-client package -----------------------


def test_codec_is_openpi_wire_format():
    message = {
        "observation/image": np.arange(2 * 3 * 3, dtype=np.uint8).reshape(2, 3, 3),
        "observation/state": np.linspace(0, 1, 8, dtype=np.float32),
        "nested": {"x": np.float32(2.5), "ints": np.array([[1, 2]], dtype=np.int64), "s": "text"},
        "prompt": "put the bowl on the plate",
    }
    for decoded in (msgpack_numpy.unpackb(protocol.pack(message)), protocol.unpack(msgpack_numpy.packb(message))):
        assert decoded["prompt"] == message["prompt"] and decoded["nested"]["s"] == "text"
        for key in ("observation/image", "observation/state"):
            assert decoded[key].dtype == message[key].dtype
            np.testing.assert_array_equal(decoded[key], message[key])
        np.testing.assert_array_equal(decoded["nested"]["ints"], message["nested"]["ints"])
        assert decoded["nested"]["x"] == 2.5 and isinstance(decoded["nested"]["x"], np.float32)
    with pytest.raises(protocol.ProtocolError):
        protocol.unpack(b"\xc1 not msgpack")


@pytest.mark.parametrize("shape", [(256, 256, 3), (360, 480, 3), (100, 37, 3), (224, 224, 3)])
def test_resize_with_pad_equals_openpi(shape):
    image = np.random.default_rng(0).integers(0, 256, size=shape, dtype=np.uint8)
    np.testing.assert_array_equal(resize_with_pad(image, 224, 224), image_tools.resize_with_pad(image, 224, 224))


# -- a plain openpi server (openpi-server package): what a real openpi model server receives --------


def test_plain_openpi_server_receives_openpi_libero_observations(catalog, tmp_path):
    port = free_port()
    env = subprocess_env(RECORD_DIR=str(tmp_path))
    with running(helper_server("openpi-record", port), port, env=env):
        policy = OpenpiPolicy(port=port)
        assert policy.served is None and policy.spec.image_size == 256 and policy.spec.replan == 5
        ((success, steps, calls, actions),) = episodes(policy, catalog, [(3, 7)])
        policy.close()
    assert (success, steps, calls) == (False, STEPS, -(-STEPS // 5))
    np.testing.assert_array_equal(actions, np.tile([0, 0, 0, 0, 0, 0, -1.0], (STEPS, 1)))

    first = dict(np.load(tmp_path / "0000.npz"))
    assert sorted(first) == ["observation/image", "observation/state", "observation/wrist_image", "prompt"]
    task = short_task(catalog)
    assert str(first["prompt"]) == task.instruction()
    assert first["observation/state"].shape == (8,)
    # Orientation: exactly openpi's LIBERO preprocessing of the raw (upside-down) render at t0, taken where
    # robosuite samples (tests/test_parity.py compares whole episodes with openpi's example loop).
    with TaskEnv(task, env_options_for(policy)) as sim_env:
        sim_env.reset(3, seed=7)
        sim_env.settle(capture=tuple(protocol.CAMERA_KEYS))
        np.testing.assert_array_equal(first["observation/state"], sim_env.observe(()).state)
        for camera, key in protocol.CAMERA_KEYS.items():
            raw = np.ascontiguousarray(sim_env.render(camera)[::-1, ::-1])  # as LIBERO renders it
            expected = image_tools.resize_with_pad(np.ascontiguousarray(raw[::-1, ::-1]), 224, 224)
            assert first[key].dtype == np.uint8 and first[key].shape == (224, 224, 3)
            np.testing.assert_array_equal(first[key], expected)
            assert not np.array_equal(first[key], image_tools.resize_with_pad(raw, 224, 224))


# -- LangGap policies served remotely behave exactly as in process ---------------------------------


PLAN = [(0, 0), (2, 5)]


@pytest.mark.parametrize("name,pairs", [("random", ("chunk=3",)), ("noop", ()), ("oracle", ())])
def test_openpi_server_package_hosts_langgap_policy(catalog, name, pairs):
    port = free_port()
    with running(helper_server("openpi-langgap", port, name, *pairs), port):
        remote = OpenpiPolicy(port=port)
        assert remote.served == make_policy(name, dict(p.split("=") for p in pairs)).spec
        remote_outcomes = episodes(remote, catalog, PLAN)
        remote.close()
    assert_same_episodes(remote_outcomes, episodes(make_policy(name, dict(p.split("=") for p in pairs)), catalog, PLAN))


def test_langgap_serve_matches_in_process_with_images_and_privileged_state(catalog):
    port = free_port()
    with running(langgap_serve(port, "tests.support.probe_policy:ProbePolicy"), port):
        remote = OpenpiPolicy(port=port)
        assert remote.spec.cameras and remote.spec.sees_state and remote.spec.sees_goal and remote.spec.image_size == 64
        remote_outcomes = episodes(remote, catalog, PLAN)
        remote.close()
    assert_same_episodes(
        remote_outcomes, episodes(make_policy("tests.support.probe_policy:ProbePolicy"), catalog, PLAN)
    )


def test_langgap_serve_gives_each_connection_its_own_policy(catalog):
    port = free_port()
    with running(langgap_serve(port, "random", "chunk=2"), port):
        first, second = OpenpiPolicy(port=port), OpenpiPolicy(port=port)
        # Interleaved episodes on two connections must not disturb each other's random streams.
        task = short_task(catalog)
        observation = Observation(state=np.zeros(8, dtype=np.float32))
        first.reset(task_context(task, catalog, init_index=0, seed=1))
        second.reset(task_context(task, catalog, init_index=0, seed=2))
        interleaved = [first.act(observation), second.act(observation), first.act(observation)]
        first.close()
        second.close()
    local = make_policy("random", {"chunk": "2"})
    local.reset(task_context(task, catalog, init_index=0, seed=1))
    np.testing.assert_array_equal(interleaved[0], local.act(observation))
    np.testing.assert_array_equal(interleaved[2], local.act(observation))


# -- failures: a clear PolicyServerError, within the timeout ---------------------------------------


def _started_episode(catalog, port: int, **kwargs) -> tuple[OpenpiPolicy, Observation]:
    policy = OpenpiPolicy(port=port, **kwargs)
    policy.reset(task_context(short_task(catalog), catalog, init_index=0, seed=0))
    return policy, Observation(state=np.zeros(8, dtype=np.float32))


def test_no_server_fails_within_connect_timeout():
    start = time.monotonic()
    with pytest.raises(PolicyServerError, match="no policy server"):
        OpenpiPolicy(port=free_port(), connect_timeout=1.0)
    assert time.monotonic() - start < 3


def test_a_long_wait_for_the_server_says_so_with_the_time_left(capsys):
    """The run's bar stands at 0 while the policy waits for its server: the wait has its own lines."""
    port = free_port()
    with pytest.raises(PolicyServerError, match="no policy server"):
        OpenpiPolicy(port=port, connect_timeout=3.0)
    notes = [line for line in capsys.readouterr().err.splitlines() if line.startswith("note: waiting")]
    assert len(notes) == 1 and f"policy server at 127.0.0.1:{port} (2 s so far" in notes[0]
    assert re.search(r"giving up in [01] s; /healthz: ConnectionRefusedError", notes[0])


def test_server_killed_mid_episode(catalog):
    port = free_port()
    with running(langgap_serve(port, "random"), port) as process:
        policy, observation = _started_episode(catalog, port, timeout=5.0, connect_timeout=1.0)
        assert policy.act(observation).shape == (1, 7)
        process.kill()
        process.wait(timeout=10)
        start = time.monotonic()
        with pytest.raises(PolicyServerError, match="closed the connection"):
            policy.act(observation)
        assert time.monotonic() - start < 5
        # The harness's retry: the next reset reconnects, and fails within the connect timeout.
        with pytest.raises(PolicyServerError, match="no policy server"):
            policy.reset(task_context(short_task(catalog), catalog, init_index=0, seed=0))
        assert time.monotonic() - start < 8


def test_server_that_never_answers_times_out(catalog):
    port = free_port()
    with running(langgap_serve(port, "tests.support.policies:HangingPolicy"), port):
        policy, observation = _started_episode(catalog, port, timeout=1.0)
        start = time.monotonic()
        with pytest.raises(PolicyServerError, match="sent no reply within 1 s"):
            policy.act(observation)
        assert time.monotonic() - start < 3
        with pytest.raises(PolicyServerError, match="not connected"):
            policy.act(observation)
        policy.close()


@pytest.mark.parametrize(
    "mode,message", [("garbage", "not a msgpack message"), ("bad-actions", "'actions' is not a 1-D or 2-D numeric")]
)
def test_malformed_reply_raises(catalog, mode, message):
    port = free_port()
    with running(helper_server(mode, port), port):
        policy, observation = _started_episode(catalog, port, timeout=5.0)
        with pytest.raises(PolicyServerError, match=message):
            policy.act(observation)
        policy.close()


def test_nan_from_a_served_policy_is_a_policy_failure_as_in_process(catalog):
    port = free_port()
    with running(langgap_serve(port, "tests.support.policies:NanPolicy"), port):
        remote = OpenpiPolicy(port=port, timeout=5.0)
        with pytest.raises(PolicyOutputError, match="non-finite"):
            episodes(remote, catalog, [(0, 0)])
        remote.close()
    with pytest.raises(PolicyOutputError, match="non-finite"):
        episodes(make_policy("tests.support.policies:NanPolicy"), catalog, [(0, 0)])


def test_policy_error_on_server_is_reported_in_one_line(catalog):
    port = free_port()
    with running(langgap_serve(port, "tests.support.policies:RaisingPolicy"), port):
        policy, observation = _started_episode(catalog, port, timeout=5.0)
        with pytest.raises(PolicyServerError, match="failed: RuntimeError: model exploded") as raised:
            policy.act(observation)
        assert "\n" not in str(raised.value)
        policy.close()


def test_langgap_server_refuses_a_plain_openpi_client():
    from websockets.sync.client import connect

    port = free_port()
    with running(langgap_serve(port, "noop"), port):
        with connect(f"ws://127.0.0.1:{port}", proxy=None) as ws:
            assert "langgap" in protocol.unpack(ws.recv(timeout=5))
            ws.send(protocol.pack({"observation/state": np.zeros(8), "prompt": "x"}))
            error = ws.recv(timeout=5)
        assert isinstance(error, str) and "needs LangGap's `openpi` client" in error
