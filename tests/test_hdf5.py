"""The robomimic/LIBERO HDF5 form of a collection (`langgap export-hdf5`), read back with h5py."""

from __future__ import annotations

import json
import shutil
import sys

import h5py
import numpy as np
import pytest

from langgap.cli.main import main
from langgap.demos.collect import CollectConfig, collect
from langgap.demos.compact import demo_files, load_demo
from langgap.demos.hdf5 import hdf5_path, obs_name, write_hdf5
from langgap.demos.record import Demo, start_episode
from langgap.demos.verify import replay_demo
from langgap.engine.spec import ExecutionOptions
from langgap.sim.env import CAMERAS, EnvOptions, TaskEnv
from langgap.version import code_version
from tests.support.harness import TINY_TASK, run_cli

STOVE_TASK = "spatial/s0/black-bowl-1-on-stove"  # same scene as TINY_TASK, another goal


@pytest.fixture(scope="module")
def exported(tiny_collection, tmp_path_factory):
    """The tiny collection (one task, two demonstrations) exported without images."""
    out = tmp_path_factory.mktemp("hdf5")
    return write_hdf5(tiny_collection, out=out, progress=False).written


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    """One demonstration of each of two tasks of one scene, exported without images."""
    root = tmp_path_factory.mktemp("pair") / "c"
    config = CollectConfig("langgap99", (TINY_TASK, STOVE_TASK), demos=1, seed=7, noise=0.2)
    collect(config, root, ExecutionOptions(workers=0, progress=False))
    return root, write_hdf5(root, out=root / "h5", progress=False).written


@pytest.fixture(scope="module")
def with_images(tmp_path_factory):
    """One demonstration exported with images (rendering both cameras costs ~25 s per demonstration here)."""
    root = tmp_path_factory.mktemp("images") / "c"
    collect(
        CollectConfig("langgap99", (TINY_TASK,), demos=1, seed=7, noise=0.2),
        root,
        ExecutionOptions(workers=0, progress=False),
    )
    return root, write_hdf5(root, out=root / "h5", images=True, workers=0, progress=False).written[0]


def demo_from_hdf5(data, index: int, *, init_only: bool = False) -> Demo:
    """A `Demo` rebuilt from `data/demo_<index>` alone; `init_only` keeps just `init_state` of the states."""
    group = data[f"demo_{index}"]
    states = group.attrs["init_state"][None] if init_only else group["states"][()]
    return Demo(
        task_id=data.attrs["langgap_task_id"],
        instruction=json.loads(data.attrs["problem_info"])["language_instruction"],
        seed=int(group.attrs["seed"]),
        states=states,
        actions=group["actions"][()],
        labels=group["labels"][()],
        robot_states=group["robot_states"][()],
        nearest_init_distance=float(group.attrs["nearest_init_distance"]),
        scene_hash=group.attrs["scene_hash"],
        body_pos=group["body_pos"][()],
        body_quat=group["body_quat"][()],
    )


def test_hdf5_holds_the_compact_demos_in_libero_layout(exported, tiny_collection, catalog):
    demos = [load_demo(p) for p in demo_files(tiny_collection)]
    assert exported == [hdf5_path(exported[0].parent, TINY_TASK)]
    assert exported[0].name == "spatial__s0__black-bowl-1-on-plate_demo.hdf5"
    assert sorted(p.name for p in exported[0].parent.iterdir()) == [exported[0].name]  # no partial file left
    with h5py.File(exported[0], "r") as f:
        data = f["data"]
        info = json.loads(data.attrs["problem_info"])
        assert info == {
            "problem_name": "libero_tabletop_manipulation",
            "domain_name": "robosuite",
            "language_instruction": catalog.get(TINY_TASK).instruction(),
        }
        assert info["language_instruction"] == demos[0].instruction
        assert data.attrs["langgap_task_id"] == TINY_TASK and data.attrs["langgap_catalog"] == "langgap99"
        assert data.attrs["langgap_version"] == code_version()
        assert json.loads(data.attrs["physics"])["mujoco"] == "3.2.3"
        env_args = json.loads(data.attrs["env_args"])
        assert env_args["env_kwargs"]["control_freq"] == 20 and "camera_names" not in env_args["env_kwargs"]
        assert "(:goal" in data.attrs["bddl_file_content"]
        assert json.loads(data.attrs["langgap_collection"])["noise"] == 0.2
        assert data.attrs["num_demos"] == 2 and data.attrs["total"] == sum(d.length for d in demos)
        assert sorted(data) == ["demo_0", "demo_1"] and "image_orientation" not in data.attrs
        for index, demo in enumerate(demos):  # the collection's order
            group = data[f"demo_{index}"]
            assert group.attrs["seed"] == demo.seed and group.attrs["num_samples"] == demo.length
            assert group.attrs["scene_hash"] == demo.scene_hash
            assert group.attrs["nearest_init_distance"] == demo.nearest_init_distance
            np.testing.assert_array_equal(group.attrs["init_state"], demo.states[0])
            for key in ("actions", "labels", "states", "robot_states", "body_pos", "body_quat"):
                np.testing.assert_array_equal(group[key][()], getattr(demo, key), err_msg=key)
                assert group[key].dtype == getattr(demo, key).dtype, key
            expected_done = np.zeros(demo.length, dtype=np.uint8)
            expected_done[-1] = 1
            np.testing.assert_array_equal(group["rewards"][()], expected_done)
            np.testing.assert_array_equal(group["dones"][()], expected_done)
            obs = group["obs"]
            assert set(obs) == {obs_name(k) for k in demo.privileged} and "body__akita_black_bowl_1" in obs
            for key, value in demo.privileged.items():
                assert obs[obs_name(key)].attrs["langgap_key"] == key
                np.testing.assert_array_equal(obs[obs_name(key)][()], value, err_msg=key)
    # The executed actions carry the noise; the labels are the clean commands (the training targets).
    assert np.abs(demos[0].actions[:, :6] - demos[0].labels[:, :6]).max() > 0.05


def test_replaying_hdf5_actions_from_init_state_and_body_placements_succeeds(exported, catalog):
    with h5py.File(exported[0], "r") as f, TaskEnv(catalog.get(TINY_TASK)) as env:
        for index in range(f["data"].attrs["num_demos"]):
            demo = demo_from_hdf5(f["data"], index, init_only=True)
            verdict = replay_demo(env, demo)
            assert verdict.ok, verdict
            # The stored fixture placements are what rebuilds the scene: altered ones are refused.
            demo.body_pos = demo.body_pos + 0.01
            assert "cannot rebuild the scene" in replay_demo(env, demo).error


def test_one_file_per_task_each_with_its_own_instruction(pair, catalog):
    root, paths = pair
    assert paths == [hdf5_path(root / "h5", TINY_TASK), hdf5_path(root / "h5", STOVE_TASK)]
    for path, demo_path in zip(paths, demo_files(root), strict=True):
        demo = load_demo(demo_path)
        with h5py.File(path, "r") as f:
            data = f["data"]
            assert data.attrs["langgap_task_id"] == demo.task_id and sorted(data) == ["demo_0"]
            instruction = json.loads(data.attrs["problem_info"])["language_instruction"]
            assert instruction == catalog.get(demo.task_id).instruction() == demo.instruction
            np.testing.assert_array_equal(data["demo_0/actions"][()], demo.actions)
            assert data.attrs["total"] == demo.length


def test_images_are_upright_renders_of_the_recorded_states(with_images, catalog):
    root, path = with_images
    demo = load_demo(demo_files(root)[0])
    step = demo.length // 2
    with h5py.File(path, "r") as f, TaskEnv(catalog.get(TINY_TASK), EnvOptions(cameras=CAMERAS)) as env:
        data = f["data"]
        assert "rotated 180 degrees" in data.attrs["image_orientation"]
        kwargs = json.loads(data.attrs["env_args"])["env_kwargs"]
        assert kwargs["camera_names"] == list(CAMERAS) and kwargs["camera_heights"] == 256
        obs = data["demo_0/obs"]
        for key in ("agentview_rgb", "eye_in_hand_rgb"):
            assert obs[key].shape == (demo.length, 256, 256, 3) and obs[key].dtype == np.uint8
            assert obs[key].compression == "gzip"
        # A frame of each camera equals a fresh upright render of the recorded state (gzip is lossless).
        start_episode(env, demo)
        env.set_sim_state(demo.states[step])
        for camera, key in (("agentview", "agentview_rgb"), ("robot0_eye_in_hand", "eye_in_hand_rgb")):
            stored, expected = obs[key][step], env.render(camera)
            np.testing.assert_array_equal(stored, expected, err_msg=camera)
            assert not np.array_equal(stored, expected[::-1, ::-1]), camera  # an upside-down frame would differ


def test_cli_refuses_to_overwrite_and_rejects_what_is_not_a_collection(tiny_collection, tmp_path):
    root = tmp_path / "c"
    shutil.copytree(tiny_collection, root)
    first = run_cli("export-hdf5", str(root), "--no-progress")
    assert first.returncode == 0, first.stderr
    path = hdf5_path(root / "hdf5", TINY_TASK)
    assert path.is_file()
    again = run_cli("export-hdf5", str(root), "--no-progress")
    assert again.returncode == 2 and len(again.stderr.splitlines()) == 1
    assert again.stderr.startswith(f"error: {path} exists already") and "--force" in again.stderr
    assert "--resume" in again.stderr
    forced = run_cli("export-hdf5", str(root), "--no-progress", "--force", "--out", str(root / "hdf5"))
    assert forced.returncode == 0, forced.stderr
    (tmp_path / "empty").mkdir()
    for not_a_collection in (tmp_path / "empty", tmp_path / "missing"):
        bad = run_cli("export-hdf5", str(not_a_collection))
        assert bad.returncode == 2 and len(bad.stderr.splitlines()) == 1
        assert bad.stderr.startswith(f"error: {not_a_collection} is not a demonstration collection")
    (tmp_path / "broken").mkdir()
    (tmp_path / "broken" / "collection.json").write_text("{")
    broken = run_cli("export-hdf5", str(tmp_path / "broken"))
    assert broken.returncode == 2 and len(broken.stderr.splitlines()) == 1
    assert broken.stderr.startswith(f"error: cannot read {tmp_path / 'broken' / 'collection.json'}")
    (tmp_path / "broken" / "collection.json").write_text("{}")  # JSON, but no collection's manifest
    empty = run_cli("export-hdf5", str(tmp_path / "broken"))
    assert empty.returncode == 2 and len(empty.stderr.splitlines()) == 1
    assert empty.stderr.startswith(f"error: {tmp_path / 'broken' / 'collection.json'} is not a collection's manifest")


def test_resume_keeps_the_finished_files_and_writes_the_rest(pair, tmp_path):
    root = tmp_path / "c"
    shutil.copytree(pair[0], root)
    out = root / "h5"
    finished, missing = hdf5_path(out, TINY_TASK), hdf5_path(out, STOVE_TASK)
    expected = {path: first_actions(path) for path in (finished, missing)}
    missing.unlink()  # an export killed after its first task
    inode = finished.stat().st_ino
    resumed = run_cli("export-hdf5", str(root), "--out", str(out), "--no-progress", "--resume")
    assert resumed.returncode == 0, resumed.stderr
    assert resumed.stdout.strip() == f"wrote 1 HDF5 file(s) to {out} (kept 1 written before)"
    assert finished.stat().st_ino == inode  # kept, not written again
    for path, actions in expected.items():
        np.testing.assert_array_equal(first_actions(path), actions)
    assert sorted(out.iterdir()) == [finished, missing]
    again = run_cli("export-hdf5", str(root), "--out", str(out), "--no-progress", "--resume")
    assert again.returncode == 0 and again.stdout.startswith("wrote 0 HDF5 file(s)"), again.stderr


def first_actions(path) -> np.ndarray:
    with h5py.File(path, "r") as f:
        return f["data/demo_0/actions"][()]


def test_resume_refuses_files_of_other_settings_or_another_collection(pair, tmp_path):
    root = tmp_path / "c"
    shutil.copytree(pair[0], root)
    out = root / "h5"
    path = hdf5_path(out, TINY_TASK)
    before = path.read_bytes()

    def refused(*args: str) -> str:
        result = run_cli("export-hdf5", str(root), "--out", str(out), "--no-progress", *args)
        assert result.returncode == 2 and len(result.stderr.splitlines()) == 1, result.stderr
        assert path.read_bytes() == before  # nothing was written
        return result.stderr

    assert refused("--resume", "--images", "--image-size", "64").startswith(
        f"error: cannot resume: {path} has no images, this export asks for 64 px images; pass --force"
    )
    assert refused("--resume", "--force").startswith("error: --force replaces the existing files and --resume")
    other = hdf5_path(out, STOVE_TASK)
    other.write_bytes(b"not hdf5")
    assert refused("--resume").startswith(f"error: cannot resume: {other} is not a LangGap HDF5 export")
    manifest = json.loads((root / "collection.json").read_text())
    (root / "collection.json").write_text(json.dumps({**manifest, "noise": 0.1}))
    assert refused("--resume").startswith(f"error: cannot resume: {path} was exported from another collection")


def test_a_failed_export_leaves_no_file_and_keeps_the_previous_one(tiny_collection, tmp_path, capsys):
    root = tmp_path / "c"
    shutil.copytree(tiny_collection, root)
    out = tmp_path / "out"
    # The second demonstration is unreadable: the export fails after writing the first into the file.
    demo_files(root)[1].write_bytes(b"not an npz")
    assert main(["export-hdf5", str(root), "--out", str(out), "--no-progress"]) == 2
    assert "cannot read demonstration" in capsys.readouterr().err
    assert list(out.iterdir()) == []
    # With --force, a failure leaves the complete previous file in place.
    good = write_hdf5(tiny_collection, out=out, progress=False).written[0]
    before = good.read_bytes()
    assert main(["export-hdf5", str(root), "--out", str(out), "--no-progress", "--force"]) == 2
    assert sorted(out.iterdir()) == [good] and good.read_bytes() == before


def test_missing_h5py_is_a_dependency_error(tiny_collection, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "h5py", None)  # `import h5py` now raises ImportError
    assert main(["export-hdf5", str(tiny_collection), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: the HDF5 export needs h5py") and "langgap[hdf5]" in err
