"""`langgap doctor`."""

from __future__ import annotations


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("doctor", help="check the simulation stack, renderer, assets and catalog")
    parser.set_defaults(handler=run)


def run(args) -> int:
    from langgap.diagnostics.checks import check_lines
    from langgap.diagnostics.doctor import run_checks

    failed = 0
    for check in run_checks():
        print("\n".join(check_lines(check)), flush=True)
        failed += not check.ok
    print(f"doctor: {'all checks passed' if not failed else f'{failed} check(s) failed'}")
    return 1 if failed else 0
