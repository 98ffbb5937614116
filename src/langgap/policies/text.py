"""Word tokenizer shared by instructions and scene entity names, so that "ramekin" in a sentence and the
entity `glazed_rim_porcelain_ramekin_1` meet in one embedding table; and the vocabulary a model is trained with.

The default vocabulary (`catalog_vocabulary`) is fixed before training from every sentence a policy may be asked:
every instruction, in every style, of every catalog LangGap ships, and the object and fixture names of their
scenes. A word no training sentence holds still has its own (untrained) embedding, so two held-out sentences
never reach the model as the same input. The earlier vocabulary of the training sentences alone (`training`)
stays for reproducing results made with it.
"""

from __future__ import annotations

import functools
from collections.abc import Iterable

from langgap import stack
from langgap.bddl import parse_bddl
from langgap.catalog.catalog import available_catalogs, load_catalog
from langgap.catalog.words import words

PAD, UNK = "<pad>", "<unk>"
# Where a trained model's vocabulary comes from (`TrainConfig.vocabulary`): the shipped catalogs (the default),
# or only its training data's sentences and entity names (how checkpoints were trained before).
VOCABULARIES = ("catalogs", "training")
__all__ = ["PAD", "UNK", "VOCABULARIES", "Vocabulary", "catalog_texts", "catalog_vocabulary", "words"]


class Vocabulary:
    """Word -> id, with padding (0) and unknown (1), the rest sorted: the same words give the same ids. Saved with
    the model, which reads it back from its checkpoint."""

    def __init__(self, tokens: Iterable[str]):
        self.tokens = [PAD, UNK, *sorted(set(tokens) - {PAD, UNK})]
        self._ids = {t: i for i, t in enumerate(self.tokens)}

    @classmethod
    def from_texts(cls, texts: Iterable[str]) -> Vocabulary:
        """The vocabulary of the words of `texts`."""
        return cls(w for text in texts for w in words(text))

    def __len__(self) -> int:
        return len(self.tokens)

    def encode(self, text: str, length: int) -> list[int]:
        """Ids of `text`'s words, truncated or padded to `length`."""
        ids = [self._ids.get(w, 1) for w in words(text)][:length]
        return ids + [0] * (length - len(ids))


def catalog_texts() -> list[str]:
    """Every instruction, in every style, of every shipped catalog's tasks, and the object and fixture names of
    their scenes (LIBERO's BDDL files; a scene read from a benchmark's package holds no other names), sorted."""
    sentences: set[str] = set()
    scenes: set[tuple[str, str]] = set()
    for name in available_catalogs():
        for task in load_catalog(name):
            sentences.update(task.instructions.values())
            scenes.add((task.suite, task.scene_task))
    names: set[str] = set()
    for suite, scene in sorted(scenes):
        path = stack.bddl_path(suite, scene)
        problem = parse_bddl(path.read_text(encoding="utf-8"), source=str(path))
        names.update(problem.objects, problem.fixtures)
    return sorted(sentences | names)


@functools.cache
def catalog_vocabulary() -> Vocabulary:
    """The vocabulary of `catalog_texts`: fixed before training, the same for every run of one LangGap version."""
    return Vocabulary.from_texts(catalog_texts())
