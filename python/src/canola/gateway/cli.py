# SPDX-License-Identifier: Apache-2.0
"""``canola gateway``: the CiA 309-3 ASCII gateway as a command.

    canola gateway [--iface IFACE | --bus URL | --simulate EDS] [--listen WHERE]
                   [--node-id N] [--sdo-timeout MS] [--eds FILE] [--max-clients N]
                   [--max-line BYTES] [--max-queued BYTES] [--max-queued-total BYTES]
                   [--idle-timeout S]

``--listen`` is ``tcp:HOST:PORT`` (default tcp:127.0.0.1:6000, loopback only),
``unix:PATH`` or ``stdio``. A TCP address that is not loopback needs a token (``--token``
or ``CANOLA_TOKEN``: :mod:`canola.access`), which every client then sends first.
``--simulate EDS`` runs the gateway's master and the devices named by ``--sim-node`` on a
simulated bus (no hardware; for trying the protocol out).
Without a bus option the gateway runs on the default bus (:func:`canola.bus.open.default_bus`).
The same options work as ``python -m canola.gateway``. SIGINT and SIGTERM stop it at once,
whatever its clients are doing (their transfers are aborted).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import importlib
import signal
import sys
from collections.abc import Sequence

from canola import access
from canola.errors import Error
from canola.gateway.backend import Backend
from canola.gateway.events import EventHub
from canola.gateway.executor import Executor
from canola.gateway.server import (
    DEFAULT_LISTEN,
    IDLE_TIMEOUT,
    MAX_CLIENTS,
    MAX_LINE,
    MAX_QUEUED,
    MAX_QUEUED_TOTAL,
    GatewayServer,
)
from canola.gateway.server import parse_listen as _parse_listen

__all__ = ["add_arguments", "main", "run"]


def _listen(text: str) -> str:
    try:
        _parse_listen(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def _node(text: str) -> int:
    try:
        value = int(text, 0)
    except ValueError:
        value = 0
    if not 1 <= value <= 127:
        raise argparse.ArgumentTypeError(f"bad node-ID {text!r}: 1..127")
    return value


def _positive(text: str) -> int:
    try:
        value = int(text, 0)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"bad number {text!r}: 1 or more")
    return value


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not 0 <= value <= 86400:
        raise argparse.ArgumentTypeError(f"bad time {text!r}: 0..86400 seconds (0: never)")
    return value


def add_arguments(parser: argparse.ArgumentParser, *, bus_options: bool = True) -> None:
    """The gateway's options (``bus_options``: also ``--iface`` / ``--bus``)."""
    group = parser.add_mutually_exclusive_group(required=not bus_options)  # default bus
    if bus_options:
        group.add_argument("--iface", metavar="IFACE", help="SocketCAN interface, e.g. can0")
        group.add_argument("--bus", metavar="URL", help="socketcand://HOST:PORT/CHANNEL, "
                                                        "socketcan://IFACE or virtual://CHANNEL")
    group.add_argument("--simulate", metavar="EDS",
                       help="a simulated network: the gateway and --sim-node devices from EDS")
    parser.add_argument("--listen", type=_listen, default=DEFAULT_LISTEN, metavar="WHERE",
                        help=f"tcp:HOST:PORT, unix:PATH or stdio (default {DEFAULT_LISTEN})")
    parser.add_argument("--node-id", type=_node, default=None, metavar="N",
                        help="the gateway's own node-ID (default 127)")
    parser.add_argument("--sdo-timeout", type=_positive, default=1000, metavar="MS",
                        help="the master's SDO time-out per answer (default 1000 ms)")
    parser.add_argument("--eds", metavar="FILE",
                        help="the gateway's own object dictionary (default: built in)")
    parser.add_argument("--sim-node", type=_node, action="append", default=[], metavar="N",
                        help="with --simulate: a device with this node-ID (repeatable)")
    parser.add_argument("--max-clients", type=_positive, default=MAX_CLIENTS, metavar="N",
                        help=f"clients at once (default {MAX_CLIENTS})")
    parser.add_argument("--max-line", type=_positive, default=MAX_LINE, metavar="BYTES",
                        help=f"longest request line (default {MAX_LINE})")
    parser.add_argument("--max-queued", type=_positive, default=MAX_QUEUED, metavar="BYTES",
                        help="request lines and replies held per client (default "
                             f"{MAX_QUEUED}; a line beyond: ERROR:600)")
    parser.add_argument("--max-queued-total", type=_positive, default=MAX_QUEUED_TOTAL,
                        metavar="BYTES", help="the same over all clients (default "
                                              f"{MAX_QUEUED_TOTAL})")
    parser.add_argument("--token", metavar="TOKEN",
                        help="a secret every client sends first ([seq] auth TOKEN); default "
                             f"${access.TOKEN_ENV}; needed to listen beyond loopback")
    parser.add_argument("--idle-timeout", type=_seconds, default=IDLE_TIMEOUT, metavar="S",
                        help=f"drop a client silent for S seconds (default {IDLE_TIMEOUT:g}; "
                             "0: never; clients that asked for events stay)")


def _simulated(args: argparse.Namespace) -> tuple[Backend, asyncio.Task[None] | None]:
    from canola.core import SimBus  # noqa: PLC0415 -- the simulator only when asked for
    from canola.device import Device  # noqa: PLC0415
    from canola.formats import eds  # noqa: PLC0415
    from canola.gateway.masterbackend import MasterBackend  # noqa: PLC0415
    from canola.master import Master  # noqa: PLC0415

    model = eds.parse(args.simulate)  # read even without --sim-node: a bad file is reported
    bus = SimBus()
    own = args.node_id or 127
    master = Master(bus, node_id=own, eds_file=args.eds, sdo_timeout_ms=args.sdo_timeout)
    devices = [Device(model, n, bus) for n in args.sim_node if n != own]
    master.start()
    for device in devices:
        device.start()
    backend = MasterBackend(master)
    return backend, asyncio.get_running_loop().create_task(backend.run())


def _backend(args: argparse.Namespace) -> tuple[Backend, asyncio.Task[None] | None]:
    if args.simulate:
        return _simulated(args)
    try:  # canola.Master comes with its own branch; until then only --simulate works
        module = importlib.import_module("canola.gateway.masterbackend")
    except ImportError:
        raise Error("the gateway on a real bus needs canola.Master, which this build "
                    "lacks; try --simulate EDS") from None
    backend: Backend = module.open_master(args)
    return backend, None


async def _serve(args: argparse.Namespace) -> int:
    where = _parse_listen(args.listen)
    backend, pump = _backend(args)
    hub = EventHub(backend)
    server = GatewayServer(Executor(backend, hub), hub, max_clients=args.max_clients,
                           max_line=args.max_line,
                           idle_timeout=getattr(args, "idle_timeout", IDLE_TIMEOUT),
                           max_queued=getattr(args, "max_queued", MAX_QUEUED),
                           max_queued_total=getattr(args, "max_queued_total",
                                                    MAX_QUEUED_TOTAL),
                           token=getattr(args, "token_value", None))
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError, RuntimeError):
            loop.add_signal_handler(sig, stop.set)
    try:
        if where.kind == "stdio":
            served = asyncio.create_task(server.serve_stdio())
            stopped = asyncio.create_task(stop.wait())
            await asyncio.wait({served, stopped}, return_when=asyncio.FIRST_COMPLETED)
            stopped.cancel()
            if served.done():
                served.result()  # its error, if it ended with one
            return 0
        srv = await server.start(where)
        if where.kind == "tcp" and access.exposed_addresses(where.host):
            print(f"canola gateway: {where} is not loopback: clients must send the token; "
                  "the traffic is not encrypted (docs/security.md)", file=sys.stderr)
        print(f"canola gateway: listening on {GatewayServer.address(srv)}", file=sys.stderr,
              flush=True)
        await stop.wait()
        return 0
    finally:
        for sig in (signal.SIGINT, signal.SIGTERM):
            with contextlib.suppress(NotImplementedError, RuntimeError):
                loop.remove_signal_handler(sig)
        await server.close()
        hub.close()
        if pump is not None:
            pump.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await pump
        close = getattr(backend, "close", None)
        if close is not None:
            close()


def run(args: argparse.Namespace) -> int:
    """Run the gateway until SIGINT / SIGTERM (or the end of stdin with ``stdio``)."""
    queued = getattr(args, "max_queued", MAX_QUEUED)
    if not args.max_line <= queued <= getattr(args, "max_queued_total", MAX_QUEUED_TOTAL):
        print("canola gateway: --max-queued must hold a line (--max-line) and "
              "--max-queued-total must hold --max-queued", file=sys.stderr)
        return 2
    try:
        args.token_value = access.token_from(getattr(args, "token", None))
        where = _parse_listen(args.listen)
        refused = where.kind == "tcp" and access.unguarded(where.host, args.token_value,
                                                             "--listen")
    except ValueError as exc:
        print(f"canola gateway: {exc}", file=sys.stderr)
        return 2
    if refused:
        print(f"canola gateway: {refused}", file=sys.stderr)
        return 2
    try:
        return asyncio.run(_serve(args))
    except ValueError as exc:  # e.g. a host name that is not an address
        print(f"canola gateway: {exc}", file=sys.stderr)
        return 2
    except (Error, OSError) as exc:
        print(f"canola gateway: {' '.join(str(exc).split())}", file=sys.stderr)
        return 1


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m canola.gateway",
                                     description="CiA 309-3 ASCII gateway")
    add_arguments(parser)
    args = parser.parse_args(argv)
    return run(args)
