"""Tiny LeRobot checkpoints with random weights, built from real LeRobot classes (nothing downloaded)."""

from __future__ import annotations

from pathlib import Path

import torch
from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.policies.diffusion.configuration_diffusion import DiffusionConfig
from lerobot.policies.diffusion.modeling_diffusion import DiffusionPolicy
from lerobot.policies.factory import make_pre_post_processors

IMAGE_SIZE = 64
N_ACTION_STEPS = 4


def _features(image_size: int) -> tuple[dict, dict]:
    image = PolicyFeature(type=FeatureType.VISUAL, shape=(3, image_size, image_size))
    inputs = {
        "observation.images.image": image,
        "observation.images.image2": image,
        "observation.state": PolicyFeature(type=FeatureType.STATE, shape=(8,)),
    }
    return inputs, {"action": PolicyFeature(type=FeatureType.ACTION, shape=(7,))}


def _stats(inputs: dict) -> dict:
    stats = {key: {"mean": torch.full((3, 1, 1), 0.5), "std": torch.full((3, 1, 1), 0.25)} for key in inputs}
    for key, size in (("observation.state", 8), ("action", 7)):
        stats[key] = {
            "mean": torch.zeros(size),
            "std": torch.ones(size),
            "min": -torch.ones(size),
            "max": torch.ones(size),
        }
    return stats


def diffusion_checkpoint(directory: Path, seed: int = 0) -> Path:
    """A small Diffusion policy (stochastic sampling, action chunks of N_ACTION_STEPS, 2 observation steps)
    with its pre/post processors, saved as a LeRobot `pretrained_model/` directory."""
    torch.manual_seed(seed)
    inputs, outputs = _features(IMAGE_SIZE)
    config = DiffusionConfig(
        input_features=inputs,
        output_features=outputs,
        pretrained_backbone_weights=None,  # the default downloads ImageNet weights
        use_separate_rgb_encoder_per_camera=False,
        crop_shape=None,
        horizon=8,
        n_action_steps=N_ACTION_STEPS,
        n_obs_steps=2,
        down_dims=(16, 32),
        n_groups=4,
        diffusion_step_embed_dim=16,
        spatial_softmax_num_keypoints=8,
        num_inference_steps=3,
        device="cpu",
    )
    policy = DiffusionPolicy(config)
    preprocessor, postprocessor = make_pre_post_processors(config, dataset_stats=_stats(inputs))
    target = directory / "pretrained_model"
    for part in (policy, preprocessor, postprocessor):
        part.save_pretrained(target)
    return target


def lora_adapter(checkpoint: Path, directory: Path) -> Path:
    """A PEFT LoRA adapter on the checkpoint's policy (non-zero weights, so it changes the actions)."""
    from peft import LoraConfig, get_peft_model

    torch.manual_seed(1)
    policy = DiffusionPolicy.from_pretrained(checkpoint)
    linear = [name for name, module in policy.named_modules() if isinstance(module, torch.nn.Linear)]
    config = LoraConfig(r=4, lora_alpha=8, target_modules=linear, init_lora_weights=False)
    get_peft_model(policy, config).save_pretrained(directory)
    return directory
