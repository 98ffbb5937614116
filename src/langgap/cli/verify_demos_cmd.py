"""`langgap verify-demos`: replay every demonstration of a collection and check it still succeeds."""

from __future__ import annotations


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("verify-demos", help="replay each demonstration's actions; exit 1 if one fails")
    parser.add_argument("collection", metavar="DIR", help="a directory written by `langgap collect`")
    parser.set_defaults(handler=run)


def run(args) -> int:
    from langgap.demos.verify import verify_collection

    verdicts = verify_collection(args.collection)
    failed = [v for v in verdicts if not v.ok]
    for v in failed:
        reason = v.error or (
            "goal never reached" if v.success_step is None else f"goal at step {v.success_step} of {v.steps}"
        )
        print(f"FAIL {v.task_id} seed {v.seed}: {reason}")
    print(f"{len(verdicts) - len(failed)}/{len(verdicts)} demonstrations replay to success")
    return 1 if failed else 0
