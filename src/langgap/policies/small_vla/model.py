"""The `small-vla` model: both cameras, the 8-D state and the instruction in, a chunk of actions out.

* Text: the instruction's words through the word-level encoder `small-bc` uses (`langgap.policies.word_encoding`).
* Vision: one small convolutional network for both cameras (stride-2 stages); after every stage the feature
  maps are modulated by the sentence (FiLM: a per-channel scale and shift computed from the pooled instruction),
  so what the network extracts depends on what it was asked. The last map's cells become tokens (with their
  position and camera), and each token attends to the instruction's words (cross-attention).
* A transformer over [action query, state, pooled instruction, image tokens]; the query's output is decoded into
  `chunk` 7-D actions (the chunk transformer small-bc shares: `langgap.policies.chunk_transformer`).

Saved as one safetensors file (weights + JSON metadata: config, vocabulary, state normalisation).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from langgap.policies.chunk_transformer import ChunkTransformer, Statistics, TrunkConfig, feature_mlp, mean_and_std
from langgap.policies.text import Vocabulary
from langgap.policies.word_encoding import nn, torch
from langgap.sim.env import CAMERAS

FORMAT = "langgap-small-vla/1"
STATE_DIM = 8
CAMERA_COUNT = len(CAMERAS)  # agentview and the wrist camera, in that order


@dataclass(frozen=True)
class VisionConfig(TrunkConfig):
    """The model's sizes. `image_size` is the cameras' (square) size in pixels: the policy asks for it."""

    image_size: int = 96
    channels: tuple[int, ...] = (32, 64, 64, 128)  # one stride-2 stage each: 96 px -> a 6 x 6 map

    def __post_init__(self) -> None:
        object.__setattr__(self, "channels", tuple(self.channels))  # JSON gives a list back

    @property
    def grid(self) -> int:
        """The last feature map's side: the image tokens per camera are its square."""
        side = self.image_size
        for _ in self.channels:
            side = (side + 1) // 2
        return side


@dataclass
class StateNormalizer(Statistics):
    """Mean and std of the 8-D state over the training frames."""

    state_mean: list[float]
    state_std: list[float]

    @classmethod
    def fit(cls, states: np.ndarray) -> StateNormalizer:
        return cls(*mean_and_std(states))


class FilmStage(nn.Module):
    """A stride-2 convolution, group norm, a sentence-conditioned per-channel scale and shift, GELU."""

    def __init__(self, in_channels: int, out_channels: int, d_model: int):
        super().__init__()
        self.conv = nn.Conv2d(in_channels, out_channels, 3, stride=2, padding=1)
        self.norm = nn.GroupNorm(8, out_channels)
        self.film = nn.Linear(d_model, 2 * out_channels)
        nn.init.zeros_(self.film.weight)  # starts as the identity: scale 1, shift 0
        nn.init.zeros_(self.film.bias)

    def forward(self, x: torch.Tensor, sentence: torch.Tensor) -> torch.Tensor:
        scale, shift = self.film(sentence).unsqueeze(-1).unsqueeze(-1).chunk(2, dim=1)
        return nn.functional.gelu(self.norm(self.conv(x)) * (1 + scale) + shift)


class SmallVLA(ChunkTransformer):
    """Both cameras, the 8-D state and the instruction -> a chunk of actions."""

    FORMAT = FORMAT
    NAME = "small-vla"
    config_type = VisionConfig
    statistics_type = StateNormalizer

    def __init__(self, config: VisionConfig, vocab_size: int, normalizer: StateNormalizer):
        super().__init__(config)
        d = config.d_model
        self.add_words(vocab_size)
        self.add_text_encoder()
        widths = (3, *config.channels)
        self.stages = nn.ModuleList(FilmStage(a, b, d) for a, b in zip(widths, widths[1:], strict=False))
        self.project = nn.Linear(config.channels[-1], d)
        self.cell = nn.Parameter(torch.zeros(config.grid * config.grid, d))  # where a token is in its image
        self.camera = nn.Embedding(CAMERA_COUNT, d)
        self.add_token_kinds()  # query, state, instruction, image
        self.state = feature_mlp(STATE_DIM, d)
        self.add_trunk(normalizer)
        nn.init.normal_(self.cell, std=0.02)

    def forward(self, images: torch.Tensor, state: torch.Tensor, instruction: torch.Tensor) -> torch.Tensor:
        """images (B, 2, H, W, 3) uint8 (agentview, wrist), state (B, 8), instruction (B, L) word ids
        -> actions (B, chunk, 7)."""
        batch = state.shape[0]
        words, pooled, word_pad = self.encode_instruction(instruction)
        pixels = images.flatten(0, 1).permute(0, 3, 1, 2).float() / 255.0 - 0.5  # (B * 2, 3, H, W)
        sentence = pooled.repeat_interleave(CAMERA_COUNT, dim=0)
        for stage in self.stages:
            pixels = stage(pixels, sentence)
        tokens = self.project(pixels.flatten(2).transpose(1, 2)) + self.cell  # (B * 2, cells, d)
        tokens = tokens.view(batch, CAMERA_COUNT, -1, tokens.shape[-1]) + self.camera.weight[:, None]
        tokens = self.grounded(tokens.flatten(1, 2), words, word_pad)
        state_token = self.state((state - self.state_mean) / self.state_std)
        return self.decode(state_token, pooled, tokens)


def load_checkpoint(path: str | Path) -> tuple[SmallVLA, Vocabulary, dict]:
    """Read a checkpoint written by `chunk_transformer.save_checkpoint`; returns (model in eval mode, vocabulary,
    training info)."""
    return SmallVLA.load(path)
