"""Splits: named, stored selections of a catalog's tasks into training tasks and held-out tasks, tied to the
catalog's registry file by its SHA-256.

Three kinds, each with a rule `check` verifies on the stored split:

* `instruction`: the paper's instruction-level split, the catalog's own `split` field (`train` / `heldout`;
  originals are in neither).
* `compositional`: every held-out task pairs an object with a target, or with a relation, in a way no training
  task does, and yet every word of its sentence and every component (object, target, relation; `components`)
  occurs in the training tasks, in other combinations.
* `novel-word`: every held-out task's sentence holds a word that no training sentence holds.

A split also stores nested training subsets (`subsets`: size -> the first tasks of its training tasks in a
seeded order), so that a sweep over the number of training tasks draws the same tasks every time and each
larger set holds the smaller. Shipped splits live in `registry/splits/`, beside the catalogs; a split file of
one's own is given by its path. Select a split's tasks anywhere a selection is taken: `split:NAME:train`,
`split:NAME:heldout`, `split:NAME:K` (its nested subset of K training tasks).
"""

from __future__ import annotations

import json
import random
from collections.abc import Iterable
from dataclasses import asdict, dataclass, field
from importlib import resources
from pathlib import Path

from langgap import vocabulary
from langgap.atomic import write_text_atomically
from langgap.catalog.catalog import Catalog, catalog_hash, load_catalog
from langgap.catalog.task import DEFAULT_STYLE, Task
from langgap.catalog.words import words
from langgap.errors import CatalogError, CatalogParameterError

SPLIT_KINDS = ("instruction", "compositional", "novel-word")
PARTS = ("train", "heldout")


@dataclass(frozen=True)
class Split:
    """A named selection of catalog `catalog`'s tasks (its registry's SHA-256 `catalog_sha256` when made) into
    `train` and `heldout` task ids, made by `rule` (the generator's inputs: selection, seed, sizes, style).
    `subsets` maps a size k to the nested subset of k training tasks (each a prefix of the next)."""

    name: str
    kind: str
    catalog: str
    catalog_sha256: str
    train: tuple[str, ...]
    heldout: tuple[str, ...]
    rule: dict = field(default_factory=dict)
    subsets: dict[int, tuple[str, ...]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.kind not in SPLIT_KINDS:
            raise CatalogError(f"split {self.name}: kind {self.kind!r} is not one of {', '.join(SPLIT_KINDS)}")
        object.__setattr__(self, "train", tuple(self.train))
        object.__setattr__(self, "heldout", tuple(self.heldout))
        object.__setattr__(self, "subsets", {int(k): tuple(v) for k, v in self.subsets.items()})

    @property
    def style(self) -> str:
        """The instruction style whose sentences the split's word rules read."""
        return self.rule.get("style", DEFAULT_STYLE)

    def part(self, part: str) -> tuple[str, ...]:
        """The task ids of `part`: `train`, `heldout`, or a number k (the nested subset of k training tasks)."""
        if part in PARTS:
            return getattr(self, part)
        if part.isdigit() and int(part) in self.subsets:
            return self.subsets[int(part)]
        sizes = ", ".join(map(str, sorted(self.subsets))) or "none stored"
        raise CatalogError(f"split {self.name} has no part {part!r} (train, heldout, or a subset size: {sizes})")

    def to_dict(self) -> dict:
        """The split's JSON form (as stored)."""
        data = asdict(self)
        data["train"], data["heldout"] = list(self.train), list(self.heldout)
        data["subsets"] = {str(k): list(v) for k, v in sorted(self.subsets.items())}
        return data


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


# -- storage ------------------------------------------------------------------------------------------------


def shipped_dir() -> Path:
    """Where the splits that ship with LangGap are stored."""
    return Path(str(resources.files("langgap.catalog") / "registry" / "splits"))


def available_splits() -> list[str]:
    """Names of the shipped splits."""
    return sorted(p.stem for p in shipped_dir().glob("*.json"))


def split_path(name: str) -> Path:
    """The file of split `name`: a shipped split's name, or the path of a split file (`.json`, or holding `/`)."""
    if name.endswith(".json") or "/" in name:
        return Path(name)
    if name not in available_splits():
        raise CatalogError(f"unknown split {name!r} (shipped: {', '.join(available_splits())}; or a split file)")
    return shipped_dir() / f"{name}.json"


def load_split(name: str) -> Split:
    """The split `name` (a shipped name or a file's path), read from its JSON file."""
    path = split_path(name)
    try:
        return Split(**json.loads(path.read_text(encoding="utf-8")))
    except (OSError, json.JSONDecodeError, TypeError) as exc:
        raise CatalogError(f"cannot read split {path}: {exc}") from None


def save_split(split: Split, path: str | Path) -> Path:
    """Write `split` as JSON to `path` (atomically)."""
    path = Path(path)
    write_text_atomically(path, json.dumps(split.to_dict(), indent=1) + "\n")
    return path


def split_tasks(catalog: Catalog, term: str) -> set[str]:
    """The task ids of the selection term `split:NAME:PART` in `catalog` (`Catalog.select`): the split must be
    of this catalog, unchanged since it was made."""
    name, _, part = term.removeprefix("split:").rpartition(":")
    if not name:
        raise CatalogError(f"{term!r}: a split term reads split:NAME:train, split:NAME:heldout or split:NAME:K")
    split = load_split(name)
    if split.catalog != catalog.name:
        raise CatalogParameterError(
            "split {name} is of catalog {of}, not {this}: pass {catalog} {of}",
            name=split.name,
            of=split.catalog,
            this=catalog.name,
        )
    if catalog_hash(split.catalog) != split.catalog_sha256:
        raise CatalogError(f"split {split.name}: catalog {split.catalog} changed since it was made: generate it again")
    return set(split.part(part))
