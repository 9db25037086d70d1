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
    from canola.manager import NetworkManager

#: Longest one slave's boot may take, per SDO time-out (reads, DCF records, retries).
_STEPS_PER_SLAVE = 16


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    p = subs.add_parser(
        "boot", help="boot a network (CANopen manager, CiA 302-2)",
        description="Check every slave's identity, download its configuration (the DCF's "
                    "ParameterValues), watch its heartbeat and start the network. NETWORK "
                    "is one YAML description, or DCF files (one mandatory slave each). With "
                    "--timeout, a slave that does not answer yet is booted when its boot-up "
                    "comes, until then. Exit code 0 only when the network started. The "
                    "master runs the network: it "
                    "announces itself as node --master-id (boot-up, heartbeat if its 0x1017 "
                    "says so).")
    p.add_argument("files", nargs="+", metavar="NETWORK.yaml|DCF",
                   help="a network description, or the DCF of each slave")
    add_bus_options(p)
    add_master_options(p, announce=False)  # the network's master announces itself
    p.add_argument("--timeout", type=float, default=None, metavar="S",
                   help="wait up to S seconds, for late slaves too (no answer yet: "
                        "booted at their boot-up; default: until the boot settled, at "
                        "most enough for every slave's time-outs)")
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


def _nothing_to_wait_for(manager: NetworkManager, late: bool) -> bool:
    """The boot settled (:meth:`NetworkManager.settled`) and, with ``late``, no slave is
    still to come: every one booted, or failed for a reason other than no answer (B) or a
    lost heartbeat. A slave that has not answered yet may boot late: CiA 302-2 boots a
    slave when its boot-up arrives, mandatory or optional, for as long as the manager runs
    (as canola.Master.boot(wait=False) does); --timeout is how long the command waits for
    it (the role of the boot time, 0x1F89)."""
    if not manager.settled():
        return False
    return not late or not any(s.state == "missing" or (s.state == "failed" and s.reason == "B")
                               for s in manager.slaves())


def run(args: argparse.Namespace) -> int:
    from canola.boot_plan import NetworkError, from_files  # noqa: PLC0415 -- on first use

    try:
        network = from_files(args.files, node_id_of_master=args.master_id)
    except NetworkError as exc:
        raise CliError(f"canola boot: error: {exc}", 2) from None
    limit = _limit(args, network)
    with master_from_args(args, announce=True) as master:
        manager = master.boot(network, wait=False)
        late = args.timeout is not None
        manager.wait_until(lambda: _nothing_to_wait_for(manager, late), limit)
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
