"""Stored splits: each kind's rule holds on the shipped splits and on generated ones (checked here from the
sentences and goals, not by `check` alone), a changed catalog is caught, and a split selects tasks."""

from __future__ import annotations

import dataclasses
import json

import pytest

from langgap.catalog.catalog import catalog_hash, load_catalog
from langgap.catalog.split_files import available_splits, load_split, save_split
from langgap.catalog.splits import check, generate
from langgap.catalog.words import words
from langgap.cli.main import main
from langgap.errors import CatalogError

COMPOSITIONAL = "full-spatial-s0-compositional"
NOVEL_WORD = "full-spatial-s0-novel-word"


def _words(catalog, ids) -> set[str]:
    return {w for i in ids for w in words(catalog.get(i).instruction())}


def _goal_parts(catalog, task_id) -> tuple[set, set]:
    """(components, pairs) of a task, read straight from its goal's atoms."""
    parts, pairs = set(), set()
    for atom in catalog.get(task_id).bddl_goal:
        obj, *rest = atom.args
        parts |= {("object", obj), ("relation", atom.name), *(("target", t) for t in rest)}
        pairs |= {(obj, atom.name), *((obj, t) for t in rest)}
    return parts, pairs


def _assert_compositional(split) -> None:
    catalog = load_catalog(split.catalog)
    seen_words = _words(catalog, split.train)
    seen_parts = set().union(*(_goal_parts(catalog, i)[0] for i in split.train))
    seen_pairs = set().union(*(_goal_parts(catalog, i)[1] for i in split.train))
    assert split.heldout and not set(split.heldout) & set(split.train)
    for task_id in split.heldout:
        parts, pairs = _goal_parts(catalog, task_id)
        assert _words(catalog, [task_id]) <= seen_words, task_id
        assert parts <= seen_parts, task_id
        assert pairs - seen_pairs, f"{task_id}: no pair of it is new"


# The sweep's shipped splits, one pair per scene: (compositional, novel-word, its pool size, the scene's doable tasks)
SWEEP_SPLITS = [
    (COMPOSITIONAL, NOVEL_WORD, 24, 31, "spatial/s0"),
    ("full-goal-s8-compositional", "full-goal-s8-novel-word", 20, 27, "goal/s8"),
]


@pytest.mark.parametrize(("compositional", "pool_size"), [(c, n) for c, _, n, _, _ in SWEEP_SPLITS])
def test_the_shipped_compositional_splits_hold_out_new_combinations_of_seen_words_and_parts(compositional, pool_size):
    split = load_split(compositional)
    _assert_compositional(split)
    assert (len(split.train), len(split.heldout)) == (pool_size, 4)


def test_a_generated_compositional_split_does_too():
    full = load_catalog("full")
    split = generate("compositional", "s1", full, "spatial/s1/*&feasible", heldout=5, seed=3, subsets=(2, 4))
    _assert_compositional(split)
    assert len(split.heldout) == 5 and check(split) == []
    assert split == generate("compositional", "s1", full, "spatial/s1/*&feasible", heldout=5, seed=3, subsets=(2, 4))


def test_novel_word_splits_hold_out_a_sentence_with_a_word_training_never_says():
    full = load_catalog("full")
    generated = generate("novel-word", "s1", full, "spatial/s1/*&feasible", heldout=4, seed=1)
    for split in (load_split(NOVEL_WORD), generated):
        seen = _words(full, split.train)
        assert split.heldout and all(_words(full, [i]) - seen for i in split.heldout)
    # the words are the style's: the paper's sentence of the original alone says "akita"
    one = {style: generate("novel-word", "one", full, "spatial/s0/*&feasible", heldout=1, style=style).heldout
           for style in ("libero", "paper")}  # fmt: skip
    assert one == {"libero": ("spatial/s0/turn-on-stove",), "paper": ("spatial/s0/black-bowl-1-on-plate",)}
    # the shipped one: each of its three sentences has its own word no training sentence has
    shipped = load_split(NOVEL_WORD)
    unseen = {i: _words(full, [i]) - _words(full, shipped.train) for i in shipped.heldout}
    assert unseen == {
        "spatial/s0/open-cabinet-bottom-drawer": {"bottom"},
        "spatial/s0/open-cabinet-middle-drawer": {"middle"},
        "spatial/s0/turn-on-stove": {"turn"},
    }


@pytest.mark.parametrize(("compositional", "novel_word", "pool_size", "doable", "scene"), SWEEP_SPLITS)
def test_the_sweep_trains_on_nested_subsets_of_a_pool_that_holds_no_held_out_task(
    compositional, novel_word, pool_size, doable, scene
):
    pool, novel = load_split(compositional), load_split(novel_word)
    full = load_catalog("full")
    assert sorted(pool.subsets) == [1, 3, 6, 12, pool_size]
    previous: tuple[str, ...] = ()
    for size, ids in sorted(pool.subsets.items()):
        assert len(ids) == size and ids[: len(previous)] == previous and set(ids) <= set(pool.train)
        previous = ids
    assert set(previous) == set(pool.train)
    assert not set(pool.train) & (set(pool.heldout) | set(novel.heldout))
    assert all(_words(full, [i]) - _words(full, pool.train) for i in novel.heldout)
    every = {t.id for t in full.select(f"{scene}/*&feasible")}
    assert set(pool.train) | set(pool.heldout) | set(novel.heldout) == every and len(every) == doable


def test_every_shipped_split_checks():
    sweeps = {name for compositional, novel_word, *_ in SWEEP_SPLITS for name in (compositional, novel_word)}
    assert set(available_splits()) >= {*sweeps, "langgap99-instruction"}
    assert {name: check(load_split(name)) for name in available_splits()} == {n: [] for n in available_splits()}
    paper = load_split("langgap99-instruction")
    assert (len(paper.train), len(paper.heldout)) == (16, 43)  # the paper's instruction-level split


def test_a_split_that_breaks_its_rule_or_outlives_its_catalog_is_caught(tmp_path, capsys):
    novel = load_split(NOVEL_WORD)
    leaked = dataclasses.replace(novel, train=(*novel.train, "spatial/s0/open-cabinet-bottom-drawer"))
    assert check(leaked) == [
        "in training and held out: spatial/s0/open-cabinet-bottom-drawer",
        "spatial/s0/open-cabinet-bottom-drawer: every word of its sentence is in a training sentence",
    ]
    stove = ("spatial/s0/plate-on-stove",)
    moved = dataclasses.replace(
        novel, train=(*novel.train, "spatial/s0/turn-on-stove"), heldout=novel.heldout[:2] + stove
    )
    assert check(moved) == ["spatial/s0/plate-on-stove: every word of its sentence is in a training sentence"]
    pool = load_split(COMPOSITIONAL)
    broken = dataclasses.replace(pool, train=pool.train[1:])  # the only task saying "plate" and "black bowl 1"
    assert check(broken) and all(p.startswith(pool.heldout) or "subset" in p for p in check(broken))

    # every word of "...place it on the wooden cabinet" is said in training, but never its target, the cabinet's top
    words_only = dataclasses.replace(
        pool,
        train=("spatial/s0/ramekin-in-cabinet-top-drawer", "spatial/s0/cookie-box-on-plate"),
        heldout=("spatial/s0/ramekin-on-cabinet-top",),
        subsets={},
    )
    assert check(words_only) == [
        "spatial/s0/ramekin-on-cabinet-top: components never in training: target wooden_cabinet_1_top_side"
    ]

    # the paper's sentence of the original says "akita", which no training sentence says in that style
    akita = dataclasses.replace(
        words_only,
        train=("spatial/s0/black-bowl-1-on-stove", "spatial/s0/ramekin-on-plate"),
        heldout=("spatial/s0/black-bowl-1-on-plate",),
        rule={**pool.rule, "style": "paper"},
    )
    assert check(akita) == ["spatial/s0/black-bowl-1-on-plate: words never in training: akita"]
    # a reworded sentence of a trained goal is no new combination
    plus = load_catalog("libero-plus-language")
    reworded = dataclasses.replace(
        words_only,
        catalog=plus.name,
        catalog_sha256=catalog_hash(plus.name),
        train=("spatial/s0/black-bowl-1-on-plate",),
        heldout=("spatial/s0/plus-language-1",),
    )
    problem = "every pair (object, target) and (object, relation) of it occurs in training"
    assert check(reworded) == [f"spatial/s0/plus-language-1: {problem}"]

    stale = dataclasses.replace(pool, catalog_sha256="0" * 64)
    (problem,) = check(stale)
    assert "catalog full changed since the split was made" in problem
    path = save_split(stale, tmp_path / "stale.json")
    with pytest.raises(CatalogError, match="changed since it was made"):
        load_catalog("full").select(f"split:{path}:heldout")
    assert main(["splits", "check", str(path)]) == 1
    assert "changed since the split was made" in capsys.readouterr().out


def test_a_split_selects_its_tasks():
    full = load_catalog("full")
    pool = load_split(COMPOSITIONAL)
    assert [t.id for t in full.select(f"split:{COMPOSITIONAL}:heldout")] == list(pool.heldout)
    assert {t.id for t in full.select(f"split:{COMPOSITIONAL}:train")} == set(pool.train)
    assert {t.id for t in full.select(f"split:{COMPOSITIONAL}:6")} == set(pool.subsets[6])
    chosen = full.select(f"split:{COMPOSITIONAL}:12&!split:{COMPOSITIONAL}:3")
    assert {t.id for t in chosen} == set(pool.subsets[12]) - set(pool.subsets[3])
    with pytest.raises(CatalogError, match="no part '5'"):
        full.select(f"split:{COMPOSITIONAL}:5")
    with pytest.raises(CatalogError, match="is of catalog full, not langgap99"):
        load_catalog("langgap99").select(f"split:{COMPOSITIONAL}:train")


@pytest.mark.parametrize(
    "argv",
    [
        ["splits", "show", "no-such-split"],
        ["splits", "check", "no-such-split"],
        ["tasks", "list", "--catalog", "full", "--tasks", "split:no-such-split:train"],
    ],
)
def test_a_bad_split_name_is_one_error_line(argv, capsys):
    assert main(argv) != 0
    captured = capsys.readouterr()
    assert captured.err.startswith("error: unknown split 'no-such-split'") and captured.err.count("\n") == 1


def test_generate_writes_a_file_that_shows_and_checks(tmp_path, capsys):
    out = tmp_path / "mine.json"
    argv = ["splits", "generate", "novel-word", "--name", "mine", "--catalog", "full", "--tasks",
            "spatial/s1/*&feasible", "--heldout", "3", "--subsets", "1,2", "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    data = json.loads(out.read_text())
    assert data["kind"] == "novel-word" and len(data["heldout"]) == 3 and list(data["subsets"]) == ["1", "2"]
    assert main(["splits", "check", str(out)]) == 0 and f"{out}: ok" in capsys.readouterr().out
    assert main(["splits", "show", str(out)]) == 0 and "[unseen: " in capsys.readouterr().out
    assert main(["splits", "show", str(out), "--json"]) == 0 and json.loads(capsys.readouterr().out) == data


def test_show_marks_a_held_out_task_that_says_a_libero_sentence(capsys):
    # goal/s8's own original, and goal/s3's sentence on the shared LIBERO-goal layout: held out from the pool only
    assert main(["splits", "show", "full-goal-s8-compositional"]) == 0
    out = capsys.readouterr().out
    marked = {line.split()[0] for line in out.splitlines() if line.endswith("a LIBERO sentence]")}
    assert marked == {"goal/s8/black-bowl-on-plate", "goal/s8/black-bowl-in-cabinet-top-drawer"}
    assert "2 held-out task(s) say a LIBERO task's sentence" in out
    assert main(["splits", "show", COMPOSITIONAL]) == 0
    assert "LIBERO" not in capsys.readouterr().out
