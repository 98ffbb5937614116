"""The `small-bc` model: a small language-conditioned policy over scene entities that predicts action chunks.
Saved as one safetensors file (weights + JSON metadata: config, vocabulary, normalisation statistics).

* Text: the instruction's words (learned embeddings + positions) through a small transformer encoder.
* Scene: one token per entity (its name through the same text encoder + an MLP of its features); each
  entity token attends to the encoded instruction (cross-attention), which is where a word like "ramekin"
  meets the entity `glazed_rim_porcelain_ramekin_1` (sentences and names share word embeddings).
* A transformer over [action query, proprioception, pooled instruction, entities]; the query's output
  is decoded into `chunk` 7-D actions.

Instructions are encoded once per distinct sentence in a batch, so training cost hardly depends on
their length.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from langgap.policies.checkpoints import load_model, save_model
from langgap.policies.small_bc.features import ENTITY_DIM, PROPRIO_DIM
from langgap.policies.text import Vocabulary
from langgap.policies.word_encoding import encode_words, nn, torch, transformer_layer

FORMAT = "langgap-small-bc/1"


@dataclass(frozen=True)
class ModelConfig:
    d_model: int = 64
    heads: int = 4
    layers: int = 2
    text_layers: int = 1
    chunk: int = 8
    max_words: int = 24
    max_name_words: int = 8


@dataclass
class Normalizer:
    """Per-feature mean and std of proprioception and entity features (from the training data)."""

    proprio_mean: list[float]
    proprio_std: list[float]
    entity_mean: list[float]
    entity_std: list[float]

    @classmethod
    def fit(cls, proprio: np.ndarray, entities: np.ndarray, entity_mask: np.ndarray) -> Normalizer:
        present = entities[entity_mask]
        return cls(
            proprio.mean(0).tolist(),
            (proprio.std(0) + 1e-3).tolist(),
            present.mean(0).tolist(),
            (present.std(0) + 1e-3).tolist(),
        )


class SmallBC(nn.Module):
    def __init__(self, config: ModelConfig, vocab_size: int, normalizer: Normalizer):
        super().__init__()
        self.config = config
        d = config.d_model
        self.words = nn.Embedding(vocab_size, d, padding_idx=0)
        self.word_position = nn.Embedding(config.max_words, d)
        self.kind = nn.Embedding(4, d)  # query, proprioception, instruction, entity
        self.query = nn.Parameter(torch.zeros(d))
        self.text = nn.TransformerEncoder(_layer(config), config.text_layers, enable_nested_tensor=False)
        self.proprio = nn.Sequential(nn.Linear(PROPRIO_DIM, d), nn.GELU(), nn.Linear(d, d))
        self.entity = nn.Sequential(nn.Linear(ENTITY_DIM, d), nn.GELU(), nn.Linear(d, d))
        self.ground = nn.MultiheadAttention(d, config.heads, batch_first=True)
        self.encoder = nn.TransformerEncoder(_layer(config), config.layers, enable_nested_tensor=False)
        self.head = nn.Sequential(nn.LayerNorm(d), nn.Linear(d, d), nn.GELU(), nn.Linear(d, config.chunk * 7))
        for name, values in asdict(normalizer).items():
            self.register_buffer(name, torch.tensor(values, dtype=torch.float32))

    def encode_text(self, instruction: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """(S, L) word ids -> per-word encodings (S, L, d) and pooled sentence vectors (S, d)."""
        return encode_words(self.words, self.word_position, self.text, instruction)

    def forward(
        self, proprio: torch.Tensor, entities: torch.Tensor, names: torch.Tensor, instruction: torch.Tensor
    ) -> torch.Tensor:
        """proprio (B, 14), entities (B, E, 14), names (B, E, W) word ids (0 = no entity), instruction (B, L) ids
        -> actions (B, chunk, 7)."""
        batch = proprio.shape[0]
        sentences, which = torch.unique(instruction, dim=0, return_inverse=True)
        words, pooled = self.encode_text(sentences)
        words, pooled, word_pad = words[which], pooled[which], (sentences == 0)[which]
        entity_mask = names[..., 0] > 0
        # Names through the text encoder (once per distinct name): word order tells bowl 1 from bowl 2.
        flat = names.reshape(-1, names.shape[-1])
        distinct, where = torch.unique(flat, dim=0, return_inverse=True)
        name_vec = self.encode_text(distinct)[1][where].view(*names.shape[:2], -1)
        entity_tok = self.entity((entities - self.entity_mean) / self.entity_std) + name_vec
        grounded, _ = self.ground(entity_tok, words, words, key_padding_mask=word_pad, need_weights=False)
        entity_tok = entity_tok + grounded + self.kind.weight[3]
        query = (self.query + self.kind.weight[0]).expand(batch, 1, -1)
        proprio_tok = self.proprio((proprio - self.proprio_mean) / self.proprio_std) + self.kind.weight[1]
        text_tok = pooled + self.kind.weight[2]
        tokens = torch.cat([query, proprio_tok.unsqueeze(1), text_tok.unsqueeze(1), entity_tok], dim=1)
        always = torch.ones(batch, 3, dtype=torch.bool, device=proprio.device)
        keep = torch.cat([always, entity_mask], dim=1)
        out = self.encoder(tokens, src_key_padding_mask=~keep)
        return self.head(out[:, 0]).view(batch, self.config.chunk, 7)


def _layer(config: ModelConfig) -> nn.TransformerEncoderLayer:
    return transformer_layer(config.d_model, config.heads)


def save_checkpoint(path: str | Path, model: SmallBC, vocab: Vocabulary, training: dict) -> Path:
    """Write weights and metadata to one safetensors file."""
    return save_model(path, model, vocab, training, format=FORMAT)


def load_checkpoint(path: str | Path) -> tuple[SmallBC, Vocabulary, dict]:
    """Read a checkpoint written by `save_checkpoint`; returns (model in eval mode, vocabulary, training info)."""

    def build(config: dict, vocab_size: int, state: dict) -> SmallBC:
        stats = {k: state[k].tolist() for k in ("proprio_mean", "proprio_std", "entity_mean", "entity_std")}
        return SmallBC(ModelConfig(**config), vocab_size, Normalizer(**stats))

    return load_model(path, format=FORMAT, kind="small-bc", build=build)
