"""`langgap doctor`."""

from __future__ import annotations


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("doctor", help="check the simulation stack, renderer, assets and catalog")
    parser.set_defaults(handler=run)


def run(args) -> int:
    from langgap.doctor import run_checks

    failed = 0
    for check in run_checks():
        verdict = "ok  " if check.ok else "FAIL"
        print(f"[{verdict}] {check.name:<15} {check.detail}", flush=True)
        if not check.ok:
            failed += 1
            if check.remedy:
                print(f"       {'':<15} fix: {check.remedy}", flush=True)
    print(f"doctor: {'all checks passed' if not failed else f'{failed} check(s) failed'}")
    return 1 if failed else 0
