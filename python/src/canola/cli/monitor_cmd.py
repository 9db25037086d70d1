# SPDX-License-Identifier: Apache-2.0
"""``canola monitor``: a live view of every node (state, heartbeat age, EMCY, PDO rates)."""

from __future__ import annotations

import argparse
import contextlib
import sys
import time

import can

from canola.cli.common import (
    CliError,
    Parser,
    add_bus_options,
    add_dictionary_options,
    add_pdo_reading_options,
    bus_from_args,
    decoder_from_args,
    emit_json,
    live_frames,
)
from canola.netview import NetworkView, render


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    p = subs.add_parser(
        "monitor", help="live view of every node",
        description="Watch the bus and show every node: NMT state, heartbeat age, last EMCY, "
                    "PDO rates. On a terminal the view refreshes until Ctrl-C; with --once "
                    "or when the output is not a terminal it listens for --duration seconds "
                    "and prints the view once.")
    add_bus_options(p)
    add_dictionary_options(p)
    add_pdo_reading_options(p)
    p.add_argument("--once", action="store_true", help="print one view and exit")
    p.add_argument("--duration", type=float, default=3.0, metavar="S",
                   help="listening time of --once (default 3 s)")
    p.add_argument("--window", type=float, default=5.0, metavar="S",
                   help="PDO rates over the last S seconds (default 5)")
    p.add_argument("--json", action="store_true", help="the view as JSON (implies --once)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    if args.duration <= 0 or args.window <= 0:
        raise CliError("canola monitor: error: --duration and --window must be > 0", 2)
    once = args.once or args.json or not sys.stdout.isatty()
    view = NetworkView(window=args.window, decoder=decoder_from_args(args))
    bus = bus_from_args(args)
    try:
        if once:
            for f in live_frames(bus, args.duration):
                view.feed(time.time(), f.can_id, f.data, rtr=f.rtr, extended=f.extended)
            rows = view.rows(time.time())
            if args.json:
                emit_json({"frames": view.frames, "nodes": rows})
            else:
                print(render(rows, view.frames))
            return 0
        with contextlib.suppress(KeyboardInterrupt):  # Ctrl-C is how the live view ends
            _live(view, bus)
    finally:
        bus.shutdown()
    return 0


def _live(view: NetworkView, bus: can.BusABC) -> None:
    next_draw = 0.0
    frames = live_frames(bus, None, idle=True)
    for f in frames:
        if f is not None:
            view.feed(time.time(), f.can_id, f.data, rtr=f.rtr, extended=f.extended)
        if time.monotonic() >= next_draw:  # redrawn on a quiet bus too (ages grow)
            next_draw = time.monotonic() + 0.5
            sys.stdout.write("\x1b[H\x1b[2J" + render(view.rows(time.time()), view.frames)
                             + "\n")
            sys.stdout.flush()
