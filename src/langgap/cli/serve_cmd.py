"""`langgap serve`: serve a LangGap policy over openpi's websocket protocol."""

from __future__ import annotations

from langgap.cli.policy_options import add_policy_arg_option, parse_key_values


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "serve", help="serve a policy over openpi's websocket protocol (for the `openpi` policy elsewhere)"
    )
    parser.add_argument("--policy", required=True, help="policy name (oracle, blind, lerobot, …) or module:Class")
    add_policy_arg_option(parser)
    parser.add_argument("--host", default="127.0.0.1", help="address to bind (default: %(default)s, this machine only)")
    parser.add_argument("--port", type=int, required=True, help="port to listen on")
    parser.set_defaults(handler=run)


def run(args) -> int:
    from langgap.serve import serve

    serve(args.policy, parse_key_values(args.policy_arg, "--policy-arg"), host=args.host, port=args.port)
    return 0
