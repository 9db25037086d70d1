"""The gateway's transport: clients over TCP, a Unix socket or stdio, one session each.

Each client gets its own :class:`~canola.gateway.executor.Session` and three small
tasks: the reader splits its bytes into lines (at most ``max_line`` bytes each; a longer
line is answered ``ERROR:600`` and skipped, the connection stays usable), the worker runs
its requests one after the other, in order, and the writer sends replies and events.
Clients never wait for each other (except for SDO transfers to one and the same node).

A socket client that goes away (end of stream or reset) is dropped at once: the request
it was waiting for is cancelled, which aborts an SDO transfer in progress on the bus. On
stdio, the end of input lets pending requests finish first (``canola gateway --listen
stdio < script`` answers every line).

At most ``max_clients`` clients at once; one more is answered ``ERROR:102`` and closed.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import socket
import stat
import sys
from collections.abc import Awaitable, Callable
from dataclasses import dataclass

from canola.gateway.codes import GatewayError
from canola.gateway.events import EventHub
from canola.gateway.executor import Executor, error_reply
from canola.gateway.parser import ParseError, parse_line, read_seq
from canola.gateway.requests import Request

__all__ = ["DEFAULT_LISTEN", "GatewayServer", "LineSplitter", "Listen", "parse_listen"]

DEFAULT_LISTEN = "tcp:127.0.0.1:6000"
MAX_LINE = 4 * 1024 * 1024  # a 1 MiB domain in base64 fits three times over
MAX_CLIENTS = 16
_QUEUED_LINES = 1024  # per client: replies and events not yet sent


@dataclass(frozen=True)
class Listen:
    """Where to listen: ``kind`` is "tcp" (host, port), "unix" (path) or "stdio"."""

    kind: str
    host: str = ""
    port: int = 0
    path: str = ""

    def __str__(self) -> str:
        if self.kind == "tcp":
            host = f"[{self.host}]" if ":" in self.host else self.host
            return f"tcp:{host}:{self.port}"
        return f"unix:{self.path}" if self.kind == "unix" else "stdio"


def parse_listen(text: str) -> Listen:
    """``tcp:HOST:PORT``, ``tcp:PORT`` (loopback), ``unix:PATH`` or ``stdio``."""
    if text == "stdio":
        return Listen("stdio")
    kind, _, rest = text.partition(":")
    if kind == "unix" and rest:
        return Listen("unix", path=rest)
    if kind == "tcp" and rest:
        host, _, port = rest.rpartition(":")
        host = host.strip("[]") or "127.0.0.1"
        if port.isdigit() and 0 <= int(port) <= 65535:
            return Listen("tcp", host=host, port=int(port))
    raise ValueError(f"cannot listen on {text!r} (tcp:HOST:PORT, unix:PATH or stdio)")


class LineSplitter:
    """Bytes in, lines out; a line longer than ``limit`` comes out as ``None`` items'
    sequence number (see :meth:`feed`)."""

    def __init__(self, limit: int) -> None:
        self.limit = limit
        self._buf = bytearray()
        self._skipping = False

    def feed(self, data: bytes) -> list[bytes | tuple[int | None]]:
        """Complete lines (without the line feed); ``(seq,)`` for each line that was too
        long (``seq`` read from its start, if any)."""
        out: list[bytes | tuple[int | None]] = []
        start = 0
        while start < len(data):
            nl = data.find(b"\n", start)
            end = len(data) if nl < 0 else nl
            if self._skipping:
                if nl >= 0:
                    self._skipping = False
            elif len(self._buf) + end - start > self.limit:
                head = bytes(self._buf[:32] or data[start:start + 32])
                out.append((read_seq(head.decode("latin-1")),))
                self._buf.clear()
                self._skipping = nl < 0
            else:
                self._buf += data[start:end]
                if nl >= 0:
                    out.append(bytes(self._buf))
                    self._buf.clear()
            start = end + 1 if nl >= 0 else len(data)
        return out

    def tail(self) -> bytes | None:
        """What is left at the end of the stream (a last line without line feed)."""
        if self._skipping or not self._buf:
            return None
        data = bytes(self._buf)
        self._buf.clear()
        return data


Read = Callable[[], Awaitable[bytes]]
Write = Callable[[bytes], Awaitable[None]]


class GatewayServer:
    """Serves an :class:`Executor` (and its :class:`EventHub`) to clients."""

    def __init__(self, executor: Executor, hub: EventHub | None = None, *,
                 max_clients: int = MAX_CLIENTS, max_line: int = MAX_LINE) -> None:
        self.executor = executor
        self.hub = hub
        self.max_clients = max_clients
        self.max_line = max_line
        self.clients = 0
        self._servers: list[asyncio.Server] = []
        self._tasks: set[asyncio.Task[None]] = set()

    # ---- listening

    async def start(self, where: Listen) -> asyncio.Server:
        """Listen for socket clients (tcp or unix); returns the asyncio server."""
        if where.kind == "tcp":
            server = await asyncio.start_server(self._socket_client, where.host, where.port,
                                                reuse_address=True)
        elif where.kind == "unix":
            with contextlib.suppress(FileNotFoundError):
                if stat.S_ISSOCK(os.stat(where.path).st_mode):
                    os.unlink(where.path)  # a stale socket of an earlier run
            server = await asyncio.start_unix_server(self._socket_client, where.path)
        else:
            raise ValueError("stdio is served with serve_stdio()")
        self._servers.append(server)
        return server

    @staticmethod
    def address(server: asyncio.Server) -> str:
        sock = server.sockets[0]
        if sock.family == socket.AF_UNIX:
            return f"unix:{sock.getsockname()}"
        host, port = sock.getsockname()[:2]
        return str(Listen("tcp", host=host, port=port))

    async def serve_stdio(self) -> None:
        """Serve one client on stdin/stdout until the end of its input."""
        loop = asyncio.get_running_loop()
        fd_in, fd_out = sys.stdin.fileno(), sys.stdout.fileno()

        async def read() -> bytes:
            return await loop.run_in_executor(None, os.read, fd_in, 65536)

        async def write(data: bytes) -> None:
            view = memoryview(data)
            while view:
                n = await loop.run_in_executor(None, os.write, fd_out, view)
                view = view[n:]

        await self.serve_stream(read, write, eof_cancels=False)

    async def close(self) -> None:
        """Stop listening and drop every client (their transfers are aborted)."""
        for server in self._servers:
            server.close()
        for task in list(self._tasks):
            task.cancel()
        for task in list(self._tasks):
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
        for server in self._servers:
            with contextlib.suppress(Exception):
                await server.wait_closed()
        self._servers.clear()

    async def _socket_client(self, reader: asyncio.StreamReader,
                             writer: asyncio.StreamWriter) -> None:
        task = asyncio.current_task()
        assert task is not None
        self._tasks.add(task)
        try:
            if self.clients >= self.max_clients:
                writer.write(f"{error_reply(None, GatewayError.INTERNAL_STATE)}\r\n".encode())
                with contextlib.suppress(ConnectionError):
                    await writer.drain()
                return

            async def read() -> bytes:
                try:
                    return await reader.read(65536)
                except ConnectionError:
                    return b""

            async def write(data: bytes) -> None:
                writer.write(data)
                await writer.drain()

            await self.serve_stream(read, write, eof_cancels=True)
        except asyncio.CancelledError:
            pass  # close() drops the client; the task ends here, not with an error
        finally:
            self._tasks.discard(task)
            writer.close()
            with contextlib.suppress(Exception):
                await writer.wait_closed()

    # ---- one client

    async def serve_stream(self, read: Read, write: Write, *, eof_cancels: bool) -> None:
        """Serve one client reading with ``read`` (b"" at the end) and writing with
        ``write``. ``eof_cancels``: the end of input drops pending requests (sockets)."""
        self.clients += 1
        session = self.executor.new_session()
        # replies and events on their way out; a client that does not read fills it, then
        # its own requests wait (and its events are dropped), nobody else's
        out: asyncio.Queue[str | None] = asyncio.Queue(maxsize=_QUEUED_LINES)
        requests: asyncio.Queue[Request | list[str] | None] = asyncio.Queue(maxsize=64)

        def deliver(line: str) -> None:
            if not out.full():
                out.put_nowait(line)

        token = None
        if self.hub is not None:
            hub = self.hub
            token = hub.add_sink(deliver)
            session.on_events_changed = lambda kinds: hub.set_kinds(token, kinds)

        async def writer() -> None:
            while (line := await out.get()) is not None:
                try:
                    await write(line.encode("utf-8") + b"\r\n")
                except (ConnectionError, OSError):
                    return

        async def worker() -> None:
            while (item := await requests.get()) is not None:
                lines = item if isinstance(item, list) else await self.executor.execute(
                    session, item)
                for line in lines:
                    await out.put(line)

        write_task = asyncio.create_task(writer())
        work_task = asyncio.create_task(worker())
        splitter = LineSplitter(self.max_line)
        try:
            while True:
                chunk = await read()
                items = splitter.feed(chunk) if chunk else []
                if not chunk and (last := splitter.tail()) is not None:
                    items.append(last)
                for item in items:
                    if isinstance(item, tuple):
                        await requests.put([error_reply(item[0], GatewayError.OUT_OF_MEMORY)])
                        continue
                    parsed = self._parse(item)
                    if parsed is not None:
                        await requests.put(parsed)
                if not chunk:
                    break
            if eof_cancels:
                work_task.cancel()
            else:
                await requests.put(None)
            with contextlib.suppress(asyncio.CancelledError):
                await work_task
        finally:
            work_task.cancel()  # the client is gone: abort what it was doing
            with contextlib.suppress(asyncio.CancelledError):
                await work_task
            if token is not None and self.hub is not None:
                self.hub.remove_sink(token)
            try:
                out.put_nowait(None)
            except asyncio.QueueFull:
                write_task.cancel()
            try:  # the last replies, unless the client does not read them
                await asyncio.wait_for(write_task, 5.0)
            except (TimeoutError, asyncio.CancelledError):
                write_task.cancel()
            self.clients -= 1

    @staticmethod
    def _parse(raw: bytes) -> Request | list[str] | None:
        text = raw.decode("utf-8", "replace")
        try:
            return parse_line(text)
        except ParseError as exc:
            return [error_reply(exc.seq, exc.code)]
