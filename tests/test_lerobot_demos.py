"""Demonstrations as a LeRobot v3 dataset (schema and image orientation of `lerobot/libero`), and the paper's
experiments as `lerobot-train` configurations. Runs in the LeRobot environment; skipped elsewhere."""

from __future__ import annotations

import contextlib
import io
import re
import shutil

import numpy as np
import pytest

pytest.importorskip("lerobot", reason="LeRobot lives in .venv-lerobot (created by ./setup.sh)")

from lerobot.datasets.lerobot_dataset import LeRobotDataset  # noqa: E402

from langgap.demos.compact import demo_files, load_demo  # noqa: E402
from langgap.demos.export import CAMERA_FEATURES, FPS  # noqa: E402
from langgap.demos.record import start_episode  # noqa: E402
from langgap.sim.env import CAMERAS, EnvOptions, TaskEnv  # noqa: E402
from langgap.training.lerobot_train import (  # noqa: E402
    EXPERIMENTS,
    POLICIES,
    load_experiment,
    load_recipe,
    train_command,
    train_options,
)
from tests.support.harness import TINY_TASK  # noqa: E402
from tests.test_lerobot import lerobot_libero_batch  # noqa: E402


@pytest.fixture(scope="module")
def exported(tiny_collection, tmp_path_factory):
    """`langgap export-lerobot DIR --workers 0 --no-progress` on a copy of the tiny collection: the copy, the
    dataset and what the command wrote to stderr."""
    from langgap.cli.main import main

    root = tmp_path_factory.mktemp("export") / "tiny"
    shutil.copytree(tiny_collection, root)
    with contextlib.redirect_stderr(io.StringIO()) as err:
        assert main(["export-lerobot", str(root), "--workers", "0", "--no-progress"]) == 0
    return root, LeRobotDataset("local/langgap_demos", root=root / "lerobot", video_backend="pyav"), err.getvalue()


@pytest.fixture(scope="module")
def dataset(exported):
    root, ds, _ = exported
    return root, ds


SMALL = 64


@pytest.fixture(scope="module")
def small_dataset(tiny_collection, tmp_path_factory):
    """`langgap export-lerobot DIR --image-size 64` on a copy of the tiny collection."""
    from langgap.cli.main import main

    root = tmp_path_factory.mktemp("export-small") / "tiny"
    shutil.copytree(tiny_collection, root)
    command = ["export-lerobot", str(root), "--workers", "0", "--no-progress", "--image-size", str(SMALL)]
    with contextlib.redirect_stderr(io.StringIO()):
        assert main(command) == 0
    return root, LeRobotDataset("local/langgap_demos", root=root / "lerobot", video_backend="pyav")


def test_dataset_has_the_lerobot_libero_schema(dataset, catalog):
    root, ds = dataset
    demos = [load_demo(p) for p in demo_files(root)]
    assert ds.fps == FPS == 10 and ds.num_episodes == 2 and ds.num_frames == sum(d.length for d in demos)
    features = ds.meta.features
    for key in CAMERA_FEATURES.values():
        assert features[key]["dtype"] == "video" and tuple(features[key]["shape"]) == (256, 256, 3)
    assert tuple(features["observation.state"]["shape"]) == (8,) and tuple(features["action"]["shape"]) == (7,)
    frame = ds[demos[0].length - 1]  # the last frame of the first episode
    assert frame["task"] == catalog.get(TINY_TASK).instruction()
    np.testing.assert_allclose(frame["action"].numpy(), demos[0].labels[-1], atol=1e-6)
    np.testing.assert_allclose(frame["observation.state"].numpy(), demos[0].robot_states[-1], atol=1e-6)
    assert int(ds[demos[0].length]["episode_index"]) == 1


def test_export_lerobot_cli_writes_the_dataset_it_is_told(exported, tiny_collection, tmp_path, capsys):
    """`--workers 2` renders in worker processes the dataset `--workers 0` renders here (`exported`);
    `--no-progress` hides the progress bar the default shows."""
    from langgap.cli.main import main

    _, here, quiet = exported
    there = tmp_path / "there"
    shutil.copytree(tiny_collection, there)
    assert main(["export-lerobot", str(there), "--workers", "2"]) == 0
    shown = capsys.readouterr().err
    ours = re.compile(r"\d+/\d+ \[[^\]]*demo")  # our bar counts demos (LeRobot's own `Map:` bars show anyway)
    assert not ours.search(quiet) and ours.search(shown)
    datasets = [here, LeRobotDataset("local/langgap_demos", root=there / "lerobot", video_backend="pyav")]
    assert len(datasets[0]) == len(datasets[1]) > 0
    for i in (0, len(datasets[0]) - 1):
        first, second = datasets[0][i], datasets[1][i]
        assert all(
            np.array_equal(first[k], second[k]) for k in ("action", "observation.state", *CAMERA_FEATURES.values())
        )


@pytest.mark.parametrize(("exported_at", "size"), [("dataset", 256), ("small_dataset", SMALL)])
def test_frames_are_oriented_as_lerobots_libero_processor_makes_them(exported_at, size, catalog, request):
    """The frames are the upright render at the dataset's size: 256 by default, `--image-size`'s otherwise."""
    root, ds = request.getfixturevalue(exported_at)
    assert all(tuple(ds.meta.features[key]["shape"]) == (size, size, 3) for key in CAMERA_FEATURES.values())
    demo = load_demo(demo_files(root)[0])
    with TaskEnv(catalog.get(TINY_TASK), EnvOptions(cameras=CAMERAS, image_size=size)) as env:
        start_episode(env, demo)
        expected = lerobot_libero_batch(env, demo.instruction)
    frame = ds[0]
    for key in CAMERA_FEATURES.values():
        ours, theirs = frame[key], expected[key][0]
        error = (ours - theirs).abs().mean().item()
        assert error < 0.02, key  # video compression only
        assert (ours - theirs.flip(-1)).abs().mean().item() > 3 * error  # a mirror image would be caught
        assert (ours - theirs.flip(-2)).abs().mean().item() > 3 * error  # so would an upside-down one


@pytest.mark.parametrize("name", EXPERIMENTS)
@pytest.mark.parametrize("policy", POLICIES)
def test_experiment_commands_parse_with_lerobots_own_config(name, policy):
    """Every experiment, policy and tuning makes a command LeRobot's own parser reads back as written: LoRA's rank,
    alpha and targets where the tuning uses LoRA, the experiment's steps, the dataset."""
    import draccus
    import lerobot.policies  # noqa: F401  (registers the policy types the parser chooses from)
    from lerobot.configs.train import TrainPipelineConfig

    experiment, recipe = load_experiment(name), load_recipe(policy)
    for tuning in recipe.tunings.values():
        options = train_options(experiment, recipe, tuning=tuning.name)
        command = train_command(options, dataset_root="/d", repo_id="local/x", output_dir="/o", job_name=name)
        config = draccus.parse(TrainPipelineConfig, args=command[1:])
        assert config.policy.type == recipe.lerobot["policy.type"] and config.steps == experiment.paper["steps"]
        assert str(config.dataset.root) == "/d" and config.dataset.repo_id == "local/x" and config.batch_size == 8
        if "peft.method_type" in tuning.options:
            assert config.peft.method_type == "LORA" and config.peft.r == experiment.paper["lora_rank"]
            assert config.peft.target_modules == tuning.options["peft.target_modules"]
            expected_alpha = experiment.lora_rank if tuning.options["peft.lora_alpha"] == "rank" else 8
            assert float(config.peft.lora_alpha) == expected_alpha
        else:
            assert config.peft is None
