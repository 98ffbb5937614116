"""small-bc: tokenizer, training on a tiny real collection, checkpoint round trip, `langgap eval` in a worker."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from langgap.policies.text import Vocabulary, words
from tests.support.harness import TINY_TASK, run_cli, store_rows
from tests.support.small_checkpoints import trained_checkpoint

torch = pytest.importorskip("torch", reason="small-bc needs PyTorch (pip install 'langgap[train]')")

FAILED = "goal/s0/open-cabinet-bottom-drawer"  # collected once with heavy execution noise: the attempt fails
NEVER = "spatial/s0/black-bowl-2-on-plate"  # in the catalog, never collected in these tests
TINY_SCENE = "pick_up_the_black_bowl_between_the_plate_and_the_ramekin_and_place_it_on_the_plate"  # TINY_TASK's


def test_words_and_vocabulary():
    assert words("Pick up the black bowl_1 on the Stove") == [
        "pick",
        "up",
        "the",
        "black",
        "bowl",
        "1",
        "on",
        "the",
        "stove",
    ]
    assert words("glazed_rim_porcelain_ramekin_1") == ["glazed", "rim", "porcelain", "ramekin", "1"]
    vocab = Vocabulary.from_texts(["place it on the plate", "akita_black_bowl_1"])
    assert vocab.tokens[:2] == ["<pad>", "<unk>"]
    ids = vocab.encode("place it on the stove", 7)
    assert ids[4] == 1 and ids[5:] == [0, 0] and 0 not in ids[:5]
    assert Vocabulary(vocab.tokens).tokens == vocab.tokens  # what a checkpoint stores restores the same ids


@pytest.fixture(scope="module")
def checkpoint(tiny_collection, tmp_path_factory):
    out = tmp_path_factory.mktemp("bc") / "tiny.safetensors"
    return trained_checkpoint("small-bc", tiny_collection, out, steps=20, batch_size=32)


def test_training_is_deterministic_and_checkpoint_round_trips(tiny_collection, checkpoint, tmp_path):
    from langgap.policies.small_bc.model import load_checkpoint
    from langgap.training.train_small_bc import TrainConfig, train

    facts = train(
        TrainConfig(data=(str(tiny_collection),), steps=20, batch_size=32, threads=1), tmp_path / "again.safetensors",
        log=None,
    )  # fmt: skip
    first, vocab, info = load_checkpoint(checkpoint)
    second, _, _ = load_checkpoint(tmp_path / "again.safetensors")
    for (name, a), (_, b) in zip(first.state_dict().items(), second.state_dict().items(), strict=True):
        assert torch.equal(a, b), name
    assert info["final_loss"] == facts["final_loss"] and info["tasks"] == [TINY_TASK]
    assert "plate" in vocab.tokens and "ramekin" in vocab.tokens  # from the sentence and the entity names


def test_the_vocabulary_is_fixed_before_training(tiny_collection, checkpoint, tmp_path):
    """Trained on one task, the model still has an id of its own for every word of every catalog, so no two
    sentences of its scene read the same; `--vocabulary training` (`vocabulary:` in a config file) gives the
    earlier vocabulary of the training data alone back."""
    from langgap.catalog.catalog import available_catalogs, load_catalog
    from langgap.policies.small_bc.model import load_checkpoint
    from langgap.policies.text import catalog_vocabulary

    model, vocab, info = load_checkpoint(checkpoint)
    assert info["tasks"] == [TINY_TASK] and info["vocabulary"] == "catalogs"
    assert vocab.tokens == catalog_vocabulary().tokens and model.words.num_embeddings == len(vocab)
    # every sentence, in every style, any shipped catalog asks on its scene
    scene = [t for name in available_catalogs() for t in load_catalog(name) if t.scene_task == TINY_SCENE]
    sentences = {" ".join(words(s)) for t in scene for s in t.instructions.values()}
    assert len({tuple(vocab.encode(s, model.config.max_words)) for s in sentences}) == len(sentences) > 100
    config = tmp_path / "earlier.yaml"
    config.write_text(f"data: [{tiny_collection}]\nsteps: 1\nthreads: 1\n")
    earlier_run = ("--config", str(config), "--vocabulary", "training", "--out", str(tmp_path / "earlier.safetensors"))
    result = run_cli("train", "small-bc", *earlier_run)
    assert result.returncode == 0, result.stderr
    _, earlier, earlier_info = load_checkpoint(tmp_path / "earlier.safetensors")
    assert earlier_info["vocabulary"] == "training" and "ramekin" in earlier.tokens and "not" not in earlier.tokens
    assert len({tuple(earlier.encode(s, model.config.max_words)) for s in sentences}) < len(sentences)


def test_policy_reads_the_instruction_and_is_deterministic(checkpoint, catalog):
    from langgap.engine.context import task_context
    from langgap.policies import make_policy
    from langgap.sim.env import EnvOptions, TaskEnv

    policy = make_policy("small-bc", {"checkpoint": str(checkpoint)})
    # It reads simulator state but is never told the goal: a learned policy under test.
    assert policy.spec.sees_state and not policy.spec.sees_goal
    assert policy.spec.chunk == 8 and policy.spec.replan == 2
    task = catalog.get(TINY_TASK)
    with TaskEnv(task, EnvOptions(privileged=True)) as env:
        env.reset(0)
        env.settle()
        observation = env.observe()
    outputs = []
    for instruction in (None, None, "pick up the ramekin and place it on the stove"):
        policy.reset(task_context(task, catalog, init_index=0, seed=0, instruction=instruction))
        outputs.append(policy.act(observation))
    assert outputs[0].shape == (8, 7) and np.all(np.abs(outputs[0]) <= 1) and set(outputs[0][:, 6]) <= {-1.0, 1.0}
    np.testing.assert_array_equal(outputs[0], outputs[1])
    assert not np.array_equal(outputs[0], outputs[2])  # another sentence, another action
    # The instruction in force is the observation's: changed mid-episode, it is read at once.
    policy.reset(task_context(task, catalog, init_index=0, seed=0))
    switched = dataclasses.replace(observation, instruction="pick up the ramekin and place it on the stove")
    np.testing.assert_array_equal(policy.act(switched), outputs[2])
    np.testing.assert_array_equal(policy.act(observation), outputs[0])  # no instruction given: the context's


def test_eval_runs_small_bc_in_a_worker(checkpoint, tmp_path):
    run = tmp_path / "run"
    result = run_cli(
        "eval", "--policy", "small-bc", "--policy-arg", f"checkpoint={checkpoint}", "--tasks", TINY_TASK,
        "--episodes", "1", "--run", str(run), "--workers", "1", "--no-progress", "--quiet",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    (row,) = store_rows(run)
    assert row["status"] == "done" and row["policy"] == "small-bc" and row["steps"] > 0
    # A learned policy that read simulator state, never told the goal: so recorded, so reported.
    assert (row["sees_state"], row["sees_goal"]) == (1, 0)
    report = run_cli("report", str(run), "--format", "md").stdout
    assert "run (small-bc) ‡" in report and "‡ reads simulator state" in report
    assert "scripted reference" not in report


def test_missing_or_foreign_checkpoint_is_a_clear_error(tmp_path):
    from langgap.policies import make_policy
    from langgap.policies.checkpoints import CheckpointError

    with pytest.raises(CheckpointError, match="no small-bc checkpoint"):
        make_policy("small-bc", {"checkpoint": str(tmp_path / "none.safetensors")})
    from safetensors.torch import save_file

    save_file({"w": torch.zeros(1)}, str(tmp_path / "other.safetensors"))
    with pytest.raises(CheckpointError, match="not a small-bc checkpoint"):
        make_policy("small-bc", {"checkpoint": str(tmp_path / "other.safetensors")})


def test_a_task_collected_without_success_is_skipped_and_an_uncollected_one_is_an_error(tiny_collection, tmp_path):
    # One real attempt at the bottom drawer, which fails: the oracle does it from this start (seed 0), but
    # not with noise of one action unit (std) on every motion command.
    failed = tmp_path / "failed"
    result = run_cli(
        "collect", "--tasks", FAILED, "--demos", "1", "--max-attempts", "1", "--out", str(failed),
        "--format", "compact", "--workers", "0", "--no-progress", "--noise", "1.0",
    )  # fmt: skip
    assert result.returncode == 1, result.stderr
    data = ("--data", str(tiny_collection), "--data", str(failed))
    train = ("train", "small-bc", *data, "--steps", "2", "--threads", "1")
    result = run_cli(*train, "--tasks", f"{TINY_TASK},{FAILED}", "--out", str(tmp_path / "a.safetensors"))
    assert result.returncode == 0, result.stderr
    assert f"kept no demonstration, e.g. {FAILED}" in result.stdout and "of 1 tasks" in result.stdout
    result = run_cli(*train, "--tasks", f"{TINY_TASK},{NEVER}", "--out", str(tmp_path / "b.safetensors"))
    assert result.returncode != 0 and f"error: no demonstrations of 1 selected task(s), e.g. {NEVER}" in result.stderr


def test_a_smoke_run_trains_on_the_selected_tasks_its_shrunk_collection_holds(tiny_collection, tmp_path, monkeypatch):
    """LANGGAP_SMOKE=1 (the docs' tests): a selection that names tasks the shrunk collection never attempted
    trains on the ones it did, and says so, instead of stopping."""
    monkeypatch.setenv("LANGGAP_SMOKE", "1")
    out = tmp_path / "c.safetensors"
    argv = ("train", "small-bc", "--data", str(tiny_collection), "--tasks", f"{TINY_TASK},{NEVER}", "--steps", "2")
    result = run_cli(*argv, "--threads", "1", "--out", str(out))
    assert result.returncode == 0, result.stderr
    assert (
        f"task selection '{TINY_TASK},{NEVER}' -> {TINY_TASK} (the 1 of 2 its collections attempted)" in result.stderr
    )
    assert out.exists()
