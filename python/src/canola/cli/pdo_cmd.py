# SPDX-License-Identifier: Apache-2.0
"""``canola pdo``: a node's PDOs, read and configured by SDO.

    canola pdo show NODE [PDO...]               communication and mapping parameters
    canola pdo map NODE TPDO1 "Statusword" "Position actual value" --type 255 \\
        --event-timer 100                       CiA 301 re-mapping procedure

With ``--eds`` the entries are named (and mapped by name); without, ``INDEX:SUB:BITS``.
"""

from __future__ import annotations

import argparse
from dataclasses import asdict

from canola.cli.common import (
    CliError,
    Parser,
    UsageError,
    add_bus_options,
    add_dictionary_options,
    add_group,
    add_master_options,
    dictionaries_from_args,
    emit_json,
    int_in_range,
    master_from_args,
    node_id,
)
from canola.cli.sdo_cmd import sdo_errors
from canola.errors import Error
from canola.pdomap import (
    Pdo,
    PdoConfigError,
    PdoError,
    configure_pdo,
    describe,
    mapped_entry,
    parse_pdo_name,
    read_pdos,
)


def _pdo_name(text: str) -> str:
    try:
        kind, number = parse_pdo_name(text)
    except PdoError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return f"{kind}{number}"


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    pdo_subs = add_group(subs, "pdo", "a node's PDOs: show, map",
                         "Read or configure a node's PDOs by SDO.")

    def common(sp: argparse.ArgumentParser) -> None:
        sp.add_argument("node", type=node_id, metavar="NODE", help="node-ID 1..127")
        add_bus_options(sp)
        add_dictionary_options(sp)
        add_master_options(sp)
        sp.add_argument("--json", action="store_true", help="print JSON")

    s = pdo_subs.add_parser(
        "show", help="print each PDO's communication and mapping parameters",
        description="Read each PDO's communication parameter (COB-ID, transmission type, "
                    "inhibit time, event timer) and mapping by SDO: the PDOs named, else "
                    "those of the EDS, else RPDO1..4 and TPDO1..4.")
    common(s)
    s.add_argument("pdos", nargs="*", type=_pdo_name, metavar="PDO", help="e.g. TPDO1")
    s.set_defaults(func=run_show)

    m = pdo_subs.add_parser(
        "map", help="configure a PDO (CiA 301 re-mapping procedure)",
        description="Invalidate the PDO (COB-ID bit 31), set the communication parameters "
                    "given, mapping count 0, the entries, the count, and validate it again.")
    common(m)
    m.add_argument("pdo", type=_pdo_name, metavar="PDO", help="e.g. TPDO1")
    m.add_argument("entries", nargs="*", metavar="ENTRY",
                   help="entry names (with --eds) or INDEX:SUB[:BITS]; none: empty mapping")
    m.add_argument("--type", type=lambda t: int_in_range(t, 0, 255, "transmission type"),
                   metavar="N", help="transmission type (0..240 SYNC, 254/255 events)")
    m.add_argument("--event-timer", type=lambda t: int_in_range(t, 0, 0xFFFF, "time", "ms"),
                   metavar="MS", help="event timer (TPDO) or deadline (RPDO), 0 = off")
    m.add_argument("--inhibit", type=lambda t: int_in_range(t, 0, 0xFFFF, "time",
                                                            "x 100 us"),
                   metavar="N", help="inhibit time in units of 100 us (TPDO)")
    m.set_defaults(func=run_map)


def _print(pdos: list[Pdo], as_json: bool, node: int) -> None:
    if as_json:
        emit_json({"node": node, "pdos": [{**asdict(p), "name": p.name} for p in pdos]})
        return
    for pdo in pdos:
        print("\n".join(describe(pdo)))


def run_show(args: argparse.Namespace) -> int:
    od = dictionaries_from_args(args).get(args.node)
    with master_from_args(args) as master, sdo_errors(args.node, args.sdo_timeout):
        pdos = read_pdos(master.sdo(args.node), od, args.pdos or None)
    if not pdos:
        raise CliError(f"node {args.node} has none of the PDOs asked for")
    _print(pdos, args.json, args.node)
    return 0


def run_map(args: argparse.Namespace) -> int:
    od = dictionaries_from_args(args).get(args.node)
    try:
        entries = [mapped_entry(od, text) for text in args.entries]
    except Error as exc:
        raise UsageError(f"canola pdo map: error: {exc}") from None
    with master_from_args(args) as master, sdo_errors(args.node, args.sdo_timeout,
                                                      f"node {args.node} {args.pdo}"):
        try:
            configure_pdo(master.sdo(args.node), args.pdo, entries,
                          transmission_type=args.type, event_timer_ms=args.event_timer,
                          inhibit_100us=args.inhibit)
        except PdoConfigError as exc:  # half-way: what failed, and the state it left
            raise CliError(f"node {args.node} {exc}") from None
        except PdoError as exc:
            raise UsageError(f"canola pdo map: error: {exc}") from None
        pdos = read_pdos(master.sdo(args.node), od, [args.pdo])
    _print(pdos, args.json, args.node)
    return 0
