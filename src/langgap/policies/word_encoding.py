"""The word-level instruction encoder `small-bc` and `small-vla` share: learned word embeddings and positions
through a small transformer encoder; words come from `langgap.policies.text.Vocabulary`. Both models import PyTorch
through this module, which says how to install it when it is missing."""

from __future__ import annotations

from langgap.errors import DependencyNotInstalled

try:
    import torch
    from torch import nn
except ImportError:  # pragma: no cover - depends on the environment
    raise DependencyNotInstalled(
        "small-bc and small-vla need PyTorch: pip install 'langgap[train]' (./setup.sh installs it)"
    ) from None

__all__ = ["encode_words", "nn", "torch", "transformer_layer"]


def transformer_layer(d_model: int, heads: int) -> nn.TransformerEncoderLayer:
    """One pre-norm transformer encoder layer without dropout (deterministic training)."""
    return nn.TransformerEncoderLayer(d_model, heads, 4 * d_model, dropout=0.0, batch_first=True, norm_first=True)


def encode_words(
    embedding: nn.Embedding, position: nn.Embedding, encoder: nn.TransformerEncoder, ids: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor]:
    """(S, L) word ids (0: padding) -> per-word encodings (S, L, d) and pooled sentence vectors (S, d)."""
    positions = torch.arange(ids.shape[1], device=ids.device)
    pad = ids == 0
    words = encoder(embedding(ids) + position(positions), src_key_padding_mask=pad)
    keep = (~pad).unsqueeze(-1).float()
    return words, (words * keep).sum(1) / keep.sum(1).clamp(min=1.0)
