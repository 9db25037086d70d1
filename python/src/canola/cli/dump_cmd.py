"""``canola dump``: CAN traffic in CANopen terms, live from a bus or from a candump file."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Iterator

from canola.candump import CandumpError, LogFrame, read_log
from canola.cli.common import (
    CliError,
    Parser,
    add_bus_options,
    bus_from_args,
    emit_json,
    live_frames,
)
from canola.decode import Decoder


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    p = subs.add_parser(
        "dump", help="decode traffic into CANopen meaning",
        description="Print every frame with its CANopen meaning (NMT, SYNC, TIME, EMCY, "
                    "heartbeat, PDO by COB-ID, SDO transfers with their values), live from a "
                    "bus or from a candump file (log or screen format; - is stdin).")
    p.add_argument("file", nargs="?", metavar="FILE", help="candump file instead of a bus")
    add_bus_options(p)
    p.add_argument("--count", type=int, metavar="N", help="stop after N frames")
    p.add_argument("--duration", type=float, metavar="S", help="stop after S seconds (live)")
    p.add_argument("--json", action="store_true", help="one JSON object per frame")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    live = args.file is None
    if not live and (args.iface is not None or args.bus is not None):
        raise CliError("canola dump: error: give a FILE or --iface/--bus (not both)", 2)
    if args.count is not None and args.count < 1:
        raise CliError(f"canola dump: error: bad --count {args.count}", 2)
    decoder = Decoder()
    frames = _live(args) if live else _file(args.file)
    seen = 0
    try:
        for frame in frames:
            _print(decoder, frame, args.json)
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


def _print(decoder: Decoder, frame: LogFrame, as_json: bool) -> None:
    event = decoder.decode(frame.can_id, frame.data, rtr=frame.rtr, extended=frame.extended)
    stamp = frame.timestamp if frame.timestamp is not None else time.time()
    ident = f"{frame.can_id:08X}" if frame.extended else f"{frame.can_id:03X}"
    if as_json:
        emit_json({"t": round(stamp, 6), "id": frame.can_id, "data": frame.data.hex(),
                   "rtr": frame.rtr, "kind": event.kind, "node": event.node,
                   "text": event.text, **event.fields})
        return
    payload = "R" if frame.rtr else frame.data.hex().upper()
    print(f"({stamp:.6f}) {ident}#{payload:<16} {event.text}", flush=True)
