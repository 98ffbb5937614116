"""`langgap check-policy`: check a policy in a minute before a long `langgap eval` run.

Exit codes: 0 every check passed; 1 a check failed (the page says what, and how to fix it); 2 bad input
(an unknown policy or argument, a selection or episode count eval refuses).
"""

from __future__ import annotations

from langgap.cli.policy_options import add_policy_arg_option, parse_key_values
from langgap.cli.tasks_cmd import add_catalog_options
from langgap.diagnostics.policy_timing import WHOLE_EPISODE_BUDGET_S
from langgap.engine.spec import DEFAULT_TIMEOUT_S, PAPER_EPISODES


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "check-policy",
        help="check a policy on a short episode and one played whole (spec, actions, reset/close, determinism, "
        "latency) before a run",
    )
    parser.add_argument(
        "policy", metavar="POLICY", help="policy name (oracle, blind, noop, random, openpi, …) or module:Class"
    )
    add_policy_arg_option(parser)
    add_catalog_options(parser)
    parser.add_argument(
        "--tasks",
        metavar="SELECTION",
        help="the run's task selection, as for eval: the check runs its first task's first episode and estimates "
        "the run's wall time (default: feasible)",
    )
    parser.add_argument(
        "--episodes",
        type=int,
        default=PAPER_EPISODES,
        help="the run's episodes per task, as for eval, for the wall-time estimate (default: %(default)s)",
    )
    parser.add_argument(
        "--timeout",
        type=float,
        default=DEFAULT_TIMEOUT_S,
        metavar="S",
        help="the run's seconds per episode, as for eval: latency fails when the longest episode would take more "
        "than half of it (default: %(default)g)",
    )
    parser.add_argument(
        "--budget",
        dest="budget_s",
        type=float,
        default=WHOLE_EPISODE_BUDGET_S,
        metavar="S",
        help="seconds the episode played whole may take at the measured speed; a slower policy plays as many steps "
        "as fit, and the page says how many (default: %(default)g)",
    )
    parser.set_defaults(handler=run)


def run(args) -> int:
    from langgap.diagnostics.policy_check import check_policy

    report = check_policy(
        args.policy,
        parse_key_values(args.policy_arg, "--policy-arg"),
        catalog=args.catalog,
        tasks=args.tasks,
        style=args.style,
        episodes=args.episodes,
        timeout_s=args.timeout,
        budget_s=args.budget_s,
    )
    print(report.page())
    return report.exit_code
