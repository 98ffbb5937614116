"""The `small-bc` model: a small language-conditioned policy over scene entities that predicts action chunks.
Saved as one safetensors file (weights + JSON metadata: config, vocabulary, normalisation statistics).

* Text: the instruction's words (learned embeddings + positions) through a small transformer encoder.
* Scene: one token per entity (its name through the same text encoder + an MLP of its features); each
  entity token attends to the encoded instruction (cross-attention), which is where a word like "ramekin"
  meets the entity `glazed_rim_porcelain_ramekin_1` (sentences and names share word embeddings).
* A transformer over [action query, proprioception, pooled instruction, entities]; the query's output
  is decoded into `chunk` 7-D actions (the chunk transformer small-vla shares: `langgap.policies.chunk_transformer`).

Instructions are encoded once per distinct sentence in a batch, so training cost hardly depends on
their length.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from langgap.policies.chunk_transformer import ChunkTransformer, Statistics, TrunkConfig, feature_mlp, mean_and_std
from langgap.policies.small_bc.features import ENTITY_DIM, PROPRIO_DIM
from langgap.policies.text import Vocabulary
from langgap.policies.word_encoding import torch

FORMAT = "langgap-small-bc/1"


@dataclass(frozen=True)
class ModelConfig(TrunkConfig):
    """small-bc's sizes: the trunk's, and how many words of an entity's name it reads."""

    max_name_words: int = 8


@dataclass
class Normalizer(Statistics):
    """Per-feature mean and std of proprioception and entity features (from the training data)."""

    proprio_mean: list[float]
    proprio_std: list[float]
    entity_mean: list[float]
    entity_std: list[float]

    @classmethod
    def fit(cls, proprio: np.ndarray, entities: np.ndarray, entity_mask: np.ndarray) -> Normalizer:
        return cls(*mean_and_std(proprio), *mean_and_std(entities[entity_mask]))


class SmallBC(ChunkTransformer):
    """Proprioception, the scene's named entities and the instruction -> a chunk of actions."""

    FORMAT = FORMAT
    NAME = "small-bc"
    config_type = ModelConfig
    statistics_type = Normalizer

    def __init__(self, config: ModelConfig, vocab_size: int, normalizer: Normalizer):
        super().__init__(config)
        self.add_words(vocab_size)
        self.add_token_kinds()  # query, proprioception, instruction, entity
        self.add_text_encoder()
        self.proprio = feature_mlp(PROPRIO_DIM, config.d_model)
        self.entity = feature_mlp(ENTITY_DIM, config.d_model)
        self.add_trunk(normalizer)

    def forward(
        self, proprio: torch.Tensor, entities: torch.Tensor, names: torch.Tensor, instruction: torch.Tensor
    ) -> torch.Tensor:
        """proprio (B, 14), entities (B, E, 14), names (B, E, W) word ids (0 = no entity), instruction (B, L) ids
        -> actions (B, chunk, 7)."""
        words, pooled, word_pad = self.encode_instruction(instruction)
        # Names through the text encoder (once per distinct name): word order tells bowl 1 from bowl 2.
        flat = names.reshape(-1, names.shape[-1])
        distinct, where = torch.unique(flat, dim=0, return_inverse=True)
        name_vec = self.encode_text(distinct)[1][where].view(*names.shape[:2], -1)
        entity_tok = self.entity((entities - self.entity_mean) / self.entity_std) + name_vec
        entity_tok = self.grounded(entity_tok, words, word_pad)
        proprio_tok = self.proprio((proprio - self.proprio_mean) / self.proprio_std)
        return self.decode(proprio_tok, pooled, entity_tok, present=names[..., 0] > 0)


def load_checkpoint(path: str | Path) -> tuple[SmallBC, Vocabulary, dict]:
    """Read a checkpoint written by `chunk_transformer.save_checkpoint`; returns (model in eval mode, vocabulary,
    training info)."""
    return SmallBC.load(path)
