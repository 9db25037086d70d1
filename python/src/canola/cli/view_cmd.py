# SPDX-License-Identifier: Apache-2.0
"""``canola view``: a live picture of the network in the browser (:mod:`canola.view`)."""

from __future__ import annotations

import argparse

import can

from canola.bus.open import open_bus as bus_open
from canola.cli.common import (
    CliError,
    Parser,
    add_bus_options,
    add_dictionary_options,
    add_master_options,
    bus_from_args,
    dictionaries_from_args,
    node_id,
    stop_signals,
)
from canola.errors import Error
from canola.master import Master

LISTEN_HELP = ("address of the web page (default 127.0.0.1:8080; port 0: any free one). "
               "Another than a loopback address lets other machines see the bus")
WRITE_HELP = ("let the page write entries by SDO and send NMT commands: from this machine, "
              "or from another with the token the command prints")


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    p = subs.add_parser(
        "view", help="live picture of the network in the browser",
        description="Serve a local web page that shows the bus live: every node (NMT state, "
                    "name, identity, heartbeat, boot-ups, lost nodes), an event log (boot-up, "
                    "NMT, state changes, EMCY in words, heartbeat loss, SDO aborts), PDO "
                    "signals decoded by the EDS/DCF and plotted, bus load and frames per "
                    "second, the raw frames, and an SDO browser of each node's EDS. Runs "
                    "until Ctrl-C or SIGTERM.")
    add_bus_options(p)
    add_dictionary_options(p)
    p.add_argument("--read-pdos", type=node_id, action="append", default=[], metavar="NODE",
                   help="read node NODE's PDO mappings by SDO at the start and decode its "
                        "PDOs by them (repeatable; the page can read them too)")
    add_master_options(p, announce=False)
    p.add_argument("--listen", default="127.0.0.1:8080", metavar="HOST:PORT", help=LISTEN_HELP)
    p.add_argument("--allow-write", action="store_true", help=WRITE_HELP)
    p.add_argument("--bitrate", type=int, default=500_000, metavar="BIT/S",
                   help="the bus's bit rate, for the load figure (default 500000)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from canola.view.launch import parse_listen, start_view  # noqa: PLC0415 (aiohttp: lazily)

    if not 10_000 <= args.bitrate <= 1_000_000:
        raise CliError(f"canola view: error: bad --bitrate {args.bitrate}: 10000..1000000", 2)
    try:
        parse_listen(args.listen)
    except Error as exc:
        raise CliError(f"canola view: error: {exc}", 2) from None
    dicts = dictionaries_from_args(args)
    bus_from_args(args).shutdown()  # a bus that does not open fails here, before serving

    def open_bus() -> can.BusABC:  # BusError, as the reader expects
        return bus_open(iface=args.iface, url=args.bus)

    def open_master() -> Master:
        return Master(open_bus(), args.master_id, sdo_timeout_ms=args.sdo_timeout,
                      announce=False)

    with stop_signals() as stop:  # Ctrl-C as early as the line with the URL
        try:
            view = start_view(open_bus=open_bus, open_master=open_master,
                              dictionaries=dicts, listen=args.listen,
                              allow_write=args.allow_write, bitrate=args.bitrate,
                              where=f"bus {args.bus or args.iface or 'default'}")
        except Error as exc:
            raise CliError(str(exc)) from None
        try:
            for node in args.read_pdos:
                view.read_pdos(node)
            while not stop.wait(0.2):
                pass
        finally:
            view.stop()
    return 0
