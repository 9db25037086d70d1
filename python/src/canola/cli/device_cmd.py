# SPDX-License-Identifier: Apache-2.0
"""``canola device``: run a canola device (canola.Device) from an EDS/DCF on a bus; it
prints its NMT states and every EMCY it sends or receives, in words."""

from __future__ import annotations

import argparse
import logging
import os
import sys
import threading

from canola._engine import Frame
from canola._nodebase import EmcyEvent
from canola.bus.open import connection_lost
from canola.cli.common import (
    CliError,
    Parser,
    add_bus_options,
    bus_from_args,
    int_in_range,
    node_id,
    positive_ms,
    stop_signals,
)
from canola.device import Device, StoreRejectedEvent
from canola.emcycodes import emcy_line
from canola.errors import EdsError, Error

log = logging.getLogger("canola.device")

#: Largest --domain-size: every DOMAIN entry of the device gets this much RAM.
MAX_DOMAIN = 64 * 1024 * 1024


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    p = subs.add_parser(
        "device", help="run a device from an EDS/DCF",
        description="Run a canola device with the dictionary of an EDS/DCF on a bus until "
                    "SIGINT/SIGTERM; prints its NMT state changes and EMCYs in words (e.g. "
                    "0x8150 when another node uses its node-ID). With --store, 0x1010 "
                    "'save' writes the parameters to DIR and resets load them. DOMAIN and "
                    "string entries live in RAM of --domain-size/--string-size bytes: an SDO "
                    "download of any protocol writes values up to that size (larger ones "
                    "are refused with 0x06070012).")
    p.add_argument("--eds", required=True, metavar="FILE", help="EDS or DCF file")
    p.add_argument("--node-id", type=node_id, required=True, metavar="N", help="1..127")
    add_bus_options(p)
    p.add_argument("--store", metavar="DIR",
                   help="parameter storage folder (made when missing and its parent "
                        "exists; you need permission to write in it)")
    p.add_argument("--sdo-timeout", type=positive_ms, default=1000, metavar="MS",
                   help="the SDO server's time-out (default 1000 ms; max 65535)")
    p.add_argument("--domain-size", type=lambda t: int_in_range(t, 1, MAX_DOMAIN, "size",
                                                                "bytes"),
                   default=4096, metavar="BYTES",
                   help="RAM of each DOMAIN entry, the largest value an SDO download "
                        f"may write into it (default 4096; 1..{MAX_DOMAIN})")
    p.add_argument("--string-size", type=lambda t: int_in_range(t, 1, 0xFFFF, "size",
                                                                "bytes"),
                   default=256, metavar="BYTES",
                   help="RAM of each VISIBLE/OCTET/UNICODE_STRING entry, at least its "
                        "default's length (default 256; 1..65535)")
    p.set_defaults(func=run)


def _report_own_emcys(device: Device) -> None:
    """Print every EMCY the device sends, in words (a duplicate node-ID, 0x8150, among
    them): its frames on the COB-ID its 0x1014 holds when they are sent."""

    def sent(frame: Frame) -> None:
        if frame.extended or frame.rtr or len(frame.data) != 8:
            return
        cob_id = device.od.get(0x1014, 0)
        if not isinstance(cob_id, int) or cob_id >> 31 or frame.can_id != cob_id & 0x7FF:
            return
        data = frame.data
        print(f"node {device.node_id}: EMCY "
              f"{emcy_line(int.from_bytes(data[:2], 'little'), data[2], data[3:])}",
              flush=True)

    device.on_frame_sent(sent)


def _store_folder(path: str) -> None:
    """``--store``: a folder to write in, made when missing (its parent must exist: a
    mistyped path makes no tree of folders); a one-line CliError when it cannot be."""
    if not os.path.exists(path):
        parent = os.path.dirname(os.path.abspath(path))
        if not os.path.isdir(parent):
            raise CliError(f"--store {path}: no such folder (nor its parent {parent})")
        try:
            os.mkdir(path)
        except OSError as exc:
            raise CliError(f"--store {path}: cannot make the folder: {exc.strerror}") from None
    if not os.path.isdir(path):
        raise CliError(f"--store {path}: not a folder")
    if not os.access(path, os.R_OK | os.W_OK | os.X_OK):
        raise CliError(f"--store {path}: no permission to read and write in the folder")


def run(args: argparse.Namespace) -> int:
    if not os.path.isfile(args.eds):
        raise CliError(f"cannot read {args.eds}: no such file")
    if args.sdo_timeout > 0xFFFF:
        raise CliError(f"canola device: error: --sdo-timeout {args.sdo_timeout}: at most 65535",
                       2)
    if args.store is not None:
        _store_folder(args.store)
    with stop_signals() as stop:
        return _serve(args, stop)


def _serve(args: argparse.Namespace, stop: threading.Event) -> int:
    """The device on the bus until ``stop`` is set."""
    bus = bus_from_args(args)
    try:
        try:
            device = Device(args.eds, args.node_id, bus, store_dir=args.store,
                            sdo_timeout_ms=args.sdo_timeout, domain_size=args.domain_size,
                            string_size=args.string_size)
        except EdsError as exc:  # its problems name the file: the first, and how many more
            more = len(exc.problems) - 1
            raise CliError(f"{exc.problems[0]}" + (f" (and {more} more: canola eds check "
                                                   f"{args.eds})" if more else "")) from None
        except Error as exc:
            raise CliError(f"{args.eds}: {exc}") from None

        def on_state(state: str) -> None:
            print(f"node {device.node_id}: {state}", flush=True)

        def on_store_rejected(event: StoreRejectedEvent) -> None:
            where = os.path.join(args.store, event.file)
            print(f"canola device: node {device.node_id}: {where}: {event.reason}; ignored, "
                  f"{event.group} parameters start with their defaults "
                  f"(EMCY 0x{event.code:04X})", file=sys.stderr, flush=True)

        def on_emcy(event: EmcyEvent) -> None:  # another node's, when 0x1028 watches it
            print(f"node {device.node_id}: EMCY from node {event.node} "
                  f"{emcy_line(event.code, event.register, event.manufacturer)}", flush=True)

        device.on_state(on_state)
        device.on_store_rejected(on_store_rejected)
        device.on_emcy(on_emcy)
        _report_own_emcys(device)
        device.start()
        print(f"canola device: node {device.node_id} from {args.eds} running", flush=True)
        try:
            while not stop.wait(0.2):
                if connection_lost(bus):
                    raise CliError("the bus connection was closed by the server")
        finally:
            device.stop()
        print(f"canola device: node {device.node_id} stopped", flush=True)
    finally:
        bus.shutdown()
    return 0
