"""`langgap splits generate`, `list`, `show` and `check`: stored train/held-out splits of a catalog's tasks."""

from __future__ import annotations

import json

from langgap.catalog.catalog import DEFAULT_CATALOG, catalog_hash, load_catalog
from langgap.catalog.split_files import SPLIT_KINDS, available_splits, load_split, save_split
from langgap.catalog.splits import check, generate, libero_sentences, novel_words
from langgap.catalog.task import DEFAULT_STYLE, INSTRUCTION_STYLES
from langgap.errors import LangGapError
from langgap.vocabulary import Split


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("splits", help="make, list, show and check stored train/held-out splits")
    verbs = parser.add_subparsers(dest="splits_verb", required=True, metavar="generate|list|show|check")

    make = verbs.add_parser("generate", help="split a selection of tasks by a rule and write the split file")
    make.add_argument("kind", choices=SPLIT_KINDS, help="the rule: the catalog's own split, or held-out tasks "
                      "composed of seen parts, or each with a word no training sentence holds")  # fmt: skip
    make.add_argument("--name", required=True, help="the split's name")
    make.add_argument("--out", required=True, metavar="FILE", help="the split file to write (.json)")
    make.add_argument("--catalog", default=DEFAULT_CATALOG, help="shipped catalog (default: %(default)s)")
    make.add_argument("--tasks", metavar="SELECTION", default="feasible", help="tasks to split (default: %(default)s)")
    make.add_argument("--heldout", type=int, default=0, help="how many tasks to hold out (compositional, novel-word)")
    make.add_argument("--seed", type=int, default=0, help="orders candidates and training tasks (default: 0)")
    make.add_argument(
        "--style",
        choices=INSTRUCTION_STYLES,
        default=DEFAULT_STYLE,
        help="sentences the word rules read (default: %(default)s)",
    )
    make.add_argument("--subsets", metavar="K,K,...", help="sizes of nested training subsets to store (e.g. 1,3,6)")
    make.set_defaults(handler=run_generate)

    listing = verbs.add_parser("list", help="the shipped splits")
    listing.set_defaults(handler=run_list)

    show = verbs.add_parser("show", help="one split's tasks and sentences")
    show.add_argument("split", help="shipped split name or split file")
    show.add_argument("--json", action="store_true", help="print the split file's JSON")
    show.set_defaults(handler=run_show)

    verify = verbs.add_parser("check", help="verify splits against their rule and their catalog (default: shipped)")
    verify.add_argument("split", nargs="*", help="shipped split names or split files")
    verify.add_argument(
        "--demos",
        metavar="DIR",
        help="also replay this collection's demonstrations: does any pass through a held-out task's goal, or "
        "demonstrate a held-out task?",
    )
    verify.set_defaults(handler=run_check)


def _sizes(text: str | None) -> list[int]:
    if not text:
        return []
    try:
        return [int(k) for k in text.split(",")]
    except ValueError:
        raise LangGapError(f"--subsets {text}: expected sizes such as 1,3,6") from None


def run_generate(args) -> int:
    catalog = load_catalog(args.catalog)
    split = generate(
        args.kind, args.name, catalog, args.tasks, heldout=args.heldout, seed=args.seed, style=args.style,
        subsets=_sizes(args.subsets),
    )  # fmt: skip
    problems = check(split)
    if problems:  # a generator that broke its own rule: never written
        raise LangGapError(f"split {split.name} breaks its own rule: {problems[0]}")
    save_split(split, args.out)
    print(f"{split.name}: {len(split.train)} training, {len(split.heldout)} held-out tasks ({split.kind}); "
          f"wrote {args.out}")  # fmt: skip
    return 0


def run_list(args) -> int:
    print(f"{'split':34} {'kind':14} {'catalog':10} {'train':>5} {'held':>5}  catalog unchanged")
    for name in available_splits():
        split = load_split(name)
        same = "yes" if catalog_hash(split.catalog) == split.catalog_sha256 else "no: generate it again"
        print(f"{name:34} {split.kind:14} {split.catalog:10} {len(split.train):5} {len(split.heldout):5}  {same}")
    return 0


def run_show(args) -> int:
    split = load_split(args.split)
    if args.json:
        print(json.dumps(split.to_dict(), indent=1))
        return 0
    catalog = load_catalog(split.catalog)
    print(f"{split.name}: {split.kind} split of catalog {split.catalog} (registry {split.catalog_sha256[:12]})")
    print(f"rule: {json.dumps(split.rule)}")
    train = [catalog.get(i) for i in split.train]
    libero = libero_sentences(catalog)
    known = [i for i in split.heldout if catalog.get(i).instruction() in libero]
    for part, ids in (("train", split.train), ("heldout", split.heldout)):
        print(f"\n{part} ({len(ids)}):")
        for task in map(catalog.get, ids):
            notes = []
            if part == Split.HELDOUT:
                if unseen := sorted(novel_words(task, train, split.style)):
                    notes.append(f"unseen: {', '.join(unseen)}")
                if task.id in known:
                    notes.append("a LIBERO sentence")
            note = f"   [{'; '.join(notes)}]" if notes else ""
            print(f"  {task.id:50} {task.instruction(split.style)}{note}")
    if known:
        print(
            f"\n{len(known)} held-out task(s) say a LIBERO task's sentence: held out from this split's training, "
            "not from LIBERO's (a policy fine-tuned on LIBERO has trained on them)"
        )
    for size, ids in sorted(split.subsets.items()):
        print(f"\nsubset {size}: {', '.join(ids)}")
    return 0


def run_check(args) -> int:
    names = args.split or available_splits()
    splits = [load_split(name) for name in names]
    found = _collection_reach(splits, args.demos) if args.demos else None
    failed = 0
    for name, split in zip(names, splits, strict=True):
        problems = check(split)
        if found is not None:
            problems += _collection_problems(split, args.demos, found.among(split.heldout))
        print(f"{name}: {'ok' if not problems else f'{len(problems)} problem(s)'}")
        for problem in problems:
            print(f"  {problem}")
        failed += bool(problems)
    return 1 if failed else 0


def _collection_reach(splits, root: str):
    """`splits check --demos`: the collection replayed once for every split's held-out tasks."""
    from langgap.demos.reach import goals_reached

    heldout = {i: load_catalog(split.catalog).get(i) for split in splits for i in split.heldout}
    return goals_reached(root, list(heldout.values()))


def _collection_problems(split, root: str, found) -> list[str]:
    """The held-out tasks of `split` the collection at `root` demonstrates, or whose goals it passes through
    (`found`: its `CollectionReach` among them)."""
    held = f"{root} holds {found.total} demonstration(s) of {len(found.demonstrations)} task(s)"
    if not found.replayed:  # a collection of another scene: its "ok" says nothing of this split
        print(f"{split.name}: {held}, none set in a held-out task's scene: the collection is not checked against it")
    else:
        print(f"{split.name}: {held}; {found.replayed} set in a held-out task's scene, replayed state by state")
    if found.last_unknown:
        print(f"  note: {found.last_unknown} of them do not replay to their goal on this physics stack: the state "
              "after their last action is not judged")  # fmt: skip
    problems = [f"{root} demonstrates held-out task {i} ({found.demonstrations[i]} demonstration(s))"
                for i in split.heldout if found.demonstrations[i]]  # fmt: skip
    for goal_id in split.heldout:
        if by := found.reached.get(goal_id):
            tasks = ", ".join(f"{task} {n}" for task, n in by.most_common())
            problems.append(
                f"held-out goal {goal_id} is reached by {sum(by.values())} of {found.total} demonstration(s) "
                f"({tasks}): held out by its sentence, not from the collection's states"
            )
    return problems
