"""`langgap collect`: scripted oracle demonstrations from fresh placements, as a LeRobot dataset (+ compact form)."""

from __future__ import annotations

from langgap.cli.execution_flags import add_execution_options, execution_options
from langgap.cli.tasks_cmd import add_catalog_options


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "collect",
        help="record N successful oracle demonstrations per task from fresh placements (never evaluation inits)",
    )
    add_catalog_options(parser)
    parser.add_argument("--tasks", required=True, metavar="SELECTION", help="task selection (e.g. train, spatial)")
    parser.add_argument("--demos", type=int, required=True, metavar="N", help="successful demonstrations per task")
    parser.add_argument("--out", required=True, metavar="DIR", help="new collection directory")
    parser.add_argument("--seed", type=int, default=0, help="attempt j of every task uses env seed SEED+j")
    parser.add_argument(
        "--noise",
        type=float,
        default=0.0,
        metavar="SIGMA",
        help="execution noise on the oracle's motion commands (std); labels stay the clean commands (DART)",
    )
    parser.add_argument(
        "--max-attempts", type=int, default=0, help="demonstration attempts per task before giving up (3N+10)"
    )
    parser.add_argument(
        "--format",
        choices=("auto", "compact", "lerobot"),
        default="auto",
        help="compact: NPZ only; lerobot: also the LeRobot v3 dataset (needs LeRobot); auto: lerobot if installed",
    )
    # A task's collection is one work item: its infrastructure retries have their own flag.
    add_execution_options(
        parser,
        attempts_flag="--max-task-attempts",
        attempts_help="tries at collecting a task when the machinery fails (a worker crash, a timeout; not a failed "
        "demonstration, which --max-attempts counts) before the command stops with an error (default: %(default)s)",
    )
    parser.set_defaults(handler=run, smoke=("tasks", "demos", "workers"))


def run(args) -> int:
    from langgap.catalog.catalog import load_catalog
    from langgap.demos.collect import CollectConfig, collect
    from langgap.demos.compact import short_tasks
    from langgap.demos.export import lerobot_available, write_lerobot_dataset
    from langgap.errors import LangGapError

    if args.demos < 1:
        raise LangGapError("--demos must be at least 1")
    export = args.format == "lerobot" or (args.format == "auto" and lerobot_available())
    if args.format == "lerobot" and not lerobot_available():
        raise LangGapError("--format lerobot needs LeRobot: run this in .venv-lerobot (./setup.sh makes it)")
    tasks = tuple(t.id for t in load_catalog(args.catalog).select(args.tasks))
    config = CollectConfig(
        catalog=args.catalog,
        tasks=tasks,
        demos=args.demos,
        seed=args.seed,
        noise=args.noise,
        style=args.style,
        max_attempts=args.max_attempts,
    )
    manifest = collect(config, args.out, execution_options(args))
    print(f"{'task':<48} {'kept':>5} {'attempts':>8} {'success':>8}")
    for task_id, stats in manifest["tasks"].items():
        print(f"{task_id:<48} {len(stats['kept']):>5} {stats['attempts']:>8} {stats['success_rate']:>8.0%}")
    print(f"wrote the compact form to {args.out}")
    if export:
        path = write_lerobot_dataset(args.out, workers=args.workers, progress=not args.no_progress)
        print(f"wrote the LeRobot dataset to {path}")
    else:
        print("LeRobot is not installed here: wrote the compact form only (export it with `langgap export-lerobot`)")
    if short := len(short_tasks(manifest)):
        print(f"error: {short} task(s) got fewer than {args.demos} demonstrations", flush=True)
        return 1
    return 0
