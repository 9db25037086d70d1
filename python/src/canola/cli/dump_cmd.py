# SPDX-License-Identifier: Apache-2.0
"""``canola dump``: CAN traffic in CANopen terms, live from a bus or from a candump file;
``--node``, ``--service`` and ``--id`` choose the frames shown, ``--eds`` names entries and
decodes PDOs by their mapping."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Iterator

from canola.bus.candump import CandumpError, LogFrame, read_log
from canola.cli.common import (
    CliError,
    Parser,
    add_bus_options,
    add_dictionary_options,
    add_pdo_reading_options,
    bus_from_args,
    decoder_from_args,
    emit_json,
    int_in_range,
    live_frames,
    node_id,
)
from canola.decode import Event


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    p = subs.add_parser(
        "dump", help="decode traffic into CANopen meaning",
        description="Print every frame with its CANopen meaning (NMT, SYNC, TIME, EMCY, "
                    "heartbeat, PDO by COB-ID, SDO transfers with their values), live from a "
                    "bus or from a candump file (log or screen format; - is stdin).")
    p.add_argument("file", nargs="?", metavar="FILE", help="candump file instead of a bus")
    add_bus_options(p)
    add_dictionary_options(p)
    add_pdo_reading_options(p)
    p.add_argument("--node", type=node_id, action="append", metavar="N",
                   help="only frames of node N (repeatable)")
    p.add_argument("--service", type=_services, action="append", metavar="NAME[,NAME]",
                   help=f"only these services: {', '.join(SERVICES)} (repeatable)")
    p.add_argument("--id", type=_id_range, action="append", metavar="ID[-ID]",
                   help="only these CAN-IDs, e.g. 0x181 or 0x181-0x1FF (repeatable)")
    p.add_argument("--count", type=int, metavar="N", help="stop after N frames (shown)")
    p.add_argument("--duration", type=float, metavar="S", help="stop after S seconds (live)")
    p.add_argument("--json", action="store_true", help="one JSON object per frame")
    p.set_defaults(func=run)


#: --service NAME -> the kinds of canola.decode.Event it shows.
SERVICES: dict[str, tuple[str, ...]] = {
    "nmt": ("nmt",), "hb": ("heartbeat", "bootup", "guard"), "sdo": ("sdo",),
    "pdo": ("pdo",), "emcy": ("emcy",), "sync": ("sync",), "time": ("time",),
    "lss": ("lss",),
}


def _services(text: str) -> set[str]:
    names = {name.strip().lower() for name in text.split(",")}
    unknown = sorted(names - set(SERVICES))
    if unknown:
        raise argparse.ArgumentTypeError(f"unknown service {unknown[0]!r}: "
                                         f"{', '.join(SERVICES)}")
    return {kind for name in names for kind in SERVICES[name]}


def _id_range(text: str) -> range:
    low, _, high = text.partition("-")
    first = int_in_range(low, 0, 0x1FFFFFFF, "CAN-ID")
    last = int_in_range(high, first, 0x1FFFFFFF, "CAN-ID") if high else first
    return range(first, last + 1)


def _shown(args: argparse.Namespace, frame: LogFrame, event: Event) -> bool:
    """Whether the filters of ``args`` (each one a choice of alternatives) let ``frame``
    through."""
    return ((not args.node or event.node in args.node)
            and (not args.service or any(event.kind in kinds for kinds in args.service))
            and (not args.id or any(frame.can_id in ids for ids in args.id)))


def run(args: argparse.Namespace) -> int:
    live = args.file is None
    if not live and (args.iface is not None or args.bus is not None):
        raise CliError("canola dump: error: give a FILE or --iface/--bus (not both)", 2)
    if args.count is not None and args.count < 1:
        raise CliError(f"canola dump: error: bad --count {args.count}", 2)
    decoder = decoder_from_args(args)
    frames = _live(args) if live else _file(args.file)
    seen = 0
    try:
        for frame in frames:
            event = decoder.decode(frame.can_id, frame.data, rtr=frame.rtr,
                                   extended=frame.extended)
            if not _shown(args, frame, event):
                continue
            _print(event, frame, args.json)
            seen += 1
            if args.count is not None and seen >= args.count:
                break
    except CandumpError as exc:
        raise CliError(str(exc)) from None
    except KeyboardInterrupt:  # Ctrl-C ends a live dump
        pass
    return 0


def _file(name: str) -> Iterator[LogFrame]:
    if name == "-":
        yield from read_log(sys.stdin, "stdin")
        return
    try:
        with open(name, encoding="ascii", errors="replace") as stream:
            yield from read_log(stream, name)
    except OSError as exc:
        raise CliError(f"cannot read {name}: {exc.strerror or exc}") from None


def _live(args: argparse.Namespace) -> Iterator[LogFrame]:
    bus = bus_from_args(args)
    try:
        yield from live_frames(bus, args.duration)
    finally:
        bus.shutdown()


def _print(event: Event, frame: LogFrame, as_json: bool) -> None:
    stamp = frame.timestamp if frame.timestamp is not None else time.time()
    ident = f"{frame.can_id:08X}" if frame.extended else f"{frame.can_id:03X}"
    if as_json:
        emit_json({"t": round(stamp, 6), "id": frame.can_id, "data": frame.data.hex(),
                   "rtr": frame.rtr, "kind": event.kind, "node": event.node,
                   "text": event.text, **event.fields})
        return
    payload = "R" if frame.rtr else frame.data.hex().upper()
    print(f"({stamp:.6f}) {ident}#{payload:<16} {event.text}", flush=True)
