"""`langgap eval`: evaluate a policy on a task selection into a durable, resumable run.

Exit codes: 0 every planned episode is stored and judged; 3 the run finished with gaps (episodes
infrastructure could not run; `--resume` retries them); 4 the run stopped after repeated
infrastructure failures with one cause; 2 bad input or another error (nothing stored is touched).
"""

from __future__ import annotations

from langgap.cli.execution_flags import add_execution_options, add_share_rollouts_option, execution_options
from langgap.cli.policy_options import add_policy_arg_option, check_policy_command, parse_key_values
from langgap.cli.tasks_cmd import add_catalog_options
from langgap.engine.filming import DEFAULT_VIDEO, VIDEO_DIR, VIDEO_HELP
from langgap.engine.plan import CONDITION_HELP
from langgap.engine.spec import (
    DEFAULT_MAX_BATCH,
    DEFAULT_MAX_WAIT_MS,
    PAPER_EPISODES,
    RESULT_STEPPINGS,
)
from langgap.errors import LangGapError
from langgap.stack import DEFAULT_SEED_SCHEME, DEFAULT_STEPPING
from langgap.vocabulary import Condition, SeedScheme, Stepping, words

EXIT_GAPS = 3


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("eval", help="evaluate a policy: N episodes per task on fixed init states")
    parser.add_argument(
        "--policy", required=True, help="policy name (oracle, blind, noop, random, openpi, …) or module:Class"
    )
    add_policy_arg_option(parser)
    add_catalog_options(parser)
    parser.add_argument(
        "--tasks",
        metavar="SELECTION",
        help="task selection (default: feasible, every task the feasibility gate did not reject)",
    )
    parser.add_argument(
        "--episodes",
        type=int,
        default=PAPER_EPISODES,
        help="episodes per task = init states 0..N-1 (default: %(default)s, as in the paper)",
    )
    parser.add_argument("--run", required=True, metavar="DIR", help="run directory (SQLite store, videos)")
    parser.add_argument("--resume", action="store_true", help="continue a run: skip stored episodes, redo gaps")
    parser.add_argument(
        "--extend",
        action="store_true",
        help="with --resume: let the run grow (more tasks, episodes or conditions; everything else must match)",
    )
    parser.add_argument(
        "--condition",
        action="append",
        metavar="CONDITION",
        help=f"instruction condition, repeatable ({CONDITION_HELP})",
    )
    parser.add_argument(
        "--video",
        nargs="?",
        const=DEFAULT_VIDEO,
        default="",
        metavar="WHICH",
        help=VIDEO_HELP,
    )
    parser.add_argument("--seed", type=int, default=0, help="run seed; episode k uses env seed SEED+k")
    add_stepping_option(parser)
    parser.add_argument(
        "--seed-scheme",
        choices=words(SeedScheme),
        default=DEFAULT_SEED_SCHEME,
        help=f"how seeds select fixture placements: {SeedScheme.PER_EPISODE} (episode k seeds SEED+k: independent "
        f"of order, the default) or {SeedScheme.OPENPI} (one stream per task seeded with SEED, as openpi's LIBERO "
        "example; the run records it)",
    )
    parser.add_argument(
        "--repeats",
        type=int,
        default=1,
        metavar="R",
        help="run every planned episode with R seeds on the same init state (repeat r: seed SEED+1000r+k); "
        "reports give the between-seed spread",
    )
    add_execution_options(parser)
    add_share_rollouts_option(parser)
    parser.add_argument(
        "--shared-policy",
        action="store_true",
        help="one policy process (local) or actor (ray) for all environment workers, batching their queries",
    )
    parser.add_argument("--max-batch", type=int, help=f"shared policy: largest batch (default: {DEFAULT_MAX_BATCH})")
    parser.add_argument(
        "--max-wait-ms",
        type=float,
        help=f"shared policy: how long a query waits for others (default: {DEFAULT_MAX_WAIT_MS:g})",
    )
    parser.add_argument("--policy-gpus", type=float, help="ray's shared policy: GPUs for the policy actor (default: 0)")
    parser.add_argument("--quiet", action="store_true", help="print no diagnosis table at the end")
    parser.set_defaults(handler=run, smoke=("tasks", "episodes", "repeats", "workers"))


def add_stepping_option(parser) -> None:
    """`--stepping`, shared by the commands that run episodes."""
    parser.add_argument(
        "--stepping",
        choices=words(RESULT_STEPPINGS),
        default=DEFAULT_STEPPING,
        help=f"physics substeps: {Stepping.EXACT} (bit-identical to robosuite, the default) or {Stepping.FAST} "
        "(about 1.7x faster steps; the last bits differ, the run records it)",
    )


def run(args) -> int:
    from langgap.engine.evaluate import evaluate
    from langgap.engine.scheduler import RunStopped
    from langgap.engine.spec import RunSpec

    if args.extend and not args.resume:
        raise LangGapError("--extend needs --resume")
    spec = RunSpec.create(
        args.policy,
        policy_args=parse_key_values(args.policy_arg, "--policy-arg"),
        catalog=args.catalog,
        tasks=args.tasks,
        episodes=args.episodes,
        seed=args.seed,
        repeats=args.repeats,
        conditions=tuple(args.condition or (Condition.GIVEN,)),
        style=args.style,
        stepping=args.stepping,
        seed_scheme=args.seed_scheme,
    )
    options = execution_options(
        args,
        video=args.video,
        shared_policy=args.shared_policy,
        max_batch=args.max_batch,
        max_wait_ms=args.max_wait_ms,
        policy_gpus=args.policy_gpus,
        share_rollouts=args.share_rollouts,
    )
    print_switch_note(spec.catalog, spec.tasks, spec.conditions, spec.style)
    try:
        summary = evaluate(spec, args.run, options, resume=args.resume, extend=args.extend)
    except RunStopped as exc:
        raise RunStopped(exc.template + "; {hint}", **exc.values, hint=check_hint(spec)) from None
    print(
        f"run {summary.run}: {summary.planned} planned, {summary.skipped} already stored, {summary.ran} run "
        f"({summary.successes} successes, {summary.gaps} gaps)"
    )
    if summary.policy_errors or summary.gaps:
        print(f"policy errors: {summary.policy_errors}, gaps: {summary.gaps}; {check_hint(spec)}")
    if summary.rollouts:
        print(f"shared rollouts: {summary.shared} episodes in {summary.rollouts} rollouts")
    if summary.policy_server:
        calls, queries = summary.policy_server["calls"], summary.policy_server["queries"]
        print(f"shared policy: {queries} queries in {calls} batched calls ({queries / max(1, calls):.2f} per call)")
    if options.video_selection:
        print(f"videos: {summary.filmed} episodes filmed ({options.video_selection}) in {summary.run / VIDEO_DIR}")
    if summary.film_mismatches:
        print(
            f"warning: {summary.film_mismatches} replayed episodes ended otherwise than stored (a policy that "
            "is not deterministic given the episode's seed?); they have no clip"
        )
    if not args.quiet:
        from langgap.report import diagnosis_text

        print(diagnosis_text([summary.run]))
    return 0 if summary.complete else EXIT_GAPS


def check_hint(spec) -> str:
    """Where to look when a run's policy failed: `langgap check-policy` for the run's policy, catalog and tasks."""
    command = check_policy_command(spec.policy, spec.policy_args, spec.catalog, spec.selection)
    return f"check the policy in a minute with {command}"


def print_switch_note(catalog_name: str, task_ids, conditions: tuple[str, ...], style: str = "libero") -> None:
    """Say which selected tasks a plan leaves unswitched (`langgap.engine.plan.switch_note`), before the run."""
    from langgap.catalog.catalog import load_catalog
    from langgap.engine.plan import switch_note

    catalog = load_catalog(catalog_name)
    note = switch_note([catalog.get(t) for t in task_ids], catalog, conditions, style)
    if note:
        print(note, flush=True)
