# SPDX-License-Identifier: Apache-2.0
"""``canola bus serve``: the software CAN bus (a socketcand hub, :mod:`canola.bus.hub`);
``canola bus bridge``: another bus joined to it (:mod:`canola.bus.bridge`)."""

from __future__ import annotations

import argparse
import sys

from canola import access
from canola.bus import hub
from canola.bus.bridge import Bridge, BridgeSide, shutdown
from canola.bus.open import BusError, open_bus
from canola.cli.common import CliError, Parser, add_bus_options, bus_from_args, stop_signals


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
                       help="address to listen on (default 127.0.0.1, this machine only; "
                            "any other is reachable from the network and needs --token)")
    serve.add_argument("--port", type=int, default=hub.DEFAULT_PORT,
                       help=f"TCP port (default {hub.DEFAULT_PORT}; 0 picks a free one)")
    serve.add_argument("--queue", type=int, default=1024, metavar="FRAMES",
                       help="frames queued per client before that client loses frames "
                            "(default 1024)")
    serve.add_argument("--replies", type=int, default=hub.DEFAULT_REPLY_LIMIT, metavar="N",
                       help="replies queued beyond that for a client that does not read "
                            f"them before it is disconnected (default {hub.DEFAULT_REPLY_LIMIT})")
    serve.add_argument("--token", metavar="TOKEN",
                       help="a secret every client sends first (< auth TOKEN >); default "
                            f"${access.TOKEN_ENV}; needed to listen beyond loopback")
    serve.set_defaults(func=run_serve)
    bridge = bus_subs.add_parser(
        "bridge", help="join another bus to this one",
        description="Join a bus (an SLCAN adapter, the UART of a canola firmware image in "
                    "QEMU: slcan://HOST:PORT) to the bus of --iface/--bus (or the default "
                    "bus): every frame received on one is sent on the other. Stops on "
                    "Ctrl-C or SIGTERM (exit 0), or when either side fails or closes "
                    "(exit 1, saying which).",
        epilog="e.g. canola bus bridge slcan://127.0.0.1:4000 "
               "--bus socketcand://127.0.0.1:29536/can0")
    bridge.add_argument("far", metavar="URL",
                        help="the bus to join: slcan://HOST:PORT, slcan:///dev/DEVICE, "
                             "socketcand://HOST:PORT/CHANNEL or socketcan://IFACE")
    add_bus_options(bridge)
    bridge.set_defaults(func=run_bridge)


def run_serve(args: argparse.Namespace) -> int:
    if not 0 <= args.port <= 65535:
        raise CliError(f"bad port {args.port}: 0..65535", 2)
    if args.queue < 1:
        raise CliError(f"bad queue size {args.queue}", 2)
    if args.replies < 1:
        raise CliError(f"bad reply queue size {args.replies}", 2)
    if not args.host.strip():
        raise CliError("canola bus serve: error: --host '' would listen on every address: "
                       "give one (127.0.0.1: this machine only)", 2)
    try:
        token = access.token_from(args.token)
    except ValueError as exc:
        raise CliError(f"canola bus serve: error: {exc}", 2) from None
    refused = access.unguarded(args.host, token)
    if refused is not None:
        raise CliError(f"canola bus serve: error: {refused}", 2)
    for address in access.exposed_addresses(args.host, args.port):
        print(f"canola bus: --host {args.host}: listening on {address}, not loopback: "
              "clients must send the token; the traffic is not encrypted (docs/security.md)",
              file=sys.stderr, flush=True)
    try:
        hub.serve(args.host, args.port, queue_limit=args.queue, reply_limit=args.replies,
                  token=token)
    except OSError as exc:
        raise CliError(f"cannot listen on {args.host}:{args.port}: {exc.strerror or exc}"
                       ) from None
    return 0


def run_bridge(args: argparse.Namespace) -> int:
    near = bus_from_args(args)
    try:
        far = open_bus(url=args.far)
    except BusError as exc:
        shutdown(near)
        raise CliError(str(exc)) from None
    near_name = args.bus or args.iface or "the default bus"
    bridge = Bridge(BridgeSide(far, args.far), BridgeSide(near, near_name))
    try:
        with stop_signals() as ended, bridge:
            print(f"canola bus: {args.far} joined to {bridge.sides[1].name} (Ctrl-C stops)",
                  flush=True)
            while not ended.is_set() and not bridge.wait(0.2):
                pass
    finally:
        shutdown(far)
        shutdown(near)
    a, b = bridge.sides
    print(f"canola bus: {a.frames} frames from {a.name}, {b.frames} from {b.name}", flush=True)
    if bridge.error is not None:
        raise CliError(f"bus bridge: {bridge.error}")
    return 0
