"""small-vla's training parts that need no simulator: chunk targets, the random image shift, the model's shapes."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch", reason="small-vla needs PyTorch (pip install 'langgap[train]')")


def test_chunk_targets_repeat_the_last_label_and_mask_past_the_end():
    from langgap.training.loop import chunk_targets

    labels = np.arange(3 * 7, dtype=np.float64).reshape(3, 7)
    targets, mask = chunk_targets(labels, 4)
    assert targets.shape == (3, 4, 7) and targets.dtype == np.float32
    np.testing.assert_array_equal(targets[1, :2], labels[1:3])
    np.testing.assert_array_equal(targets[1, 2], labels[2])  # past the end: the last label, masked out
    assert mask.tolist() == [[True, True, True, False], [True, True, False, False], [True, False, False, False]]


def test_random_shift_moves_each_image_within_its_padding():
    from langgap.training.train_small_vla import random_shift

    images = torch.zeros((3, 2, 8, 8, 3), dtype=torch.uint8)
    images[:, :, 3:5, 3:5] = 255  # a bright square in the middle of every image
    shifted = random_shift(images, 2, torch.Generator().manual_seed(0))
    assert shifted.shape == images.shape and shifted.dtype == torch.float32
    moved = [tuple(np.argwhere(img[..., 0].numpy() == 255).min(0)) for img in shifted.flatten(0, 1)]
    assert all(1 <= y <= 5 and 1 <= x <= 5 for y, x in moved)  # up to 2 px each way
    assert len(set(moved)) > 1  # not one shift for all
    again = random_shift(images, 2, torch.Generator().manual_seed(0))
    assert torch.equal(shifted, again)  # the generator decides: training is deterministic


def test_model_maps_images_state_and_sentence_to_a_chunk():
    from langgap.policies.small_vla.model import SmallVLA, StateNormalizer, VisionConfig

    config = VisionConfig(image_size=32, chunk=5)
    assert config.grid == 2  # four stride-2 stages
    torch.manual_seed(0)
    model = SmallVLA(config, vocab_size=10, normalizer=StateNormalizer([0.0] * 8, [1.0] * 8)).eval()
    images = torch.randint(0, 255, (2, 2, 32, 32, 3), dtype=torch.uint8)
    sentences = torch.tensor([[2, 3, 4, 0], [2, 5, 0, 0]])
    out = model(images, torch.zeros(2, 8), sentences)
    assert out.shape == (2, 5, 7)
    # Each sample's output depends on its own sentence only (sentences are encoded once, then gathered back).
    alone = model(images[1:], torch.zeros(1, 8), sentences[1:])
    torch.testing.assert_close(out[1:], alone)
