"""Splits: named, stored selections of a catalog's tasks into training tasks and held-out tasks, tied to the
catalog's registry file by its SHA-256.

Three kinds, each with a rule `check` verifies on the stored split:

* `instruction`: the paper's instruction-level split, the catalog's own `split` field (`train` / `heldout`;
  originals are in neither).
* `compositional`: every held-out task pairs an object with a target, or with a relation, in a way no training
  task does, and yet every word of its sentence and every component (object, target, relation; `components`)
  occurs in the training tasks, in other combinations.
* `novel-word`: every held-out task's sentence holds a word that no training sentence holds.

The rules are about the split's own training tasks: a task is held out from them, not from LIBERO. A held-out
task may say a LIBERO task's sentence (`libero_sentences`; LIBERO-goal's ten tasks share one layout, so each
goal scene holds the other nine's sentences, and a spatial scene can hold a goal task's), which a policy
fine-tuned on LIBERO has trained on; `langgap splits show` marks each.

A split also stores nested training subsets (`subsets`: size -> the first tasks of its training tasks in a
seeded order), so that a sweep over the number of training tasks draws the same tasks every time and each
larger set holds the smaller. Shipped splits live in `registry/splits/`, beside the catalogs; a split file of
one's own is given by its path. Select a split's tasks anywhere a selection is taken: `split:NAME:train`,
`split:NAME:heldout`, `split:NAME:K` (its nested subset of K training tasks).
"""

from __future__ import annotations

import random
from collections.abc import Iterable

from langgap import vocabulary
from langgap.catalog.catalog import Catalog, catalog_hash, load_catalog
from langgap.catalog.split_files import SPLIT_KINDS, Split
from langgap.catalog.task import DEFAULT_STYLE, Task
from langgap.catalog.words import words
from langgap.errors import CatalogError, CatalogParameterError

# -- the parts of a task ------------------------------------------------------------------------------------


def components(task: Task) -> set[tuple[str, str]]:
    """The components of `task`'s goal, each tagged with its role: ("object", o), ("target", t), ("relation", r).

    Per atom of the goal's BDDL conjunction: a binary atom `(On o t)` has object o, target t and relation On; a
    unary one `(Open d)` has object d and relation Open.
    """
    found: set[tuple[str, str]] = set()
    for atom in task.bddl_goal:
        found |= {("object", atom.args[0]), ("relation", atom.name)}
        if len(atom.args) > 1:
            found.add(("target", atom.args[1]))
    return found


def pairs(task: Task) -> set[tuple[str, str, str]]:
    """The (object, target) and (object, relation) pairs of `task`'s goal, tagged: ("target", o, t), ("relation",
    o, r)."""
    found: set[tuple[str, str, str]] = set()
    for atom in task.bddl_goal:
        found.add(("relation", atom.args[0], atom.name))
        if len(atom.args) > 1:
            found.add(("target", atom.args[0], atom.args[1]))
    return found


def task_words(task: Task, style: str = DEFAULT_STYLE) -> set[str]:
    """The words of `task`'s instruction in `style`."""
    return set(words(task.instruction(style)))


def _union(sets: Iterable[set]) -> set:
    return set().union(*sets)


def compositional_problem(task: Task, train: list[Task], style: str) -> str | None:
    """Why `task` is not a compositional held-out task for training tasks `train`, or None when it is."""
    if not pairs(task) - _union(pairs(t) for t in train):
        return "every pair (object, target) and (object, relation) of it occurs in training"
    if missing := task_words(task, style) - _union(task_words(t, style) for t in train):
        return f"words never in training: {', '.join(sorted(missing))}"
    if missing := components(task) - _union(components(t) for t in train):
        return f"components never in training: {', '.join(f'{r} {n}' for r, n in sorted(missing))}"
    return None


def libero_sentences(catalog: Catalog) -> set[str]:
    """The sentences of `catalog`'s original (LIBERO) tasks in LIBERO's own style: what a policy fine-tuned on
    LIBERO has read."""
    return {t.instruction() for t in catalog if t.kind == vocabulary.TaskKind.ORIGINAL}


def novel_words(task: Task, train: list[Task], style: str) -> set[str]:
    """The words of `task`'s sentence that no training task's sentence holds."""
    return task_words(task, style) - _union(task_words(t, style) for t in train)


# -- generating ---------------------------------------------------------------------------------------------


def generate(
    kind: str,
    name: str,
    catalog: Catalog,
    selection: str,
    *,
    heldout: int = 0,
    seed: int = 0,
    style: str = DEFAULT_STYLE,
    subsets: Iterable[int] = (),
) -> Split:
    """A split of the tasks `selection` picks from `catalog` (every one goes to training or held out).

    Args:
        kind: One of `SPLIT_KINDS`.
        name: The split's name.
        catalog: The catalog (a shipped one, whose registry hash the split records).
        selection: Which tasks (`Catalog.select`'s expression).
        heldout: How many tasks to hold out (`compositional`, `novel-word`; the instruction split's are the
            catalog's).
        seed: Orders the candidates and the training tasks: the same inputs give the same split.
        style: The instruction style whose sentences the word rules read.
        subsets: Sizes of the nested training subsets to store.

    Raises:
        CatalogError: An unknown kind, a selection that leaves too few tasks for the rule, a subset larger than
            the training tasks.
    """
    tasks = catalog.select(selection)
    rng = random.Random(seed)
    if kind == "instruction":
        held = [t for t in tasks if t.split == vocabulary.Split.HELDOUT]
        train = [t for t in tasks if t.split == vocabulary.Split.TRAIN]
    elif kind in ("compositional", "novel-word"):
        if heldout <= 0 or heldout >= len(tasks):
            raise CatalogParameterError(
                "{heldout} must be between 1 and {most} for {count} selected tasks",
                most=len(tasks) - 1,
                count=len(tasks),
            )
        pick = _compositional if kind == "compositional" else _novel_word
        held = pick(tasks, heldout, rng, style)
        train = [t for t in tasks if t not in held]
    else:
        raise CatalogError(f"unknown split kind {kind!r} (known: {', '.join(SPLIT_KINDS)})")
    if not train or not held:
        raise CatalogError(f"split {name}: the selection {selection!r} leaves no training or no held-out task")
    order = [t.id for t in train]
    rng.shuffle(order)
    sizes = sorted(set(subsets))
    if sizes and (sizes[0] < 1 or sizes[-1] > len(order)):
        raise CatalogError(f"subset sizes must be between 1 and the {len(order)} training tasks")
    rule = {"selection": selection, "seed": seed, "style": style}
    if kind != "instruction":
        rule["heldout"] = heldout
    return Split(
        name=name,
        kind=kind,
        catalog=catalog.name,
        catalog_sha256=catalog_hash(catalog.name),
        train=tuple(t.id for t in train),
        heldout=tuple(t.id for t in held),
        rule=rule,
        subsets={k: tuple(order[:k]) for k in sizes},
    )


def _compositional(tasks: list[Task], count: int, rng: random.Random, style: str) -> list[Task]:
    """`count` tasks that stay compositional together, tried in a seeded order: one is kept only if every kept
    task is still compositional against what would remain for training."""
    candidates = list(tasks)
    rng.shuffle(candidates)
    held: list[Task] = []
    for task in candidates:
        trial = [*held, task]
        train = [t for t in tasks if t not in trial]
        if all(compositional_problem(t, train, style) is None for t in trial):
            held = trial
            if len(held) == count:
                return sorted(held, key=tasks.index)
    raise CatalogError(f"only {len(held)} compositional held-out tasks found among {len(tasks)}, not {count}")


def _novel_word(tasks: list[Task], count: int, rng: random.Random, style: str) -> list[Task]:
    """`count` tasks holding a word no other kept task's sentence holds: words are taken from the rarest up (ties
    in a seeded order), each with every task that says it, while they fit in `count`."""
    by_word: dict[str, list[Task]] = {}
    for task in tasks:
        for word in sorted(task_words(task, style)):
            by_word.setdefault(word, []).append(task)
    ordered = sorted(by_word)
    rng.shuffle(ordered)
    ordered.sort(key=lambda w: len(by_word[w]))
    held: list[Task] = []
    for word in ordered:
        saying = [t for t in by_word[word] if t not in held]
        if len(held) + len(saying) <= count and len(by_word[word]) < len(tasks):
            held += saying
        if len(held) == count:
            return sorted(held, key=tasks.index)
    raise CatalogError(f"only {len(held)} held-out tasks with an unseen word fit among {len(tasks)}, not {count}")


# -- checking -----------------------------------------------------------------------------------------------


def check(split: Split) -> list[str]:
    """What is wrong with `split` (empty: nothing): its catalog changed since it was made (another registry
    hash), a task the catalog lacks, a task in both parts, subsets that are not nested training tasks, or a
    held-out task that breaks its kind's rule."""
    current = catalog_hash(split.catalog)
    if current != split.catalog_sha256:
        return [
            f"catalog {split.catalog} changed since the split was made (registry SHA-256 {current[:12]}, the split's "
            f"{split.catalog_sha256[:12]}): generate it again"
        ]
    catalog = load_catalog(split.catalog)
    known = {t.id for t in catalog}
    problems = [f"task {i} is not in catalog {split.catalog}" for i in (*split.train, *split.heldout) if i not in known]
    if problems:
        return problems
    if both := set(split.train) & set(split.heldout):
        problems.append(f"in training and held out: {', '.join(sorted(both))}")
    previous: tuple[str, ...] = ()
    for size, ids in sorted(split.subsets.items()):
        if len(ids) != size or ids[: len(previous)] != previous or not set(ids) <= set(split.train):
            problems.append(f"subset {size} is not {size} training tasks extending the smaller subsets")
        previous = ids
    train = [catalog.get(i) for i in split.train]
    for task in map(catalog.get, split.heldout):
        if split.kind == "instruction" and task.split != vocabulary.Split.HELDOUT:
            problems.append(f"{task.id}: the catalog's split is {task.split}, not heldout")
        elif split.kind == "compositional" and (why := compositional_problem(task, train, split.style)):
            problems.append(f"{task.id}: {why}")
        elif split.kind == "novel-word" and not novel_words(task, train, split.style):
            problems.append(f"{task.id}: every word of its sentence is in a training sentence")
    if split.kind == "instruction":
        problems += [
            f"{t.id}: the catalog's split is {t.split}, not train" for t in train if t.split != vocabulary.Split.TRAIN
        ]
    return problems
