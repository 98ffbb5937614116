"""`langgap experiment`: the paper's fine-tuning experiments end to end with LeRobot's policies (`run`), what
they are (`list`), and the tiny SmolVLM a CPU rehearsal of SmolVLA trains on (`tiny-smolvlm`)."""

from __future__ import annotations

from pathlib import Path

from langgap.errors import LangGapError


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "experiment", help="run one of the paper's fine-tuning experiments end to end (collect → train → eval)"
    )
    verbs = parser.add_subparsers(dest="experiment_verb", required=True, metavar="run|list|tiny-smolvlm")

    listing = verbs.add_parser("list", help="the experiments, with the paper's counts, and the policies' tunings")
    listing.set_defaults(handler=run_list)

    run = verbs.add_parser(
        "run", help="collect → export → merge → lerobot-train → eval → report, skipping stages already done"
    )
    run.add_argument("experiment", metavar="EXPERIMENT", help="exp1..exp5, or a YAML file of the same form")
    run.add_argument("--out", required=True, metavar="DIR", help="output directory (re-running continues it)")
    run.add_argument("--policy", default="pi05", help="pi05 (the paper's), pi0, smolvla, act, or a recipe YAML file")
    run.add_argument("--tuning", help="which parameters train (the policy's tunings: `langgap experiment list`)")
    run.add_argument(
        "--tiny", action="store_true", help="rehearse on this machine with the policy's tiny random-weight model"
    )
    run.add_argument("--dry-run", action="store_true", help="print the plan (stages, counts, commands) and exit")
    run.add_argument("--catalog", default=None, help="the catalog the experiment's selections use (langgap99)")
    run.add_argument("--demos", type=int, metavar="N", help="demonstrations per task of every group (a rehearsal)")
    run.add_argument("--steps", type=int, metavar="N", help="training steps instead of the experiment's")
    run.add_argument("--episodes", type=int, metavar="N", help="evaluation episodes per task instead of the file's")
    run.add_argument(
        "--eval-sets", metavar="SETS", help="comma-separated: trained, heldout, original (default: every set)"
    )
    run.add_argument("--image-size", type=int, metavar="PX", help="dataset image size (default: the policy's)")
    run.add_argument("--seed", type=int, default=0, help="collection seed (attempt j uses env seed SEED+j)")
    run.add_argument("--noise", type=float, default=0.0, metavar="SIGMA", help="demonstrations' execution noise")
    run.add_argument(
        "--allow-short",
        action="store_true",
        help="train on a collection in which some task kept fewer demonstrations than asked (default: stop)",
    )
    run.add_argument(
        "--originals", metavar="DIR", help="a local LeRobot dataset of LIBERO's originals to use, not collect"
    )
    run.add_argument("--device", default="cuda", help="where the policy trains and runs (default: cuda)")
    run.add_argument("--workers", type=int, default=1, help="processes for collecting, rendering and evaluating")
    run.add_argument("--set", action="append", metavar="KEY=VALUE", help="a lerobot-train option (repeatable)")
    run.set_defaults(handler=run_experiment, smoke=("demos", "steps", "episodes", "workers"))

    tiny = verbs.add_parser("tiny-smolvlm", help="write a tiny random-weight SmolVLM directory (LeRobot environment)")
    tiny.add_argument("out", metavar="DIR", help="the model directory to write")
    tiny.add_argument("--image-size", type=int, default=64, metavar="PX", help="its image size (default: 64)")
    tiny.set_defaults(handler=run_tiny_smolvlm)


NO_PAPER_ROW = "none (not one of the paper's experiments)"


def run_list(args) -> int:
    from langgap.catalog.catalog import load_catalog
    from langgap.training.lerobot_train import EXPERIMENTS, POLICIES, load_experiment, load_recipe

    catalog = load_catalog()
    print(f"{'experiment':<11} {'paper: demos':>12} {'here':>6}  {'steps':>7}  rank  title")
    for name in EXPERIMENTS:
        e = load_experiment(name)
        here = e.demonstrations(catalog)
        print(f"{name:<11} {e.paper['demos']:>12} {here:>6}  {e.steps:>7}  {e.lora_rank:>4}  {e.title}")
    for name in POLICIES:
        recipe = load_recipe(name)
        tiny = "tiny rehearsal: yes" if recipe.tiny is not None else f"no tiny rehearsal: {recipe.tiny_blocked_by}"
        print(f"\n{recipe.title}\n  {tiny}")
        for tuning in recipe.tunings.values():
            default = " (default)" if tuning.name == recipe.default_tuning else ""
            print(f"  --tuning {tuning.name}{default}: trains {tuning.trains}; frozen: {tuning.frozen}")
    return 0


def _settings(args):
    from langgap.cli.policy_options import parse_key_values
    from langgap.training.experiment_run import Settings
    from langgap.training.lerobot_train import EVAL_SETS

    overrides = parse_key_values(args.set, "--set")
    if args.steps is not None:
        overrides["steps"] = str(args.steps)
    sets = tuple(s.strip() for s in args.eval_sets.split(",")) if args.eval_sets else None
    if sets and set(sets) - set(EVAL_SETS):
        raise LangGapError(f"--eval-sets takes {', '.join(EVAL_SETS)}; got {args.eval_sets!r}")
    for flag in ("demos", "steps", "episodes", "image_size"):
        if getattr(args, flag) is not None and getattr(args, flag) < 1:
            raise LangGapError(f"--{flag.replace('_', '-')} must be at least 1")
    originals = Path(args.originals) if args.originals else None
    if originals is not None and not (originals / "meta" / "info.json").exists():
        raise LangGapError(f"--originals {originals}: not a LeRobot dataset (no meta/info.json)")
    return Settings(
        out=Path(args.out),
        tuning=args.tuning,
        tiny=args.tiny,
        image_size=args.image_size,
        demos=args.demos,
        episodes=args.episodes,
        eval_sets=sets,
        seed=args.seed,
        noise=args.noise,
        originals=originals,
        device=args.device,
        workers=args.workers,
        allow_short=args.allow_short,
        overrides=overrides,
    )


def run_experiment(args) -> int:
    from langgap.catalog.catalog import DEFAULT_CATALOG, load_catalog
    from langgap.training.experiment_run import plan, run, summary
    from langgap.training.lerobot_train import load_experiment, load_recipe
    from langgap.vocabulary import TaskKind

    experiment = load_experiment(args.experiment)
    recipe = load_recipe(args.policy)
    settings = _settings(args)
    catalog = args.catalog or DEFAULT_CATALOG
    stages = plan(experiment, recipe, settings, catalog)
    tuning = recipe.tuning(settings.tuning)
    tasks = load_catalog(catalog)
    print(f"{experiment.name}: {experiment.title}")
    print(f"  paper: {experiment.paper or NO_PAPER_ROW}")
    for group in experiment.train:
        count = len(tasks.select(group.tasks))
        demos = settings.demos or group.demos
        source = " (from --originals)" if settings.originals and group.tasks == TaskKind.ORIGINAL else ""
        print(f"  train: {group.tasks}: {count} tasks x {demos} demonstrations = {count * demos}{source}")
    paper_demos = f" (paper: {experiment.paper['demos']})" if "demos" in experiment.paper else ""
    print(f"  demonstrations: {experiment.demonstrations(tasks, settings.demos)}{paper_demos}")
    print(f"  policy: {recipe.title}{' -- tiny random-weight rehearsal' if settings.tiny else ''}")
    print(f"  tuning {tuning.name}: trains {tuning.trains}; frozen: {tuning.frozen}")
    for index, stage in enumerate(stages, 1):
        state = "done" if stage.done() else "to run"
        print(f"  [{index}] {stage.name} ({state}): {stage.shown()}")
    if args.dry_run:
        return 0
    run(stages, times=settings.out / "times.tsv")
    text = summary(experiment, recipe, settings, catalog)
    (settings.out / "experiment.md").write_text(text, encoding="utf-8")
    print(text, end="")
    print(f"wrote {settings.out / 'experiment.md'}, {settings.out / 'report.md'} and {settings.out / 'report'}")
    return 0


def run_tiny_smolvlm(args) -> int:
    from langgap.policies.text import catalog_texts
    from langgap.training.tiny_smolvlm import build_tiny_smolvlm

    try:
        out = build_tiny_smolvlm(args.out, image_size=args.image_size, texts=catalog_texts())
    except ValueError as exc:
        raise LangGapError(f"--image-size: {exc}") from None
    print(f"wrote a tiny SmolVLM (config, processor, tokenizer; no weights) to {out}")
    return 0
