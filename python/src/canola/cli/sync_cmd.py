# SPDX-License-Identifier: Apache-2.0
"""``canola sync`` and ``canola time``: produce SYNC and TIME.

    canola sync 10 [--counter 8] [--count N | --duration S]   SYNC every 10 ms
    canola time [--period MS] [--count N]                      TIME (now, UTC)

Both run until Ctrl-C, ``--count`` frames or ``--duration`` seconds (the frames the command
sent itself: SYNC or TIME of another producer on the bus does not count); ``canola time``
without ``--period`` sends one frame. The producer is a silent canola.Master (node
``--master-id``, no boot-up nor heartbeat): SYNC comes from the core's SYNC producer
(0x1005/0x1006/0x1019, the first one period after the start), TIME from
:meth:`canola.Master.start_time` (the first at once), so the node's timers keep the period,
in virtual time on a simulated bus too.
"""

from __future__ import annotations

import argparse
import contextlib
import datetime as dt
import threading
from collections.abc import Callable

from canola.cli.common import (
    CliError,
    Parser,
    add_bus_options,
    add_master_options,
    emit_json,
    int_in_range,
    master_from_args,
    positive_ms,
)
from canola.core import SimBus
from canola.master import Frame, Master

#: Longest wait between checks for the end (seconds of the master's time); on a simulated
#: bus a SYNC period if shorter, so that a count stops the producer between two frames.
_STEP_S = 0.2
#: The COB-ID of the SYNC :meth:`canola.Master.start_sync` produces.
_SYNC_COB_ID = 0x080


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    s = subs.add_parser("sync", help="produce SYNC",
                        description="Send SYNC (COB-ID 0x080) every PERIOD_MS until Ctrl-C, "
                                    "--count frames or --duration seconds; the first one "
                                    "PERIOD_MS after the start.")
    s.add_argument("period", type=positive_ms, metavar="PERIOD_MS", help="SYNC period")
    s.add_argument("--counter", type=lambda t: int_in_range(t, 2, 240, "counter overflow"),
                   metavar="N", help="with a counter 1..N (CiA 301 0x1019; 2..240)")
    _add_common(s)
    s.set_defaults(func=run_sync)

    t = subs.add_parser("time", help="produce TIME",
                        description="Send TIME (COB-ID 0x100) with the time of day (UTC): "
                                    "once, or every --period MS (the first at once).")
    t.add_argument("--period", type=positive_ms, metavar="MS", help="repeat every MS")
    _add_common(t)
    t.set_defaults(func=run_time)


def _add_common(p: argparse.ArgumentParser) -> None:
    add_bus_options(p)
    add_master_options(p, sdo=False)
    p.add_argument("--count", type=lambda t: int_in_range(t, 1, 1 << 31, "count"),
                   metavar="N", help="stop after N frames of its own")
    p.add_argument("--duration", type=float, metavar="S", help="stop after S seconds")
    p.add_argument("--json", action="store_true", help="print a JSON summary")


class _Count:
    """Frames produced so far; ``done`` once ``limit`` (None: no limit) is reached."""

    def __init__(self, limit: int | None) -> None:
        self.sent = 0
        self.limit = limit
        self.done = threading.Event()

    def one(self, stop: Callable[[], None]) -> None:
        """One more frame; the last one of the count calls ``stop`` (the producer's)."""
        if self.done.is_set():
            return
        self.sent += 1
        if self.limit is not None and self.sent >= self.limit:
            stop()
            self.done.set()


def _produce(args: argparse.Namespace, what: str,
             start: Callable[[Master, _Count], Callable[[], None]], sim_step_s: float) -> int:
    """Run the producer ``start`` sets up on a master (it returns its stop) until the
    count, the duration or Ctrl-C, then stop it."""
    if args.duration is not None and args.duration <= 0:
        raise CliError(f"canola {what}: error: --duration must be > 0", 2)
    count = _Count(args.count)
    with master_from_args(args) as master:
        stop = start(master, count)
        try:
            with contextlib.suppress(KeyboardInterrupt):
                _wait(master, count.done, args.duration, sim_step_s)
        finally:
            stop()
    if args.json:
        emit_json({"service": what, "frames": count.sent})
    return 0


def _wait(master: Master, done: threading.Event, duration: float | None,
          sim_step_s: float) -> None:
    """Until ``done`` or ``duration`` seconds (None: no end) of the master's time: virtual
    time on a simulated bus, run in steps of ``sim_step_s``; the wall clock on python-can."""
    sim = isinstance(master.bus, SimBus)
    step = sim_step_s if sim else _STEP_S
    left = duration
    while not done.is_set() and (left is None or left > 0):
        chunk = step if left is None else min(step, left)
        if sim:
            master.wait(chunk)
        else:
            done.wait(chunk)
        if left is not None:
            left -= chunk


def run_sync(args: argparse.Namespace) -> int:
    def start(master: Master, count: _Count) -> Callable[[], None]:
        def sent(frame: Frame) -> None:  # its own SYNCs: another producer's do not count
            if frame.can_id == _SYNC_COB_ID:
                count.one(master.stop_sync)

        master.on_frame_sent(sent)
        master.start_sync(args.period * 1000, args.counter or 0)
        return master.stop_sync

    return _produce(args, "sync", start, min(_STEP_S, args.period / 1000))


def run_time(args: argparse.Namespace) -> int:
    if args.period is None and (args.count is not None or args.duration is not None):
        raise CliError("canola time: error: --count and --duration need --period", 2)
    if args.period is None:
        args.count = 1

    def start(master: Master, count: _Count) -> Callable[[], None]:
        master.send_time()
        count.one(lambda: None)
        if not count.done.is_set():
            master.start_time(args.period, clock=lambda: _now(master, count))
        return master.stop_time

    return _produce(args, "time", start, _STEP_S)


def _now(master: Master, count: _Count) -> dt.datetime:
    """The moment of the next periodic TIME frame; the last one of the count stops the
    production (the frame is sent after this returns)."""
    count.one(master.stop_time)
    return dt.datetime.now(dt.UTC)
