"""The `langgap` command: one module per verb, each with `add_parser(subparsers)` and `run(args)`."""

from __future__ import annotations

import argparse
import os
import signal
import sys

from langgap.cli import (
    bddl_cmd,
    check_policy_cmd,
    collect_cmd,
    doctor_cmd,
    eval_cmd,
    experiment_cmd,
    export_hdf5_cmd,
    export_lerobot_cmd,
    generate_cmd,
    merge_lerobot_cmd,
    parameter_flags,
    report_cmd,
    serve_cmd,
    smoke,
    splits_cmd,
    tasks_cmd,
    train_cmd,
    validate_cmd,
    verify_demos_cmd,
)
from langgap.cli.parser import Parser, described
from langgap.errors import LangGapError

VERBS = (
    tasks_cmd,
    splits_cmd,
    eval_cmd,
    check_policy_cmd,
    serve_cmd,
    report_cmd,
    validate_cmd,
    generate_cmd,
    doctor_cmd,
    bddl_cmd,
    collect_cmd,
    verify_demos_cmd,
    export_lerobot_cmd,
    export_hdf5_cmd,
    merge_lerobot_cmd,
    train_cmd,
    experiment_cmd,
)


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="langgap", description="LangGap: does a VLA policy read its instruction? Same-scene tasks on LIBERO."
    )
    subparsers = parser.add_subparsers(dest="verb", required=True, metavar="COMMAND")
    for verb in VERBS:
        verb.add_parser(subparsers)
    described(parser)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    argv = sys.argv[1:] if argv is None else argv
    if not argv:
        # A bare `langgap` asks what it can do: the help, not a missing-argument error.
        parser.print_help()
        return 0
    args = parser.parse_args(argv)
    try:
        smoke.apply(args)
        return int(args.handler(args) or 0)
    except LangGapError as exc:
        print(f"error: {parameter_flags.error_message(exc, parser, args)}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("error: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # The reader closed the pipe (`langgap tasks list | head`): stop quietly, as Unix tools do. stdout goes to
        # /dev/null so that flushing it at exit raises nothing more.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 128 + signal.SIGPIPE


if __name__ == "__main__":
    sys.exit(main())
