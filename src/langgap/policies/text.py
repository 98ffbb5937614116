"""Word tokenizer shared by instructions and scene entity names, so that "ramekin" in a sentence and the
entity `glazed_rim_porcelain_ramekin_1` meet in one embedding table."""

from __future__ import annotations

import re
from collections.abc import Iterable

PAD, UNK = "<pad>", "<unk>"
_WORD = re.compile(r"[a-z]+|\d+")


def words(text: str) -> list[str]:
    """Lower-cased words and numbers of a sentence or an entity name (`akita_black_bowl_1`)."""
    return _WORD.findall(text.lower().replace("_", " "))


class Vocabulary:
    """Word -> id, with padding (0) and unknown (1). Built from the training data, saved with the model."""

    def __init__(self, tokens: Iterable[str]):
        self.tokens = [PAD, UNK, *sorted(set(tokens) - {PAD, UNK})]
        self._ids = {t: i for i, t in enumerate(self.tokens)}

    @classmethod
    def from_texts(cls, texts: Iterable[str]) -> Vocabulary:
        return cls(w for text in texts for w in words(text))

    def __len__(self) -> int:
        return len(self.tokens)

    def encode(self, text: str, length: int) -> list[int]:
        """Ids of `text`'s words, truncated or padded to `length`."""
        ids = [self._ids.get(w, 1) for w in words(text)][:length]
        return ids + [0] * (length - len(ids))
