"""The vocabulary small-bc and small-vla train with: fixed before training from every shipped catalog's sentences."""

from __future__ import annotations

from collections import defaultdict

import pytest

from langgap.catalog.catalog import available_catalogs, load_catalog
from langgap.policies.text import UNK, Vocabulary, catalog_texts, catalog_vocabulary, words


def test_it_holds_every_word_of_every_catalog_instruction_in_every_style():
    tokens = set(catalog_vocabulary().tokens)
    styles: set[str] = set()
    for name in available_catalogs():
        for task in load_catalog(name):
            styles.update(task.instructions)
            for sentence in task.instructions.values():
                missing = set(words(sentence)) - tokens
                assert not missing, f"{task.id}: {sentence!r} lacks {sorted(missing)}"
    assert styles == {"libero", "paper", "package"}
    # the scenes' entity names, which small-bc reads beside the sentence, are in it too
    assert {"ramekin", "frypan", "chefmate"} <= tokens


def test_two_different_sentences_of_one_scene_never_read_the_same():
    vocab = catalog_vocabulary()
    for name in available_catalogs():
        by_scene: dict[tuple[str, str], set[tuple[str, ...]]] = defaultdict(set)
        for task in load_catalog(name):
            for sentence in task.instructions.values():
                by_scene[task.suite, task.scene_task].add(tuple(words(sentence)))
        for scene, sentences in by_scene.items():
            encoded = {tuple(vocab.encode(" ".join(s), len(s))) for s in sentences}
            assert len(encoded) == len(sentences), f"{name} {scene}: two sentences read the same"
            assert all(vocab.tokens.index(UNK) not in ids for ids in encoded)


def test_a_training_sentence_alone_would_read_held_out_sentences_alike():
    """What the fixed vocabulary prevents: trained on one sentence, held-out ones collapse onto <unk>."""
    tasks = load_catalog("full").select("spatial/s0/*")
    alone = Vocabulary.from_texts([tasks[0].instruction()])
    assert len({tuple(alone.encode(t.instruction(), 24)) for t in tasks}) < len(tasks)
    fixed = catalog_vocabulary()
    assert len({tuple(fixed.encode(t.instruction(), 24)) for t in tasks}) == len(tasks)


def test_ids_are_padding_unknown_then_the_sorted_words():
    vocab = Vocabulary(["plate", "bowl", "plate", "<unk>", "<pad>", "akita"])
    assert vocab.tokens == ["<pad>", "<unk>", "akita", "bowl", "plate"] and len(vocab) == 5
    assert Vocabulary.from_texts(["Put the bowl", "the akita_black_bowl_1"]).tokens == [
        "<pad>",
        "<unk>",
        "1",
        "akita",
        "black",
        "bowl",
        "put",
        "the",
    ]


def test_encode_pads_with_zero_truncates_and_reads_an_unknown_word_as_one():
    vocab = Vocabulary(["bowl", "plate", "put"])  # ids: bowl 2, plate 3, put 4
    assert vocab.encode("put bowl", 5) == [4, 2, 0, 0, 0]
    assert vocab.encode("put the bowl on the plate", 3) == [4, 1, 2]
    assert vocab.encode("put the bowl", 3) == [4, 1, 2]
    assert vocab.encode("", 2) == [0, 0]


def test_the_texts_are_every_catalogs_sentences_and_their_scenes_entity_names():
    """`catalog_texts` itself (the vocabulary it makes is cached for the process, so it is read directly)."""
    texts = catalog_texts()
    assert texts == sorted(set(texts))
    for name in available_catalogs():
        for task in load_catalog(name):
            assert set(task.instructions.values()) <= set(texts), task.id
    # the scenes' object and fixture names, as the BDDL files write them
    assert {"glazed_rim_porcelain_ramekin_1", "flat_stove_1", "main_table"} <= set(texts)
    assert catalog_vocabulary().tokens == Vocabulary.from_texts(texts).tokens


def test_a_scene_file_that_does_not_parse_is_named_in_the_error(tmp_path, monkeypatch):
    import langgap.policies.text as text
    from langgap.bddl import BddlError

    broken = tmp_path / "broken-scene.bddl"
    broken.write_text("(define (problem", encoding="utf-8")
    monkeypatch.setattr(text.stack, "bddl_path", lambda suite, scene: broken)  # a damaged install's scene file
    with pytest.raises(BddlError) as raised:
        text.catalog_texts()
    assert str(raised.value).startswith(f"{broken}: ")
