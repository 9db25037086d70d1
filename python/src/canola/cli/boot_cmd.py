# SPDX-License-Identifier: Apache-2.0
"""``canola boot NETWORK.yaml | DCF...``: boot a network with the CANopen manager (CiA
302-2) and print each node's outcome. Exit code 0 only when the network started; 1 when
it did not (a mandatory node failed) or the bus failed; 2 for bad arguments, a bad
network description included."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from canola.cli.common import (
    CliError,
    Parser,
    add_bus_options,
    add_master_options,
    emit_json,
    master_from_args,
)

if TYPE_CHECKING:
    from canola.boot_plan import Network

#: Longest one slave's boot may take, per SDO time-out (reads, DCF records, retries).
_STEPS_PER_SLAVE = 16


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    p = subs.add_parser(
        "boot", help="boot a network (CANopen manager, CiA 302-2)",
        description="Check every slave's identity, download its configuration (the DCF's "
                    "ParameterValues), watch its heartbeat and start the network. NETWORK "
                    "is one YAML description, or DCF files (one mandatory slave each). Exit "
                    "code 0 only when the network started. The master runs the network: it "
                    "announces itself as node --master-id (boot-up, heartbeat if its 0x1017 "
                    "says so).")
    p.add_argument("files", nargs="+", metavar="NETWORK.yaml|DCF")
    add_bus_options(p)
    add_master_options(p, announce=False)  # the network's master announces itself
    p.add_argument("--timeout", type=float, default=None, metavar="S",
                   help="give up after S seconds (default: enough for every slave's "
                        "time-outs)")
    p.add_argument("--json", action="store_true",
                   help="one JSON object: started, nodes, events")
    p.set_defaults(func=run)


def _limit(args: argparse.Namespace, network: Network) -> float:
    if args.timeout is not None:
        if not 0 < args.timeout <= 86400:
            raise CliError(f"canola boot: error: bad --timeout {args.timeout}: 0..86400 s", 2)
        return float(args.timeout)
    per_slave: float = _STEPS_PER_SLAVE * args.sdo_timeout / 1000
    heartbeat = sum(s.heartbeat_ms for s in network.slaves) / 1000
    return 5.0 + per_slave * len(network.slaves) + heartbeat


def run(args: argparse.Namespace) -> int:
    from canola.boot_plan import NetworkError, from_files  # noqa: PLC0415 -- on first use

    try:
        network = from_files(args.files, node_id_of_master=args.master_id)
    except NetworkError as exc:
        raise CliError(f"canola boot: error: {exc}", 2) from None
    limit = _limit(args, network)
    with master_from_args(args, announce=True) as master:
        manager = master.boot(network, wait=False)
        manager.wait(limit)
        settled = manager.settled()
        started = manager.started
        statuses = manager.slaves()
        events = list(manager.events)
    if args.json:
        emit_json({"started": started, "settled": settled,
                   "nodes": [s.as_dict() for s in statuses],
                   "events": [e.as_dict() for e in events]})
    else:
        for status in statuses:
            print(status)
        if started:
            print("network started")
        elif not settled:
            print(f"network not started: the boot did not end within {limit:g} s")
        else:
            failed = [s.node for s in statuses if s.mandatory and not s.ok]
            print("network not started: mandatory node(s) "
                  f"{', '.join(map(str, failed))} failed")
    return 0 if started else 1
