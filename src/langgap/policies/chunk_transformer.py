"""The chunk transformer `small-bc` and `small-vla` are built on: the instruction through the word encoder
(`langgap.policies.word_encoding`), input tokens that attend to its words, a transformer over [action query, robot
token, pooled instruction, input tokens] whose query output is decoded into a chunk of 7-D actions, normalisation
statistics held as buffers, and one-file checkpoints. A model adds what it reads (entities, images) of its own.

A model makes the shared parts with the `add_*` methods in an order of its own, which is kept: the order layers
are made in is the order a seed draws their initial weights in, and the order of the parameters is the order
gradient clipping sums their norms in, so a seed trains the weights it always did (tests/test_small_model_weights.py).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import ClassVar, Self

import numpy as np

from langgap.policies.checkpoints import load_model, save_model
from langgap.policies.text import Vocabulary
from langgap.policies.word_encoding import encode_words, nn, torch, transformer_layer

ACTION_DIM = 7
PREFIX = 3  # action query, robot token, pooled instruction: the tokens before a model's own


@dataclass(frozen=True)
class TrunkConfig:
    """The sizes every chunk transformer has; a model's config adds its own."""

    d_model: int = 64
    heads: int = 4
    layers: int = 2
    text_layers: int = 1
    chunk: int = 8
    max_words: int = 24


@dataclass
class Statistics:
    """Normalisation statistics from the training data: each field a list of floats that the model holds as a buffer
    of the same name, so a checkpoint's tensors give them back."""

    @classmethod
    def from_tensors(cls, state: dict) -> Self:
        """The statistics a model with them saved (its tensors by name)."""
        return cls(**{f.name: state[f.name].tolist() for f in fields(cls)})


def mean_and_std(values: np.ndarray) -> tuple[list[float], list[float]]:
    """Per-feature mean and std over the first axis; the std is kept off zero for features that never vary."""
    return values.mean(0).tolist(), (values.std(0) + 1e-3).tolist()


def feature_mlp(features: int, d_model: int) -> nn.Sequential:
    """The two-layer perceptron that turns a feature vector into a token."""
    return nn.Sequential(nn.Linear(features, d_model), nn.GELU(), nn.Linear(d_model, d_model))


class ChunkTransformer(nn.Module):
    """Base of a model that maps an instruction and its own inputs to `config.chunk` actions. A subclass names its
    checkpoint `FORMAT`, its policy `NAME`, and its `config_type` and `statistics_type` (how a checkpoint rebuilds
    it)."""

    FORMAT: ClassVar[str]
    NAME: ClassVar[str]
    config_type: ClassVar[type[TrunkConfig]]
    statistics_type: ClassVar[type[Statistics]]

    def __init__(self, config: TrunkConfig):
        super().__init__()
        self.config = config

    def add_words(self, vocab_size: int) -> None:
        """Word embeddings (id 0 is padding) and word positions."""
        self.words = nn.Embedding(vocab_size, self.config.d_model, padding_idx=0)
        self.word_position = nn.Embedding(self.config.max_words, self.config.d_model)

    def add_token_kinds(self) -> None:
        """The action query and an embedding per kind of token: query, robot, instruction, the model's own."""
        self.kind = nn.Embedding(PREFIX + 1, self.config.d_model)
        self.query = nn.Parameter(torch.zeros(self.config.d_model))

    def add_text_encoder(self) -> None:
        """The transformer the words (and, in small-bc, entity names) go through."""
        self.text = self._transformer(self.config.text_layers)

    def add_trunk(self, statistics: Statistics) -> None:
        """The cross-attention of input tokens to words, the transformer over all tokens, the action head, and the
        normalisation statistics (buffers)."""
        d = self.config.d_model
        self.ground = nn.MultiheadAttention(d, self.config.heads, batch_first=True)
        self.encoder = self._transformer(self.config.layers)
        self.head = nn.Sequential(
            nn.LayerNorm(d), nn.Linear(d, d), nn.GELU(), nn.Linear(d, self.config.chunk * ACTION_DIM)
        )
        for name, values in asdict(statistics).items():
            self.register_buffer(name, torch.tensor(values, dtype=torch.float32))

    def _transformer(self, layers: int) -> nn.TransformerEncoder:
        layer = transformer_layer(self.config.d_model, self.config.heads)
        return nn.TransformerEncoder(layer, layers, enable_nested_tensor=False)

    def encode_text(self, ids: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """(S, L) word ids -> per-word encodings (S, L, d) and pooled sentence vectors (S, d)."""
        return encode_words(self.words, self.word_position, self.text, ids)

    def encode_instruction(self, instruction: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """(B, L) word ids -> per-word encodings (B, L, d), pooled vectors (B, d) and the padding mask (B, L); each
        distinct sentence of the batch is encoded once, so the cost hardly depends on the sentences' length."""
        sentences, which = torch.unique(instruction, dim=0, return_inverse=True)
        words, pooled = self.encode_text(sentences)
        return words[which], pooled[which], (sentences == 0)[which]

    def grounded(self, tokens: torch.Tensor, words: torch.Tensor, word_pad: torch.Tensor) -> torch.Tensor:
        """Input tokens (B, N, d) after attending to the instruction's words, marked as the model's own kind."""
        attended, _ = self.ground(tokens, words, words, key_padding_mask=word_pad, need_weights=False)
        return tokens + attended + self.kind.weight[PREFIX]

    def decode(
        self, robot: torch.Tensor, pooled: torch.Tensor, tokens: torch.Tensor, present: torch.Tensor | None = None
    ) -> torch.Tensor:
        """The robot token (B, d), the pooled instruction (B, d) and the grounded input tokens (B, N, d; `present`
        (B, N) masks out absent ones) -> actions (B, chunk, 7)."""
        batch = robot.shape[0]
        query = (self.query + self.kind.weight[0]).expand(batch, 1, -1)
        robot = robot + self.kind.weight[1]
        text = pooled + self.kind.weight[2]
        sequence = torch.cat([query, robot.unsqueeze(1), text.unsqueeze(1), tokens], dim=1)
        padding = None
        if present is not None:
            always = torch.ones(batch, PREFIX, dtype=torch.bool, device=present.device)
            padding = ~torch.cat([always, present], dim=1)
        out = self.encoder(sequence, src_key_padding_mask=padding)
        return self.head(out[:, 0]).view(batch, self.config.chunk, ACTION_DIM)

    @classmethod
    def load(cls, path: str | Path) -> tuple[Self, Vocabulary, dict]:
        """Read a checkpoint `save_checkpoint` wrote of this model; returns (model in eval mode, vocabulary, training
        facts)."""

        def build(config: dict, vocab_size: int, state: dict) -> ChunkTransformer:
            return cls(cls.config_type(**config), vocab_size, cls.statistics_type.from_tensors(state))

        return load_model(path, format=cls.FORMAT, kind=cls.NAME, build=build)


def save_checkpoint(path: str | Path, model: ChunkTransformer, vocab: Vocabulary, training: dict) -> Path:
    """Write a model's weights and metadata (config, vocabulary, training facts) to one safetensors file."""
    return save_model(path, model, vocab, training, format=model.FORMAT)
