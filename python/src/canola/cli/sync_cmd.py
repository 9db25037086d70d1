"""``canola sync`` and ``canola time``: produce SYNC and TIME.

    canola sync 10 [--counter 8] [--count N | --duration S]   SYNC every 10 ms
    canola time [--period MS] [--count N]                      TIME (now, UTC)

Both run until Ctrl-C, ``--count`` frames or ``--duration`` seconds; ``canola time``
without ``--period`` sends one frame.
"""

from __future__ import annotations

import argparse
import contextlib
import datetime as dt
import time
from collections.abc import Callable

import can

from canola.cli.common import (
    CliError,
    Parser,
    add_bus_options,
    bus_from_args,
    emit_json,
    int_in_range,
    positive_ms,
)
from canola.formats import values


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    s = subs.add_parser("sync", help="produce SYNC",
                        description="Send SYNC (COB-ID 0x080) every PERIOD_MS until Ctrl-C, "
                                    "--count frames or --duration seconds.")
    s.add_argument("period", type=positive_ms, metavar="PERIOD_MS", help="SYNC period")
    s.add_argument("--counter", type=lambda t: int_in_range(t, 2, 240, "counter overflow"),
                   metavar="N", help="with a counter 1..N (CiA 301 0x1019; 2..240)")
    _add_common(s)
    s.set_defaults(func=run_sync)

    t = subs.add_parser("time", help="produce TIME",
                        description="Send TIME (COB-ID 0x100) with the time of day (UTC): "
                                    "once, or every --period MS.")
    t.add_argument("--period", type=positive_ms, metavar="MS", help="repeat every MS")
    _add_common(t)
    t.set_defaults(func=run_time)


def _add_common(p: argparse.ArgumentParser) -> None:
    add_bus_options(p)
    p.add_argument("--count", type=lambda t: int_in_range(t, 1, 1 << 31, "count"),
                   metavar="N", help="stop after N frames")
    p.add_argument("--duration", type=float, metavar="S", help="stop after S seconds")
    p.add_argument("--json", action="store_true", help="print a JSON summary")


def time_frame(moment: dt.datetime) -> bytes:
    """The 6 data bytes of a TIME frame for ``moment`` (naive = UTC)."""
    if moment.tzinfo is None:
        moment = moment.replace(tzinfo=dt.UTC)
    delta = moment - values.TIME_EPOCH
    if delta.total_seconds() < 0:
        raise CliError("TIME cannot express moments before 1984-01-01")
    ms = delta.seconds * 1000 + delta.microseconds // 1000
    return values.encode(0x0C, values.TimeOfDay(ms, delta.days))


def _produce(args: argparse.Namespace, period_ms: int | None, frame: Callable[[int], bytes],
             can_id: int, what: str) -> int:
    """Send ``frame(n)`` (n = 0, 1, ...) on ``can_id`` every ``period_ms`` (once when None)
    until the count, the duration or Ctrl-C; each at its own time from the start (no drift)."""
    if args.duration is not None and args.duration <= 0:
        raise CliError(f"canola {what}: error: --duration must be > 0", 2)
    count = 1 if period_ms is None else args.count
    bus = bus_from_args(args)
    sent = 0
    start = time.monotonic()
    try:
        with contextlib.suppress(KeyboardInterrupt):
            while count is None or sent < count:
                due = start + sent * (period_ms or 0) / 1000
                if args.duration is not None and due - start >= args.duration:
                    break
                time.sleep(max(0.0, due - time.monotonic()))
                bus.send(can.Message(arbitration_id=can_id, data=frame(sent),
                                     is_extended_id=False))
                sent += 1
    finally:
        bus.shutdown()
    if args.json:
        emit_json({"service": what, "frames": sent})
    return 0


def run_sync(args: argparse.Namespace) -> int:
    overflow = args.counter

    def frame(n: int) -> bytes:
        return bytes([n % overflow + 1]) if overflow else b""

    return _produce(args, args.period, frame, 0x080, "sync")


def run_time(args: argparse.Namespace) -> int:
    if args.period is None and (args.count is not None or args.duration is not None):
        raise CliError("canola time: error: --count and --duration need --period", 2)
    return _produce(args, args.period, lambda _: time_frame(dt.datetime.now(dt.UTC)), 0x100,
                    "time")
