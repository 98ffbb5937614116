"""The words of a sentence or an entity name: what the small policies' tokenizer reads and what a split compares."""

from __future__ import annotations

import re

_WORD = re.compile(r"[a-z]+|\d+")


def words(text: str) -> list[str]:
    """Lower-cased words and numbers of a sentence or an entity name (`akita_black_bowl_1`)."""
    return _WORD.findall(text.lower().replace("_", " "))
