# SPDX-License-Identifier: Apache-2.0
"""Shared pieces of the gateway tests: a fake master, a line client with time-outs, and a
gateway served on a real backend."""

from __future__ import annotations

import asyncio
import contextlib
import subprocess
import sys
from collections.abc import AsyncIterator, Awaitable, Callable, Iterator
from typing import TypeVar

from bounded import first_line

from canola.errors import SdoAbort
from canola.gateway import Executor, GatewayServer, parse_listen
from canola.gateway.backend import Event, Listener, LssOp
from canola.gateway.codes import GatewayError, GatewayFailure
from canola.gateway.events import EventHub
from canola.gateway.masterbackend import MasterBackend
from canola.gateway.requests import NmtCommand

T = TypeVar("T")
TIMEOUT = 60.0  # a bound a starved machine meets (load 20), not an expected answer time


def run(coro: Awaitable[T], timeout: float = 300.0) -> T:
    """Run a test coroutine with an overall time limit (never a hang)."""

    async def bounded() -> T:
        return await asyncio.wait_for(coro, timeout)

    return asyncio.run(bounded())


class FakeMaster:
    """Objects in a dict; nodes in ``gates`` answer only when their event is set."""

    def __init__(self, node_id: int = 1) -> None:
        self._node_id = node_id
        self.objects: dict[tuple[int, int, int], bytes] = {}
        self.gates: dict[int, asyncio.Event] = {}
        self.started: dict[int, asyncio.Event] = {}
        self.aborted: list[tuple[int, int, int]] = []
        self.nmt_sent: list[tuple[int, str]] = []
        self.local_nmt_done: list[str] = []
        self.calls: list[tuple[str, int, bool, int]] = []
        self._listeners: list[Listener] = []
        self.nmt_state = "OPERATIONAL"
        self.sdo_closings = 0

    @property
    def node_id(self) -> int:
        return self._node_id

    @property
    def has_lss(self) -> bool:
        return False

    async def _gate(self, node: int, index: int, sub: int) -> None:
        if node in self.gates:
            self.started.setdefault(node, asyncio.Event()).set()
            try:
                await self.gates[node].wait()
            except asyncio.CancelledError:
                self.aborted.append((node, index, sub))  # "abort frame sent"
                raise

    async def sdo_upload(self, node: int, index: int, sub: int, *, block: bool,
                         timeout_ms: int) -> bytes:
        self.calls.append(("up", node, block, timeout_ms))
        await self._gate(node, index, sub)
        if node == 99:
            raise TimeoutError
        if (node, index, sub) not in self.objects:
            raise SdoAbort(0x06020000)
        return self.objects[node, index, sub]

    async def sdo_download(self, node: int, index: int, sub: int, data: bytes, *,
                           block: bool, timeout_ms: int) -> None:
        self.calls.append(("down", node, block, timeout_ms))
        await self._gate(node, index, sub)
        self.objects[node, index, sub] = data

    def local_read(self, index: int, sub: int) -> bytes:
        try:
            return self.objects[self._node_id, index, sub]
        except KeyError:
            raise SdoAbort(0x06020000) from None

    def local_write(self, index: int, sub: int, data: bytes) -> None:
        if (self._node_id, index, sub) not in self.objects:
            raise SdoAbort(0x06020000)
        self.objects[self._node_id, index, sub] = data

    async def nmt(self, node: int, command: NmtCommand) -> None:
        self.nmt_sent.append((node, command))

    async def local_nmt(self, command: NmtCommand) -> None:
        self.local_nmt_done.append(command)

    def subscribe(self, listener: Listener) -> Callable[[], None]:
        self._listeners.append(listener)
        return lambda: self._listeners.remove(listener)

    async def lss(self, op: LssOp, args: tuple[int, ...] = ()) -> tuple[int, ...]:
        raise GatewayFailure(GatewayError.REQUEST_NOT_SUPPORTED, f"LSS {op} {args}")

    def emit(self, event: Event) -> None:
        for listener in list(self._listeners):
            listener(event)


class Client:
    """A line client of the gateway; every read has a time-out."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.reader = reader
        self.writer = writer

    @classmethod
    async def connect(cls, address: str) -> Client:
        kind, _, rest = address.partition(":")
        if kind == "unix":
            reader, writer = await asyncio.open_unix_connection(rest, limit=8 * 1024 * 1024)
        else:
            host, _, port = rest.rpartition(":")
            reader, writer = await asyncio.open_connection(host, int(port),
                                                           limit=8 * 1024 * 1024)
        return cls(reader, writer)

    async def send(self, line: str) -> None:
        self.writer.write(line.encode() + b"\r\n")
        await self.writer.drain()

    async def line(self, timeout: float = TIMEOUT) -> str:
        """The next reply or event: up to CR LF (a reply of several lines has LF inside)."""
        data = await asyncio.wait_for(self.reader.readuntil(b"\r\n"), timeout)
        return data[:-2].decode()

    async def ask(self, line: str, timeout: float = TIMEOUT) -> str:
        await self.send(line)
        return await self.line(timeout)

    async def reply(self, line: str, timeout: float = TIMEOUT) -> tuple[str, list[str]]:
        """Send ``line``; its reply and the event lines that came before it."""
        await self.send(line)
        seq = line.split("]", 1)[0] + "]"
        events: list[str] = []
        while seq not in (got := await self.line(timeout)).rsplit("\n", 1)[-1]:
            events.append(got)
        return got, events

    async def close(self) -> None:
        self.writer.close()
        with contextlib.suppress(ConnectionError, TimeoutError):
            await asyncio.wait_for(self.writer.wait_closed(), TIMEOUT)


async def eventually(check: Callable[[], bool], timeout: float = TIMEOUT) -> None:
    """Wait until ``check()`` holds (polling), or fail after ``timeout`` seconds."""
    async with asyncio.timeout(timeout):
        while not check():
            await asyncio.sleep(0.005)


@contextlib.asynccontextmanager
async def serving(backend: MasterBackend) -> AsyncIterator[str]:
    """The gateway on ``backend``, listening on a free TCP port of 127.0.0.1, with the
    backend's event pump running: its address; pump, server and event hub closed after."""
    hub = EventHub(backend)
    server = GatewayServer(Executor(backend, hub), hub)
    srv = await server.start(parse_listen("tcp:127.0.0.1:0"))
    pump = asyncio.create_task(backend.run())
    try:
        yield GatewayServer.address(srv)
    finally:
        pump.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await pump
        await server.close()
        hub.close()


@contextlib.asynccontextmanager
async def client_of(backend: MasterBackend) -> AsyncIterator[Client]:
    """A client of the gateway on ``backend`` over TCP, with no event pump: on a SimBus
    the test alone moves virtual time. Client, server and event hub closed after."""
    hub = EventHub(backend)
    server = GatewayServer(Executor(backend, hub), hub)
    srv = await server.start(parse_listen("tcp:127.0.0.1:0"))
    client = await Client.connect(GatewayServer.address(srv))
    try:
        yield client
    finally:
        await client.close()
        await server.close()
        hub.close()


async def start_gateway(master: FakeMaster, **limits: float) -> tuple[GatewayServer, str]:
    """The gateway (and its event hub) on ``master``, listening on a free TCP port of
    127.0.0.1 (``limits``: GatewayServer's max_clients, max_line, idle_timeout)."""
    hub = EventHub(master)
    server = GatewayServer(Executor(master, hub), hub, **limits)  # type: ignore[arg-type]
    srv = await server.start(parse_listen("tcp:127.0.0.1:0"))
    return server, GatewayServer.address(srv)


@contextlib.contextmanager
def gateway_process(*options: str) -> Iterator[tuple[subprocess.Popen[str], str]]:
    """``python -m canola.gateway OPTIONS --listen tcp:127.0.0.1:0``: the process and its
    address (killed after, if still running)."""
    proc = subprocess.Popen([sys.executable, "-m", "canola.gateway", *options, "--listen",
                             "tcp:127.0.0.1:0"], stderr=subprocess.PIPE, text=True)
    try:
        line = first_line(proc.stderr, "the gateway process")
        assert line.startswith("canola gateway: listening on tcp:127.0.0.1:"), line
        yield proc, line.split()[-1]
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=300)
        if proc.stderr is not None:
            proc.stderr.close()
