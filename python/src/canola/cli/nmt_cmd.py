# SPDX-License-Identifier: Apache-2.0
"""``canola nmt CMD NODE|all``: NMT master commands."""

from __future__ import annotations

import argparse

import can

from canola.cli.common import Parser, add_bus_options, bus_from_args, emit_json, node_or_all

COMMANDS = {"start": 0x01, "stop": 0x02, "preop": 0x80, "reset-node": 0x81,
            "reset-comm": 0x82}


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    p = subs.add_parser(
        "nmt", help="send an NMT command",
        description="Send an NMT command to one node or to all (NMT has no answer: watch "
                    "the heartbeats with canola dump or canola monitor).")
    p.add_argument("cmd", choices=sorted(COMMANDS), metavar="CMD",
                   help="one of: " + ", ".join(sorted(COMMANDS)))
    p.add_argument("node", type=node_or_all, metavar="NODE|all",
                   help="node-ID 1..127, or all (0)")
    add_bus_options(p)
    p.add_argument("--json", action="store_true", help="print what was sent as JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    bus = bus_from_args(args)
    try:
        bus.send(can.Message(arbitration_id=0x000, data=[COMMANDS[args.cmd], args.node],
                             is_extended_id=False))
    finally:
        bus.shutdown()
    if args.json:
        emit_json({"command": args.cmd, "node": args.node or "all"})
    return 0
