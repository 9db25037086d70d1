# SPDX-License-Identifier: Apache-2.0
"""``canola scan``: which node-IDs answer an SDO read of 0x1000 (device type); with
``--eds`` each answer is compared with the node's EDS (product name, device type)."""

from __future__ import annotations

import argparse
import os
import time

import can

from canola.cli.common import (
    CliError,
    Parser,
    add_bus_options,
    add_dictionary_options,
    bus_from_args,
    dictionaries_from_args,
    emit_json,
    positive_ms,
)
from canola.nodedicts import NodeDictionaries


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    p = subs.add_parser(
        "scan", help="find the nodes on the bus",
        description="Ask every node-ID (1..127, or --nodes) for its device type (SDO read of "
                    "0x1000:00) at once and list those that answer within the time-out.")
    add_bus_options(p)
    add_dictionary_options(p)
    p.add_argument("--timeout", type=positive_ms, default=500, metavar="MS",
                   help="how long to wait for answers (default 500 ms)")
    p.add_argument("--nodes", metavar="A-B", default="1-127",
                   help="node-ID range to ask (default 1-127)")
    p.add_argument("--json", action="store_true", help="a JSON list of the nodes found")
    p.set_defaults(func=run)


def _range(text: str) -> range:
    low, _, high = text.partition("-")
    try:
        first, last = int(low, 0), int(high or low, 0)
    except ValueError:
        first = last = 0
    if not 1 <= first <= last <= 127:
        raise CliError(f"canola scan: error: bad --nodes {text!r}: A-B within 1..127", 2)
    return range(first, last + 1)


def _compared(dicts: NodeDictionaries, entry: dict[str, object]) -> dict[str, object]:
    """What the node's EDS says of the answer: its product name, whether its 0x1000
    default is the device type read."""
    node = entry["node"]
    assert isinstance(node, int)
    od, file = dicts.get(node), dicts.file(node)
    if od is None or file is None or "device_type" not in entry:
        return {}
    var = od.objects[0x1000].subs.get(0) if 0x1000 in od else None
    expected = None if var is None else var.value if var.value is not None else var.default
    return {"eds": os.path.basename(file),
            "product": od.device_info.get("ProductName", "?"),
            "eds_device_type": expected, "matches": expected == entry["device_type"]}


def _eds_note(entry: dict[str, object]) -> str:
    if "product" not in entry:
        return ""
    said = entry["eds_device_type"]
    if entry["matches"]:
        return f", {entry['product']} ({entry['eds']})"
    if isinstance(said, int):
        return f", not {entry['product']}: {entry['eds']} says device type 0x{said:08X}"
    return f", {entry['eds']} gives no device type"


def run(args: argparse.Namespace) -> int:
    nodes = _range(args.nodes)
    dicts = dictionaries_from_args(args)
    bus = bus_from_args(args)
    found: dict[int, dict[str, object]] = {}
    try:
        for node in nodes:
            bus.send(can.Message(arbitration_id=0x600 + node,
                                 data=[0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0],
                                 is_extended_id=False))
        deadline = time.monotonic() + args.timeout / 1000
        while (left := deadline - time.monotonic()) > 0:
            msg = bus.recv(left)
            if msg is None:
                break
            node = msg.arbitration_id - 0x580
            if (msg.is_extended_id or node not in nodes or len(msg.data) != 8
                    or msg.data[1:4] != b"\x00\x10\x00"):
                continue
            entry: dict[str, object] = {"node": node}
            if msg.data[0] & 0xE0 == 0x40 and msg.data[0] & 0x02:
                entry["device_type"] = int.from_bytes(msg.data[4:8], "little")
            elif msg.data[0] == 0x80:
                entry["abort"] = int.from_bytes(msg.data[4:8], "little")
            found[node] = entry
    finally:
        bus.shutdown()
    result = [{**found[n], **_compared(dicts, found[n])} for n in sorted(found)]
    if args.json:
        emit_json(result)
    else:
        for entry in result:
            extra = (f"device type 0x{entry['device_type']:08X}" if "device_type" in entry
                     else f"answered with abort 0x{entry.get('abort', 0):08X}"
                     if "abort" in entry else "answered")
            print(f"node {entry['node']}: {extra}{_eds_note(entry)}")
        print(f"{len(result)} node(s) found")
    return 0
