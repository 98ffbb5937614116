"""`langgap bddl FILE…`: parse BDDL files and check their goals against their scenes."""

from __future__ import annotations


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("bddl", help="check BDDL files (syntax, predicates, goal names in the scene)")
    parser.add_argument(
        "files", nargs="+", metavar="FILE", help="BDDL files to check (a task's: langgap tasks show ID --bddl)"
    )
    parser.set_defaults(handler=run)


def run(args) -> int:
    from langgap.bddl import read_bddl

    for path in args.files:
        problem = read_bddl(path)
        print(
            f"{path}: ok — {problem.problem_name}, {len(problem.objects)} objects, {len(problem.fixtures)} fixtures, "
            f"{len(problem.regions)} regions; goal {' '.join(str(p) for p in problem.goal)}"
        )
    return 0
