# SPDX-License-Identifier: Apache-2.0
"""``canola demo``: the demo network (:mod:`canola.demo`), on the simulated bus or a real one."""

from __future__ import annotations

import argparse
import sys
import threading
from typing import TextIO

from canola.cli import view_cmd
from canola.cli.common import CliError, Parser, bus_from_args, emit_json
from canola.demo.devices import DEVICES
from canola.demo.network import CanNetwork, Network, SimNetwork
from canola.demo.report import failure_line, summary_json, summary_table
from canola.demo.scenario import FAULTS, Faults, Scenario
from canola.demo.trace import Trace
from canola.errors import Error


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    p = subs.add_parser(
        "demo", help="a master and three devices: boot, configure, PDOs, EMCY, loss",
        description="A master (node 0x3F) and three devices (an I/O module, a drive, a sensor) "
                    "go through the life of a CANopen network: boot-ups, NMT "
                    "pre-operational, the CiA 302-2 manager checking each device's "
                    "identity, configuring its heartbeat and PDOs by SDO and starting it, "
                    "SYNC every 10 ms with TPDOs and RPDOs, an EMCY and a heartbeat loss. "
                    "Prints every frame decoded and a summary; exits 0 only when every step "
                    "was seen. Runs on the simulated bus in virtual time unless --bus or "
                    "--iface puts it on a real or software bus.")
    p.add_argument("--realtime", action="store_true",
                   help="pace the simulated bus to the wall clock, to watch it live")
    group = p.add_mutually_exclusive_group()
    group.add_argument("--iface", metavar="IFACE", help="SocketCAN interface, e.g. vcan0")
    group.add_argument("--bus", metavar="URL",
                       help="socketcand://HOST:PORT/CHANNEL, socketcan://IFACE or "
                            "virtual://CHANNEL")
    p.add_argument("--quiet", action="store_true", help="print the summary only")
    p.add_argument("--json", action="store_true", help="the summary as one JSON document")
    p.add_argument("--every-frame", action="store_true",
                   help="also show repeated heartbeats, SYNCs, PDOs and SDO confirmations")
    p.add_argument("--time-scale", type=int, default=1, metavar="N",
                   help="stretch every period and time-out N times (1..100), for slow or "
                        "emulated machines on a real bus (default 1: SYNC every 10 ms)")
    p.add_argument("--fault", choices=sorted(FAULTS),
                   help="break one step on purpose, to see the checks catch it")
    p.add_argument("--view", action="store_true",
                   help="show the network in the browser (canola view) while it runs, in real "
                        "time, and keep it running after the story until Ctrl-C")
    p.add_argument("--listen", default="127.0.0.1:8080", metavar="HOST:PORT",
                   help="with --view: " + view_cmd.LISTEN_HELP)
    p.add_argument("--allow-write", action="store_true", help="with --view: " + view_cmd.WRITE_HELP)
    p.set_defaults(func=run)


def _network(args: argparse.Namespace) -> Network:
    if args.iface is None and args.bus is None:
        return SimNetwork(pace=args.realtime)
    if args.realtime:
        raise CliError("canola demo: error: --realtime is for the simulated bus "
                       "(a real bus is always real time)", 2)
    where = args.iface if args.iface is not None else args.bus
    first = bus_from_args(args)  # a bad bus fails here, before anything runs
    opened = [first]

    def opener() -> object:
        return opened.pop() if opened else bus_from_args(args)

    return CanNetwork(opener, where)  # type: ignore[arg-type]


def run(args: argparse.Namespace) -> int:
    if not 1 <= args.time_scale <= 100:
        raise CliError(f"canola demo: error: bad --time-scale {args.time_scale}: 1..100", 2)
    if not args.view and (args.allow_write or args.listen != "127.0.0.1:8080"):
        raise CliError("canola demo: error: --listen and --allow-write go with --view", 2)
    if args.view:
        return _run_viewed(args)
    out: TextIO | None = None if args.quiet or args.json else sys.stdout
    net = _network(args)
    try:
        trace = Trace(out, every_frame=args.every_frame)
        faults = FAULTS[args.fault] if args.fault else Faults()
        if out is not None:
            print(f"canola demo: a master (node 0x3F) and three devices on {net.description}",
                  file=out)
            for spec in DEVICES:
                print(f"  node {spec.node_id}  {spec.role:<10}  {spec.eds} ({spec.profile})",
                      file=out)
        steps = Scenario(net, trace, faults, time_scale=args.time_scale).run()
    finally:
        net.close()
    if args.json:
        emit_json(summary_json(steps, bus=net.description, frames=trace.frames,
                               seconds=round(net.now(), 6)))
    else:
        if out is not None and trace.hidden:
            print(f"\n{trace.frames} frames in {net.now():.3f} s; {trace.hidden} repeated ones "
                  "not shown (--every-frame shows them)", file=out)
        if out is not None:
            print(file=out)
        print(summary_table(steps, unicode=_unicode_ok()))
    failed = failure_line(steps)
    if failed is not None:
        print(failed, file=sys.stderr)
        return 1
    return 0


def _unicode_ok() -> bool:
    encoding = getattr(sys.stdout, "encoding", None) or "ascii"
    try:
        "\u2713\u2717".encode(encoding)
    except (UnicodeEncodeError, LookupError):
        return False
    return True


def _run_viewed(args: argparse.Namespace) -> int:
    """``--view``: the demo in real time on its bus with ``canola view`` on it, then the
    network kept running until Ctrl-C (:mod:`canola.demo.viewing`). Exits as the demo does
    (1 when a step failed), or 130 when Ctrl-C came before the story ended."""
    from canola.demo.viewing import (  # noqa: PLC0415 (aiohttp: only for --view)
        keep_running,
        start_demo_view,
        view_bus_url,
    )
    from canola.view.launch import parse_listen  # noqa: PLC0415

    if args.realtime or args.json:
        raise CliError("canola demo: error: --view runs in real time and prints the trace: "
                       "no --realtime, --json", 2)
    try:
        parse_listen(args.listen)
    except Error as exc:
        raise CliError(f"canola demo: error: {exc}", 2) from None
    if args.iface is None and args.bus is None:
        args.bus = view_bus_url()
    out: TextIO | None = None if args.quiet else sys.stdout
    net = _network(args)
    view = None
    scenario = None
    code = 130  # Ctrl-C before the story ended
    try:
        view = start_demo_view(args.bus, args.iface, listen=args.listen,
                               allow_write=args.allow_write)
        trace = Trace(out, every_frame=args.every_frame)
        faults = FAULTS[args.fault] if args.fault else Faults()
        scenario = Scenario(net, trace, faults, time_scale=args.time_scale)
        steps = scenario.run(keep_running=True)
        print(summary_table(steps, unicode=_unicode_ok()), flush=True)
        failed = failure_line(steps)
        if failed is not None:
            print(failed, file=sys.stderr, flush=True)
        code = 0 if failed is None else 1
        keep_running(scenario, net, threading.Event(), lambda text: print(text, flush=True))
    except KeyboardInterrupt:
        pass
    finally:
        if scenario is not None:
            scenario.close()
        if view is not None:
            view.stop()
        net.close()
    return code
