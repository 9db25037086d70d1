"""``canola bus serve``: the software CAN bus (a socketcand hub, :mod:`canola.hub`)."""

from __future__ import annotations

import argparse

from canola import hub
from canola.cli.common import CliError, Parser


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    bus = subs.add_parser("bus", help="software CAN bus",
                          description="A software CAN bus shared by processes.")
    bus_subs = bus.add_subparsers(dest="bus_command", metavar="SUBCOMMAND",
                                  parser_class=Parser)
    bus_subs.required = True
    serve = bus_subs.add_parser(
        "serve", help="run a socketcand hub",
        description="Run a CAN hub speaking the socketcand protocol: python-can's socketcand "
                    "interface, canola commands and canola's C client share its channels "
                    "(each channel is one bus). Stops on Ctrl-C or SIGTERM.")
    serve.add_argument("--host", default="127.0.0.1",
                       help="address to listen on (default 127.0.0.1, this machine only)")
    serve.add_argument("--port", type=int, default=hub.DEFAULT_PORT,
                       help=f"TCP port (default {hub.DEFAULT_PORT}; 0 picks a free one)")
    serve.add_argument("--queue", type=int, default=1024, metavar="FRAMES",
                       help="frames queued per client before that client loses frames "
                            "(default 1024)")
    serve.set_defaults(func=run_serve)


def run_serve(args: argparse.Namespace) -> int:
    if not 0 <= args.port <= 65535:
        raise CliError(f"bad port {args.port}: 0..65535", 2)
    if args.queue < 1:
        raise CliError(f"bad queue size {args.queue}", 2)
    try:
        hub.serve(args.host, args.port, queue_limit=args.queue)
    except OSError as exc:
        raise CliError(f"cannot listen on {args.host}:{args.port}: {exc.strerror or exc}"
                       ) from None
    return 0
