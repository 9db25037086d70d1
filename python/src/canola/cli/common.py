# SPDX-License-Identifier: Apache-2.0
"""What every ``canola`` sub-command shares: the parser class, bus options, argument types,
and the one-line error convention."""

from __future__ import annotations

import argparse
import contextlib
import json
import signal
import sys
import threading
import time
from collections.abc import Iterator
from typing import Any, Literal, NoReturn, overload

import can

from canola.bus.candump import LogFrame
from canola.bus.open import BUS_ENV, BusError, NoBusError, connection_lost, open_bus
from canola.decode import Decoder
from canola.errors import EdsError, Error, SdoAbort
from canola.master import Master, SdoTimeout
from canola.nodedicts import NodeDictionaries
from canola.pdomap import Pdo, read_pdos

__all__ = [
    "CliError",
    "Parser",
    "UsageError",
    "add_announce_option",
    "add_bus_options",
    "add_dictionary_options",
    "add_group",
    "add_master_options",
    "add_pdo_reading_options",
    "bus_from_args",
    "decoder_from_args",
    "dictionaries_from_args",
    "emit_json",
    "live_frames",
    "master_from_args",
    "node_id",
    "node_or_all",
    "positive_ms",
    "stop_signals",
]


class CliError(Exception):
    """A failure the command reports as one line on stderr, exit code 1."""

    def __init__(self, message: str, code: int = 1) -> None:
        super().__init__(message)
        self.code = code


class UsageError(CliError):
    """Bad arguments: one line on stderr, exit code 2."""

    def __init__(self, message: str) -> None:
        super().__init__(message, 2)


class Parser(argparse.ArgumentParser):
    """argparse, but a bad argument is one line (``canola sdo read: error: ...``)."""

    def error(self, message: str) -> NoReturn:
        raise UsageError(f"{self.prog}: error: {message} (see {self.prog} --help)")


def add_group(subs: argparse._SubParsersAction[Parser], name: str, help_text: str,
              description: str) -> argparse._SubParsersAction[Parser]:
    """A command with sub-commands (``canola sdo read``, ``canola pdo show``, ...)."""
    p = subs.add_parser(name, help=help_text, description=description)
    group = p.add_subparsers(dest=f"{name}_command", metavar="SUBCOMMAND", parser_class=Parser)
    group.required = True
    return group


def int_in_range(text: str, low: int, high: int, what: str, unit: str = "") -> int:
    """``text`` as an integer (decimal or 0x-hex) in ``low..high``, else the one-line
    argparse error "bad WHAT 'TEXT': LOW..HIGH[ UNIT]"."""
    try:
        value = int(text, 0)
    except ValueError:
        value = low - 1
    if not low <= value <= high:
        raise argparse.ArgumentTypeError(
            f"bad {what} {text!r}: {low}..{high}{' ' + unit if unit else ''}")
    return value


def node_id(text: str) -> int:
    """A node-ID 1..127 (decimal or 0x-hex)."""
    return int_in_range(text, 1, 127, "node-ID")


def node_or_all(text: str) -> int:
    """A node-ID 1..127, or ``all`` (0)."""
    if text.lower() in ("all", "0"):
        return 0
    try:
        return node_id(text)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(f"bad node-ID {text!r}: 1..127 or all") from None


def positive_ms(text: str) -> int:
    return int_in_range(text, 1, 3_600_000, "time", "ms")


def add_bus_options(parser: argparse.ArgumentParser) -> None:
    """``--iface IFACE`` | ``--bus URL``; without either the default bus
    (:func:`canola.bus.open.default_bus`: ``CANOLA_BUS``, else python-can's configuration)."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--iface", metavar="IFACE", help="SocketCAN interface, e.g. can0")
    group.add_argument("--bus", metavar="URL",
                       help="socketcand://HOST:PORT/CHANNEL, socketcan://IFACE, "
                            "slcan://HOST:PORT or virtual://CHANNEL (default: "
                            f"${BUS_ENV}, else python-can's "
                            "configuration: CAN_INTERFACE, CAN_CHANNEL, ~/.canrc, ...)")


def bus_from_args(args: argparse.Namespace) -> can.BusABC:
    """The bus of ``--iface``/``--bus``, else the default bus. No bus at all is a usage
    error (exit 2), one that does not open a failure (exit 1)."""
    try:
        return open_bus(iface=args.iface, url=args.bus)
    except NoBusError as exc:
        raise CliError(f"canola: {exc}", 2) from None
    except BusError as exc:
        raise CliError(str(exc)) from None


def add_dictionary_options(parser: argparse.ArgumentParser) -> None:
    """``--eds FILE`` / ``--dcf FILE`` (every node) and ``--eds N=FILE`` (node N),
    repeatable: entries by name, types and PDO mappings from the files."""
    for flag in ("--eds", "--dcf"):
        parser.add_argument(flag, dest="dictionaries", action="append", default=[],
                            metavar="[N=]FILE",
                            help=f"{flag[2:].upper()} of every node, or of node N (N=FILE; "
                                 "repeatable): entries by name, types, PDO mappings")


def dictionaries_from_args(args: argparse.Namespace) -> NodeDictionaries:
    """The files of ``--eds``/``--dcf``, each read once now (a bad one fails here)."""
    try:
        dicts = NodeDictionaries(args.dictionaries)
        dicts.check()
    except EdsError as exc:
        raise CliError(str(exc)) from None
    except Error as exc:
        raise CliError(f"canola: error: {exc}", 2) from None
    return dicts


def add_pdo_reading_options(parser: argparse.ArgumentParser) -> None:
    """``--read-pdos NODE``: PDO mappings read from the device (and the options of the
    master that reads them)."""
    parser.add_argument("--read-pdos", type=node_id, action="append", default=[],
                        metavar="NODE",
                        help="read node NODE's PDO mappings by SDO first and decode its "
                             "PDOs by them (repeatable)")
    add_master_options(parser, announce=False)


def decoder_from_args(args: argparse.Namespace) -> Decoder:
    """A decoder with the dictionaries of ``--eds``/``--dcf`` and the PDOs of
    ``--read-pdos`` (read now, before the command listens)."""
    dicts = dictionaries_from_args(args)
    pdos: dict[int, list[Pdo]] = {}
    if args.read_pdos:
        with master_from_args(args) as master:
            for node in args.read_pdos:
                try:
                    pdos[node] = read_pdos(master.sdo(node), dicts.get(node))
                except SdoTimeout:
                    raise CliError(f"no response from node {node} (SDO time-out "
                                   f"{args.sdo_timeout} ms)") from None
                except SdoAbort as exc:
                    raise CliError(f"node {node}: reading its PDOs: {exc}") from None
    return Decoder(dicts, pdos)


def add_master_options(p: argparse.ArgumentParser, *, announce: bool = True,
                       sdo: bool = True) -> None:
    """``--master-id`` of the commands that run a canola.Master, ``--sdo-timeout`` for
    those that talk SDO (``sdo``), and ``--announce`` for the tools (``announce``)."""
    p.add_argument("--master-id", type=node_id, default=127, metavar="N",
                   help="node-ID the master uses (default 127)")
    if sdo:
        p.add_argument("--sdo-timeout", type=positive_ms, default=1000, metavar="MS",
                       help="SDO time-out (default 1000 ms)")
    if announce:
        add_announce_option(p)


def add_announce_option(p: argparse.ArgumentParser) -> None:
    """``--announce``: a tool's master takes part in the network (boot-up, heartbeat)."""
    p.add_argument("--announce", action="store_true",
                   help="take part in the network as node --master-id: send its boot-up "
                        "(and heartbeat, if configured); by default the command is silent "
                        "on the bus but for its requests")


@contextlib.contextmanager
def master_from_args(args: argparse.Namespace, sdo_timeout_ms: int | None = None, *,
                     announce: bool | None = None) -> Iterator[Master]:
    """A started canola.Master (node-ID ``args.master_id``) on the bus of ``args``; stopped
    and the bus shut down after. The SDO time-out is ``sdo_timeout_ms``, by default
    ``args.sdo_timeout`` (:func:`add_master_options`). It announces itself (boot-up,
    heartbeat) when ``announce``, by default when ``args.announce``: a command that only
    asks or commands is no member of the network."""
    bus = bus_from_args(args)
    try:
        timeout = getattr(args, "sdo_timeout", 1000) if sdo_timeout_ms is None \
            else sdo_timeout_ms
        if announce is None:
            announce = bool(getattr(args, "announce", False))
        master = Master(bus, args.master_id, sdo_timeout_ms=timeout, announce=announce)
        master.start()
        try:
            yield master
        finally:
            master.stop()
    finally:
        bus.shutdown()


def emit_json(obj: Any) -> None:
    """One JSON document per line on stdout."""
    sys.stdout.write(json.dumps(obj, sort_keys=True) + "\n")
    sys.stdout.flush()


@contextlib.contextmanager
def stop_signals() -> Iterator[threading.Event]:
    """For a command that runs until stopped: an Event that SIGINT (Ctrl-C) and SIGTERM set,
    the previous handlers back at the end. Wait on it with a time-out (``while not
    stop.wait(0.2)``): Python runs a handler in the main thread only when that thread runs
    Python code, and an untimed wait is not woken when the signal lands on another thread."""
    stop = threading.Event()
    old = {s: signal.signal(s, lambda *_: stop.set()) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield stop
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)


@overload
def live_frames(bus: can.BusABC, duration: float | None) -> Iterator[LogFrame]: ...


@overload
def live_frames(bus: can.BusABC, duration: float | None, *,
                idle: Literal[True]) -> Iterator[LogFrame | None]: ...


def live_frames(bus: can.BusABC, duration: float | None, *,
                idle: bool = False) -> Iterator[LogFrame | None]:
    """Frames received on ``bus`` until ``duration`` seconds have passed (forever if None);
    with ``idle``, None whenever 0.2 s pass without a frame."""
    deadline = None if duration is None else time.monotonic() + duration
    channel = str(getattr(bus, "channel_info", "bus"))
    while True:
        wait = 0.2 if deadline is None else min(0.2, deadline - time.monotonic())
        if wait <= 0:
            return
        msg = bus.recv(wait)
        if msg is None and connection_lost(bus):
            raise CliError("the bus connection was closed by the server")
        if msg is None or msg.is_error_frame:
            if idle:
                yield None
            continue
        yield LogFrame(msg.timestamp, channel, msg.arbitration_id, bytes(msg.data),
                       msg.is_extended_id, msg.is_remote_frame)
