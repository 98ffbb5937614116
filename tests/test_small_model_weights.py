"""small-bc's and small-vla's trained weights do not drift: a few seeded training steps on fixed synthetic inputs give,
bit for bit, the weights of the checkpoints in tests/golden/, and those checkpoints still load.

The golden files are `save_checkpoint(path, model, VOCAB, {"final_loss": ..., "order": [...]})` of `trained(kind)`
as the code wrote them before the two models shared their trunk (PyTorch 2.13, CPU, one thread). A change of the
order in which a model makes its layers (the seeded initialisation), of its parameters (gradient clipping sums their
norms in that order), of its forward pass or of the loop shows here as other bits; a renamed tensor as a checkpoint
that no longer loads. Regenerate them only for a change that is meant to move the weights.

The last bits also depend on the CPU kernels PyTorch and its BLAS choose (as numpy's do: langgap/blas.py), so the
comparison is bit for bit only on the kind of CPU the golden files were made on (`GOLDEN_CPU`: PyTorch's CPU
capability and the vendor); elsewhere it allows a kernel's rounding (1e-4 relative), which still catches a layer made
in another order (weights off by 0.08) but not a regrouped sum (off by 1e-9)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from langgap.policies.text import Vocabulary

torch = pytest.importorskip("torch", reason="small-bc and small-vla need PyTorch (pip install 'langgap[train]')")

GOLDEN = Path(__file__).parent / "golden"
GOLDEN_CPU = ("AVX512", "AuthenticAMD")  # torch.backends.cpu.get_cpu_capability(), /proc/cpuinfo's vendor_id
VOCAB = Vocabulary(f"w{i}" for i in range(10))  # 12 ids: padding, unknown, ten words
FRAMES, STEPS, BATCH = 24, 6, 8


@pytest.fixture(autouse=True)
def one_thread():
    threads = torch.get_num_threads()
    torch.set_num_threads(1)  # as the trainers run in the tests: the summation order of one thread
    yield
    torch.set_num_threads(threads)


def synthetic(rng: np.random.Generator, chunk: int, words: int) -> dict[str, np.ndarray]:
    """Two sentences (one frame in two each), action chunks whose tail is masked, and what both models share."""
    sentences = np.zeros((2, words), dtype=np.int64)
    sentences[0, :4] = (2, 5, 6, 3)
    sentences[1, :5] = (2, 7, 8, 9, 4)
    mask = np.ones((FRAMES, chunk), dtype=bool)
    mask[::3, chunk // 2 :] = False  # past a demonstration's end
    return {
        "instruction": sentences[np.arange(FRAMES) % 2],
        "actions": rng.uniform(-1, 1, (FRAMES, chunk, 7)).astype(np.float32),
        "action_mask": mask,
    }


def trained(kind: str) -> tuple[torch.nn.Module, float]:
    """A small model of `kind` after STEPS seeded steps of the trainers' loop on synthetic frames, and its last loss."""
    from langgap.training.loop import TrainConfig, chunk_loss, optimise

    rng = np.random.default_rng(0)
    config = TrainConfig(data=(), steps=STEPS, batch_size=BATCH, seed=0, threads=1)
    if kind == "small-bc":
        from langgap.policies.small_bc.model import ModelConfig, Normalizer, SmallBC

        model_config = ModelConfig(d_model=16, heads=2, layers=1, text_layers=1, chunk=4, max_words=6, max_name_words=3)
        data = synthetic(rng, model_config.chunk, model_config.max_words)
        data["proprio"] = rng.normal(size=(FRAMES, 14)).astype(np.float32)
        data["entities"] = rng.normal(size=(FRAMES, 3, 14)).astype(np.float32)
        names = np.array([[2, 3, 0], [4, 5, 6], [7, 0, 0]], dtype=np.int64)
        data["names"] = np.repeat(names[None], FRAMES, axis=0)
        data["names"][1::2, 2] = 0  # the third entity is absent from every other frame
        tensors = {k: torch.from_numpy(v) for k, v in data.items()}
        normalizer = Normalizer.fit(data["proprio"], data["entities"], data["names"][..., 0] > 0)
        torch.manual_seed(config.seed)
        model = SmallBC(model_config, len(VOCAB), normalizer)

        def predict(batch: torch.Tensor) -> torch.Tensor:
            inputs = ("proprio", "entities", "names", "instruction")
            return model(*(tensors[k][batch] for k in inputs))
    else:
        from langgap.policies.small_vla.model import SmallVLA, StateNormalizer, VisionConfig
        from langgap.training.train_small_vla import random_shift

        model_config = VisionConfig(
            image_size=16, channels=(8, 8), d_model=16, heads=2, layers=1, text_layers=1, chunk=4, max_words=6
        )
        data = synthetic(rng, model_config.chunk, model_config.max_words)
        data["images"] = rng.integers(0, 256, (FRAMES, 2, 16, 16, 3), dtype=np.uint8)
        data["state"] = rng.normal(size=(FRAMES, 8)).astype(np.float32)
        tensors = {k: torch.from_numpy(v) for k, v in data.items()}
        torch.manual_seed(config.seed)
        model = SmallVLA(model_config, len(VOCAB), StateNormalizer.fit(data["state"]))
        shifts = torch.Generator().manual_seed(config.seed + 1)

        def predict(batch: torch.Tensor) -> torch.Tensor:
            images = random_shift(tensors["images"][batch], 1, shifts)
            return model(images, tensors["state"][batch], tensors["instruction"][batch])

    def loss_of(batch: torch.Tensor) -> torch.Tensor:
        return chunk_loss(predict(batch), tensors["actions"][batch], tensors["action_mask"][batch], config.loss)

    return model, optimise(model, loss_of, FRAMES, config, log=None)


@pytest.mark.parametrize("kind", ["small-bc", "small-vla"])
def test_seeded_training_gives_the_golden_weights_bit_for_bit(kind):
    from safetensors.torch import load_file

    load_checkpoint = _loader(kind)
    path = GOLDEN / f"{kind}.safetensors"
    golden, vocab, facts = load_checkpoint(path)  # a checkpoint written before: it still loads, under its names
    assert vocab.tokens == VOCAB.tokens
    model, loss = trained(kind)
    assert model.config == golden.config
    # The same tensors, made and registered in the same order (the order gradient clipping sums their norms in).
    assert list(model.state_dict()) == facts["order"]
    assert sorted(load_file(str(path))) == sorted(facts["order"])
    exact = _cpu() == GOLDEN_CPU
    for name, value in model.state_dict().items():
        expected = golden.state_dict()[name]
        same = torch.equal(value, expected) if exact else torch.allclose(value, expected, rtol=1e-4, atol=1e-6)
        assert same, f"{name}: off by up to {(value - expected).abs().max().item():.3g}"
    assert loss == facts["final_loss"] if exact else loss == pytest.approx(facts["final_loss"], rel=1e-4)


def _cpu() -> tuple[str, str]:
    try:
        lines = Path("/proc/cpuinfo").read_text().splitlines()
    except OSError:
        lines = []
    vendor = next((line.partition(":")[2].strip() for line in lines if line.startswith("vendor_id")), "")
    return torch.backends.cpu.get_cpu_capability(), vendor


def _loader(kind: str):
    if kind == "small-bc":
        from langgap.policies.small_bc.model import load_checkpoint
    else:
        from langgap.policies.small_vla.model import load_checkpoint
    return load_checkpoint
