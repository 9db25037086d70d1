# SPDX-License-Identifier: Apache-2.0
"""``canola lss scan | set-id | inquire``: layer setting services (CiA 305).

    canola lss scan                          devices without node-ID (fastscan)
    canola lss set-id VENDOR:PRODUCT:REVISION:SERIAL NODE-ID [--store]
    canola lss inquire VENDOR:PRODUCT:REVISION:SERIAL
"""

from __future__ import annotations

import argparse
import time
from typing import TYPE_CHECKING

from canola.cli.common import (
    CliError,
    Parser,
    add_bus_options,
    add_master_options,
    emit_json,
    int_in_range,
    master_from_args,
    node_id,
)
from canola.errors import Error

if TYPE_CHECKING:
    from canola.lss import LssAddress


def _address(text: str) -> LssAddress:
    from canola.lss import LssAddress  # noqa: PLC0415 -- on first use

    try:
        return LssAddress.parse(text)
    except Error as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _lss_timeout(text: str) -> int:
    return int_in_range(text, 1, 65535, "time", "ms")


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    p = subs.add_parser("lss", help="layer setting services: find devices, give node-IDs",
                        description="LSS master (CiA 305). Fastscan costs 134 LSS time-outs "
                                    "for the first device (about 13 s at the default 100 "
                                    "ms), from 7 for each one after it.")
    lss_subs = p.add_subparsers(dest="lss_command", metavar="SUBCOMMAND", parser_class=Parser)
    lss_subs.required = True

    def common(sp: argparse.ArgumentParser) -> None:
        add_bus_options(sp)
        add_master_options(sp)
        sp.add_argument("--timeout", type=_lss_timeout, default=100, metavar="MS",
                        help="LSS time-out of every request (default 100 ms)")
        sp.add_argument("--json", action="store_true", help="print JSON")

    scan = lss_subs.add_parser("scan", help="list the devices without node-ID (fastscan)",
                               description="Find every device without node-ID by fastscan "
                                           "and print its address "
                                           "VENDOR:PRODUCT:REVISION:SERIAL (hex), then how "
                                           "long the scan took.")
    common(scan)
    scan.add_argument("--max-devices", type=lambda t: int_in_range(t, 1, 127, "count"),
                      default=127, metavar="N", help="stop after N devices (default 127)")
    scan.add_argument("--time-limit", type=lambda t: int_in_range(t, 1, 86400, "time", "s"),
                      default=None, metavar="S",
                      help="give up after S seconds (default: no limit; the scan ends by "
                           "itself)")
    scan.set_defaults(func=run_scan)

    set_id = lss_subs.add_parser("set-id", help="give a device a node-ID",
                                 description="Select the device with this LSS address and give "
                                             "it NODE-ID; a device without one boots with it "
                                             "at once, another takes it at its next reset "
                                             "communication (CiA 305). Without --store an NMT "
                                             "reset node or a power cycle brings back the "
                                             "node-ID the device had stored.")
    set_id.add_argument("address", type=_address, metavar="VENDOR:PRODUCT:REVISION:SERIAL",
                        help="the device's identity (0x1018 sub1..4) in hex")
    set_id.add_argument("node_id", type=node_id, metavar="NODE-ID", help="1..127")
    set_id.add_argument("--store", action="store_true",
                        help="make the device store the node-ID (store configuration): "
                             "kept through reset node and power cycles")
    common(set_id)
    set_id.set_defaults(func=run_set_id)

    inquire = lss_subs.add_parser("inquire", help="read a device's LSS values",
                                  description="Select the device with this LSS address and "
                                              "read its identity and active node-ID.")
    inquire.add_argument("address", type=_address, metavar="VENDOR:PRODUCT:REVISION:SERIAL",
                         help="the device's identity (0x1018 sub1..4) in hex")
    common(inquire)
    inquire.set_defaults(func=run_inquire)


def run_scan(args: argparse.Namespace) -> int:
    from canola.lss import FastscanTimeLimitError, LssError  # noqa: PLC0415 -- on first use

    began = time.monotonic()
    with master_from_args(args) as master:
        master.lss.timeout_ms = args.timeout
        try:
            found = master.lss.fastscan(args.max_devices, time_limit=args.time_limit)
        except FastscanTimeLimitError as exc:
            raise CliError(f"canola lss scan: {exc}; allow more with --time-limit S (the first "
                           f"device takes 134 LSS time-outs of {args.timeout} ms, "
                           f"--timeout MS)") from None
        except LssError as exc:
            raise CliError(f"canola lss scan: {exc}; devices that answer slower than the "
                           f"LSS time-out ({args.timeout} ms) need a longer one: "
                           "--timeout MS") from None
    took = time.monotonic() - began
    if args.json:
        emit_json([{**a.as_dict(), "address": str(a)} for a in found])
    else:
        for address in found:
            print(address)
        print(f"{len(found)} device(s) without node-ID (fastscan took {took:.1f} s)")
    return 0


def run_set_id(args: argparse.Namespace) -> int:
    with master_from_args(args) as master:
        master.lss.timeout_ms = args.timeout
        master.lss.set_node_id(args.address, args.node_id, store=args.store)
    if args.json:
        emit_json({"address": str(args.address), "node_id": args.node_id,
                   "stored": args.store})
    else:
        print(f"{args.address}: node-ID {args.node_id}" + (" (stored)" if args.store else ""))
    return 0


def run_inquire(args: argparse.Namespace) -> int:
    with master_from_args(args) as master:
        master.lss.timeout_ms = args.timeout
        values = master.lss.inquire(args.address)
    if args.json:
        emit_json({"address": str(args.address), **values})
    else:
        node = values["node_id"]
        print(f"vendor 0x{values['vendor']:08X} product 0x{values['product']:08X} revision "
              f"0x{values['revision']:08X} serial 0x{values['serial']:08X} node-ID "
              + ("none" if node == 0xFF else str(node)))
    return 0
