"""small-vla: images exported at the policy's size and read into one array, a tiny training run, determinism, the
checkpoint round trip, what the policy declares it sees (a VLA's inputs, nothing privileged), and `langgap eval` in a
worker."""

from __future__ import annotations

import dataclasses
import json
import shutil

import h5py
import numpy as np
import pytest

from tests.support.harness import TINY_TASK, run_cli, store_rows
from tests.support.small_checkpoints import trained_checkpoint

torch = pytest.importorskip("torch", reason="small-vla needs PyTorch (pip install 'langgap[train]')")

SIZE = 32  # pixels: the smallest images that keep the tests quick (rendering costs the same at any size here)
OTHER = "pick up the ramekin and place it on the stove"


@pytest.fixture(scope="module")
def collection(tiny_collection, tmp_path_factory):
    """The tiny collection (one task, two demonstrations) with its images exported at SIZE px, by the CLI."""
    root = tmp_path_factory.mktemp("vla") / "demos"
    shutil.copytree(tiny_collection, root)
    result = run_cli("export-hdf5", str(root), "--images", "--image-size", str(SIZE), "--workers", "0", "--no-progress")
    assert result.returncode == 0, result.stderr
    return root


@pytest.fixture(scope="module")
def checkpoint(collection, tmp_path_factory):
    out = tmp_path_factory.mktemp("vla-ckpt") / "tiny.safetensors"
    return trained_checkpoint("small-vla", collection, out, steps=8, batch_size=16)


def test_images_are_exported_at_the_asked_size(collection):
    (path,) = (collection / "hdf5").glob("*_demo.hdf5")
    with h5py.File(path, "r") as f:
        data = f["data"]
        env_kwargs = json.loads(data.attrs["env_args"])["env_kwargs"]
        assert (env_kwargs["camera_heights"], env_kwargs["camera_widths"]) == (SIZE, SIZE)
        for name in data:
            group = data[name]
            for key in ("agentview_rgb", "eye_in_hand_rgb"):
                images = group["obs"][key]
                assert images.shape == (group.attrs["num_samples"], SIZE, SIZE, 3) and images.dtype == np.uint8
                assert images[()].std() > 10  # a picture, not a blank


def test_training_reads_the_images_into_one_array_held_once(collection):
    from langgap.training.image_demos import load_image_demos

    loaded = load_image_demos([collection])
    (path,) = (collection / "hdf5").glob("*_demo.hdf5")
    with h5py.File(path, "r") as f:
        expected = [
            np.stack([f["data"][name]["obs"][key][()] for key in ("agentview_rgb", "eye_in_hand_rgb")], axis=1)
            for name in sorted(f["data"], key=lambda n: int(n.split("_")[1]))
        ]
    np.testing.assert_array_equal(loaded.frames, np.concatenate(expected))  # in order, agentview first
    for demo, images in zip(loaded.demos, expected, strict=True):
        np.testing.assert_array_equal(demo.images, images)
        assert np.shares_memory(demo.images, loaded.frames)  # a view: every frame is in memory once


def test_training_is_deterministic_and_checkpoint_round_trips(collection, checkpoint, tmp_path):
    from langgap.policies.small_vla.model import load_checkpoint
    from langgap.policies.text import catalog_vocabulary
    from langgap.training.loop import TrainConfig
    from langgap.training.train_small_vla import train

    config = TrainConfig(data=(str(collection),), steps=8, batch_size=16, threads=1)
    facts = train(config, tmp_path / "again.safetensors", log=None)
    first, vocab, info = load_checkpoint(checkpoint)
    second, _, _ = load_checkpoint(tmp_path / "again.safetensors")
    for (name, a), (_, b) in zip(first.state_dict().items(), second.state_dict().items(), strict=True):
        assert torch.equal(a, b), name
    assert info["final_loss"] == facts["final_loss"] and info["tasks"] == [TINY_TASK]
    assert info["image_size"] == SIZE and first.config.image_size == SIZE
    assert vocab.tokens == catalog_vocabulary().tokens  # fixed before training, not the two demonstrations' words
    # Another seed trains another model: the seed reaches the weights.
    other = train(dataclasses.replace(config, seed=1), tmp_path / "seed1.safetensors", log=None)
    assert other["final_loss"] != facts["final_loss"]


def test_policy_sees_what_a_vla_sees_and_reads_the_instruction(checkpoint, catalog):
    from langgap.engine.context import task_context
    from langgap.engine.rollout import env_options_for
    from langgap.policies import make_policy
    from langgap.sim.env import CAMERAS, TaskEnv

    policy = make_policy("small-vla", {"checkpoint": str(checkpoint), "replan": "3"})
    # Exactly a VLA's inputs: both cameras at the checkpoint's size, the state, the sentence; never the
    # simulator's state nor the goal.
    spec = policy.spec
    assert (spec.cameras, spec.image_size, spec.sees_state, spec.sees_goal) == (CAMERAS, SIZE, False, False)
    assert (spec.chunk, spec.replan, spec.reads_instruction) == (8, 3, True)
    task = catalog.get(TINY_TASK)
    with TaskEnv(task, env_options_for(policy)) as env:
        env.reset(0)
        env.settle()
        observation = env.observe()
    assert observation.privileged is None and observation.images[CAMERAS[0]].shape == (SIZE, SIZE, 3)
    outputs = []
    for instruction in (None, None, OTHER):
        policy.reset(task_context(task, catalog, init_index=0, seed=0, instruction=instruction))
        outputs.append(policy.act(observation))
    assert outputs[0].shape == (8, 7) and np.all(np.abs(outputs[0]) <= 1) and set(outputs[0][:, 6]) <= {-1.0, 1.0}
    np.testing.assert_array_equal(outputs[0], outputs[1])  # deterministic
    assert not np.array_equal(outputs[0], outputs[2])  # another sentence, another action
    policy.reset(task_context(task, catalog, init_index=0, seed=0))
    np.testing.assert_array_equal(policy.act(dataclasses.replace(observation, instruction=OTHER)), outputs[2])
    # The pixels reach the actions: another picture, another action.
    dark = dataclasses.replace(observation, images={c: image // 4 for c, image in observation.images.items()})
    assert not np.array_equal(policy.act(dark), outputs[0])


def test_eval_runs_small_vla_in_a_worker(checkpoint, tmp_path):
    run = tmp_path / "run"
    result = run_cli(
        "eval", "--policy", "small-vla", "--policy-arg", f"checkpoint={checkpoint}", "--tasks", TINY_TASK,
        "--episodes", "1", "--run", str(run), "--workers", "1", "--no-progress", "--quiet",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    (row,) = store_rows(run)
    assert row["status"] == "done" and row["policy"] == "small-vla" and row["steps"] > 0
    assert (row["sees_state"], row["sees_goal"], row["image_size"]) == (0, 0, SIZE)
    assert json.loads(row["cameras"]) == ["agentview", "robot0_eye_in_hand"]
    report = run_cli("report", str(run), "--format", "md").stdout
    assert f"agentview, robot0_eye_in_hand at {SIZE} px" in report
    assert "reads simulator state" not in report and "scripted reference" not in report


def test_what_cannot_be_trained_or_loaded_is_a_clear_error(tiny_collection, collection, checkpoint, tmp_path):
    from langgap.policies import make_policy
    from langgap.policies.checkpoints import CheckpointError

    without = run_cli("train", "small-vla", "--data", str(tiny_collection), "--out", str(tmp_path / "x.safetensors"))
    assert without.returncode != 0
    assert f"error: {tiny_collection} has no demonstrations with images: run `langgap export-hdf5" in without.stderr
    config = tmp_path / "model.yaml"
    config.write_text("model:\n  image_size: 64\n")
    argv = ("train", "small-vla", "--data", str(collection), "--config", str(config), "--steps", "1")
    mismatch = run_cli(*argv, "--out", str(tmp_path / "y.safetensors"))
    assert (
        mismatch.returncode != 0 and "the model takes 64 px images and the demonstrations hold 32 px" in mismatch.stderr
    )
    assert not (tmp_path / "x.safetensors").exists() and not (tmp_path / "y.safetensors").exists()
    with pytest.raises(CheckpointError, match="small-vla needs checkpoint=PATH"):
        make_policy("small-vla", {})
    with pytest.raises(CheckpointError, match="no small-vla checkpoint"):
        make_policy("small-vla", {"checkpoint": str(tmp_path / "none.safetensors")})
    bc = tmp_path / "bc.safetensors"
    assert (
        run_cli("train", "small-bc", "--data", str(tiny_collection), "--out", str(bc), "--steps", "1").returncode == 0
    )
    with pytest.raises(CheckpointError, match="is not a small-vla checkpoint"):
        make_policy("small-vla", {"checkpoint": str(bc)})
    refused = run_cli("export-hdf5", str(collection), "--image-size", "64")
    assert (
        refused.returncode == 2 and "error: --image-size is about rendered images: it needs --images" in refused.stderr
    )
