"""`langgap experiment run` executed end to end at tiny size with LeRobot's own policies, offline: collect →
export → merge (LeRobot's aggregation) → lerobot-train → checkpoint → `langgap eval` → report, with a tiny ACT
and a tiny SmolVLA built here; and the LoRA targets of the π0 / π0.5 recipes against the real models' modules.
Runs in the LeRobot environment; skipped elsewhere."""

from __future__ import annotations

import json
import re
import shutil

import numpy as np
import pytest

pytest.importorskip("lerobot", reason="LeRobot lives in .venv-lerobot (created by ./setup.sh)")

from langgap.demos.compact import demo_files, load_demo  # noqa: E402
from langgap.demos.export import FPS  # noqa: E402
from langgap.training.lerobot_train import load_recipe  # noqa: E402
from tests.support.harness import TINY_TASK, run_cli, store_rows  # noqa: E402

EXTENDED = "spatial/s0/black-bowl-1-on-stove"  # an extended task of TINY_TASK's scene
# An experiment of the paper's form at the smallest size: LIBERO's original task and one extended task of its
# scene, two demonstrations each (the originals group is the tiny collection), one evaluation episode.
TINY_EXPERIMENT = f"""
name: tiny
title: the original task of spatial/s0 and one extended task, two demonstrations each
paper: {{tasks: "1+1 ext", demos: 4, lora_rank: 8, steps: 2, eval_tasks: "1", episodes: 1, baseline: 0.0, result: 0.0}}
train:
  - {{tasks: "{TINY_TASK}", demos: 2}}
  - {{tasks: "{EXTENDED}", demos: 2}}
eval:
  trained: "{EXTENDED}"
episodes: 1
steps: 2
lora_rank: 8
"""
# The tiny collection's settings (tests.support.harness.tiny_config), so its group counts as collected.
RUN = ("--tiny", "--device", "cpu", "--workers", "0", "--seed", "7", "--noise", "0.2")
SMALL_BATCH = ("--set", "batch_size=2", "--set", "num_workers=0")


def _experiment(tmp_path, tiny_collection, name: str):
    """An experiment file and an output directory whose first group is a copy of the tiny collection."""
    spec = tmp_path / "tiny.yaml"
    spec.write_text(TINY_EXPERIMENT)
    out = tmp_path / name
    shutil.copytree(tiny_collection, out / "data" / "group0")
    return spec, out


@pytest.fixture(scope="module")
def act_run(tiny_collection, tmp_path_factory):
    """The tiny experiment run with a tiny ACT: its output directory and what the command printed."""
    spec, out = _experiment(tmp_path_factory.mktemp("experiment"), tiny_collection, "act")
    planned = run_cli("experiment", "run", str(spec), "--policy", "act", "--out", str(out), *RUN, "--dry-run")
    assert planned.returncode == 0 and sorted(p.name for p in out.iterdir()) == ["data"]  # a plan writes nothing
    result = run_cli("experiment", "run", str(spec), "--policy", "act", "--out", str(out), *RUN, *SMALL_BATCH)
    assert result.returncode == 0, result.stderr[-3000:]
    return spec, out, planned.stdout, result.stdout


def test_act_experiment_runs_end_to_end_and_resumes(act_run):
    """The plan (`--dry-run`) names every stage and writes nothing; the run makes each stage's output; a second
    run finds every stage done and runs only the report again (`--out` continues)."""
    spec, out, planned, ran = act_run
    names = ["collect", "export", "collect", "export", "merge", "train", "eval", "report"]
    stages = re.findall(r"^  \[\d+\] (\w+)", planned, flags=re.M)
    assert stages == names and "[1] collect spatial/s0/black-bowl-1-on-plate (done)" in planned
    assert "lerobot-train --policy.type=act" in planned and "--policy.pretrained_backbone_weights=null" in planned
    assert "demonstrations: 4 (paper: 4)" in planned
    times = [line.split()[0] for line in (out / "times.tsv").read_text().splitlines()]
    assert times == names[1:]  # the first collection was there: every other stage ran once, in order
    assert (out / "train" / "checkpoints" / "last" / "pretrained_model" / "model.safetensors").exists()
    (row,) = store_rows(out / "eval")
    assert row["task_id"] == EXTENDED and row["policy"] == "lerobot" and row["status"] == "done"
    assert row["policy_calls"] == row["steps"]  # one action of the chunk per control step
    assert "| trained | 1 | " in (out / "experiment.md").read_text()
    assert (out / "report" / "index.html").exists() and "act" in (out / "report.md").read_text()

    again = run_cli("experiment", "run", str(spec), "--policy", "act", "--out", str(out), *RUN, *SMALL_BATCH)
    assert again.returncode == 0, again.stderr[-3000:]
    assert again.stdout.count("done already") == len(names) - 1
    assert len(store_rows(out / "eval")) == 1


def test_the_groups_merge_with_lerobots_aggregation_and_chunks_span_consecutive_control_steps(act_run):
    """The originals group and the extended group merge through LeRobot's `aggregate_datasets` into one dataset of
    both tasks at LangGap's fps label; the action chunks the trained ACT learns from (LeRobot's own delta
    timestamps for its config) are the demonstrations' consecutive control steps, which `langgap eval` executes
    one per step."""
    import lerobot.policies  # noqa: F401  (registers the policy types a saved config names)
    from lerobot.configs.policies import PreTrainedConfig
    from lerobot.datasets.factory import resolve_delta_timestamps
    from lerobot.datasets.lerobot_dataset import LeRobotDataset, LeRobotDatasetMetadata

    _, out, _, _ = act_run
    root = out / "data" / "train"
    meta = LeRobotDatasetMetadata("local/merged", root=root)
    assert meta.fps == FPS and meta.total_episodes == 4 and meta.total_tasks == 2
    config = PreTrainedConfig.from_pretrained(out / "train" / "checkpoints" / "last" / "pretrained_model")
    delta = resolve_delta_timestamps(config, meta)
    dataset = LeRobotDataset("local/merged", root=root, delta_timestamps=delta, video_backend="pyav")
    demos = [load_demo(p) for group in ("group0", "group1") for p in demo_files(out / "data" / group)]
    start = 0
    for episode, demo in enumerate(demos):
        for t in (0, demo.length // 2):
            item = dataset[start + t]
            assert int(item["episode_index"]) == episode
            inside = min(config.chunk_size, demo.length - t)
            chunk = item["action"].numpy()[:inside]
            np.testing.assert_allclose(chunk, demo.labels[t : t + inside], atol=1e-6)
        start += demo.length
    assert dataset[0]["task"] == demos[0].instruction and dataset[start - 1]["task"] == demos[-1].instruction


def test_smolvla_experiment_trains_on_a_tiny_smolvlm_built_here(act_run, tmp_path):
    """SmolVLA trains on a SmolVLM made here (config, processor, a word-level tokenizer of the catalogs' sentences
    with SmolVLM's special tokens; `tiny-smolvlm --image-size` sets its image size), and `langgap eval` runs the
    checkpoint. The data stages are done already (copied), so they are skipped."""
    from transformers import AutoConfig, AutoTokenizer

    spec, act_out, _, _ = act_run
    out = tmp_path / "smolvla"
    shutil.copytree(act_out / "data", out / "data")
    result = run_cli("experiment", "run", str(spec), "--policy", "smolvla", "--out", str(out), *RUN, *SMALL_BATCH)
    assert result.returncode == 0, result.stderr[-3000:]
    assert result.stdout.count("done already") == 5  # two collections, two exports, the merge
    vlm = out / "tiny-smolvlm"
    assert AutoConfig.from_pretrained(vlm).vision_config.image_size == 64  # `--image-size 64`, the rehearsal's
    tokenizer = AutoTokenizer.from_pretrained(vlm)
    (row,) = store_rows(out / "eval")
    assert tokenizer.unk_token_id not in tokenizer(row["instruction"])["input_ids"]
    assert tokenizer.fake_image_token_id != tokenizer.unk_token_id != tokenizer.global_image_token_id
    saved = json.loads((out / "train" / "checkpoints" / "last" / "pretrained_model" / "config.json").read_text())
    assert saved["type"] == "smolvla" and saved["vlm_model_name"] == str(vlm.resolve())
    assert saved["train_expert_only"] is True  # the default tuning, as the recipe states
    assert row["task_id"] == EXTENDED and row["status"] == "done"


def _linear_modules(policy_type: str) -> list[str]:
    """The names of every linear layer of LeRobot's π0 or π0.5, built on the meta device (no weights, no memory)."""
    import torch
    from lerobot.configs.types import FeatureType, PolicyFeature
    from lerobot.policies.factory import get_policy_class, make_policy_config

    config = make_policy_config(policy_type, device="cpu")
    config.input_features = {
        "observation.images.image": PolicyFeature(FeatureType.VISUAL, (3, 224, 224)),
        "observation.state": PolicyFeature(FeatureType.STATE, (8,)),
    }
    config.output_features = {"action": PolicyFeature(FeatureType.ACTION, (7,))}
    moved = torch.nn.Module.to
    torch.nn.Module.to = lambda self, *args, **kwargs: self  # the policy moves itself to its device: not from meta
    try:
        with torch.device("meta"):
            policy = get_policy_class(policy_type)(config)
    finally:
        torch.nn.Module.to = moved
    return [name for name, module in policy.named_modules() if isinstance(module, torch.nn.Linear)]


@pytest.mark.parametrize("policy", ["pi05", "pi0"])
def test_lora_tunings_adapt_what_their_recipe_says(policy):
    """On the real model's layer names (PEFT matches a string target with `re.fullmatch`): the paper's tuning adapts
    the action expert's q and v projections and the action projections, nothing of the VLM; the language tuning
    adapts every attention and MLP projection of the PaliGemma language model and of the expert; neither touches
    the vision tower."""
    names = _linear_modules(policy)
    recipe = load_recipe(policy)

    def adapted(tuning: str) -> list[str]:
        pattern = re.compile(recipe.tuning(tuning).options["peft.target_modules"])
        return [n for n in names if pattern.fullmatch(n)]

    paper, language = adapted("paper"), adapted("language")
    language_model = [n for n in names if ".language_model.layers." in n]
    assert language_model and not any(".language_model." in n or "vision_tower" in n for n in paper)
    assert {n.rsplit(".", 1)[-1] for n in paper if ".gemma_expert." in n} == {"q_proj", "v_proj"}
    assert {"model.action_in_proj", "model.action_out_proj"} <= set(paper)
    assert set(language_model) <= set(language) and not any("vision_tower" in n for n in language)
    expert = {n.rsplit(".", 1)[-1] for n in language if ".gemma_expert." in n}
    assert expert == {"q_proj", "k_proj", "v_proj", "o_proj", "gate_proj", "up_proj", "down_proj"}
