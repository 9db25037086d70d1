"""What every ``canola`` sub-command shares: the parser class, bus options, argument types,
and the one-line error convention."""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
import time
from collections.abc import Iterator
from typing import Any, Literal, NoReturn, overload

import can

from canola.buses import BusError, connection_lost, open_bus
from canola.candump import LogFrame
from canola.master import Master

__all__ = [
    "CliError",
    "Parser",
    "UsageError",
    "add_announce_option",
    "add_bus_options",
    "add_master_options",
    "bus_from_args",
    "emit_json",
    "live_frames",
    "master_from_args",
    "node_id",
    "node_or_all",
    "object_address",
    "positive_ms",
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


def object_address(text: str) -> tuple[int, int]:
    """``INDEX[:SUB]``: the index in hex (``0x1018`` or ``1018``), the sub-index decimal or
    0x-hex (default 0)."""
    index_text, _, sub_text = text.partition(":")
    try:
        index = int(index_text[2:] if index_text.lower().startswith("0x") else index_text, 16)
        sub = int(sub_text, 0) if sub_text else 0
    except ValueError:
        index = sub = -1
    if not (0 <= index <= 0xFFFF and 0 <= sub <= 0xFF) or not index_text:
        raise argparse.ArgumentTypeError(
            f"bad object {text!r}: INDEX:SUB, e.g. 0x1018:1")
    return index, sub


def positive_ms(text: str) -> int:
    return int_in_range(text, 1, 3_600_000, "time", "ms")


def add_bus_options(parser: argparse.ArgumentParser, *, required: bool = True) -> None:
    """``--iface IFACE`` | ``--bus URL`` (one of them ``required``, else at most one)."""
    group = parser.add_mutually_exclusive_group(required=required)
    group.add_argument("--iface", metavar="IFACE", help="SocketCAN interface, e.g. can0")
    group.add_argument("--bus", metavar="URL",
                       help="socketcand://HOST:PORT/CHANNEL, socketcan://IFACE or "
                            "virtual://CHANNEL")


def bus_from_args(args: argparse.Namespace) -> can.BusABC:
    try:
        return open_bus(iface=args.iface, url=args.bus)
    except BusError as exc:
        raise CliError(str(exc)) from None


def add_master_options(p: argparse.ArgumentParser, *, announce: bool = True) -> None:
    """``--master-id`` and ``--sdo-timeout`` of the commands that run a canola.Master, and
    ``--announce`` for the tools among them (``announce``)."""
    p.add_argument("--master-id", type=node_id, default=127, metavar="N",
                   help="node-ID the master uses (default 127)")
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
        timeout = args.sdo_timeout if sdo_timeout_ms is None else sdo_timeout_ms
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
