# SPDX-License-Identifier: Apache-2.0
"""The gateway's transport: clients over TCP, a Unix socket or stdio, one
:class:`~canola.gateway.connection.Connection` (session, reader, worker, writer) each.
Clients never wait for each other (except for SDO transfers to one and the same node).

A socket client that goes away (end of stream or reset) is dropped at once: the request
it was waiting for is cancelled, which aborts an SDO transfer in progress on the bus. On
stdio, the end of input lets pending requests finish first (``canola gateway --listen
stdio < script`` answers every line).

Bounds (docs/security.md): at most ``max_clients`` socket clients at once; one more takes
the slot of a silent, stuck or quiet client (:mod:`canola.gateway.slots`: that one is
dropped and the log says so), or, when every client has a request running or traffic
within ``quiet_s``, is answered ``[0] ERROR:102`` and closed. A socket client idle for
``idle_timeout`` seconds is dropped (logged), unless it asked for events (it then stays
until its slot is needed). Request lines and replies held: at most ``max_queued`` bytes
per client and ``max_queued_total`` over all (:mod:`canola.gateway.budget`; a line beyond
is answered ``ERROR:600``). With a ``token``, every socket client proves it first
(:mod:`canola.gateway.connection`). :meth:`GatewayServer.close` drops every client at once,
whatever it is doing.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import socket
import stat
import sys

from canola.gateway.budget import MAX_QUEUED, MAX_QUEUED_TOTAL, Budget, Share
from canola.gateway.codes import GatewayError
from canola.gateway.connection import Connection, LineSplitter, Read, Write, off_loop
from canola.gateway.events import EventHub
from canola.gateway.executor import Executor, error_reply
from canola.gateway.listen import DEFAULT_LISTEN, Listen, parse_listen
from canola.gateway.slots import QUIET_S, victim

__all__ = ["DEFAULT_LISTEN", "IDLE_TIMEOUT", "MAX_CLIENTS", "MAX_LINE", "MAX_QUEUED",
           "MAX_QUEUED_TOTAL", "QUIET_S", "GatewayServer", "LineSplitter", "Listen",
           "parse_listen"]

MAX_LINE = 4 * 1024 * 1024  # a 1 MiB domain in base64 fits three times over
MAX_CLIENTS = 16
IDLE_TIMEOUT = 60.0  # seconds

log = logging.getLogger("canola.gateway")


class GatewayServer:
    """Serves an :class:`Executor` (and its :class:`EventHub`) to clients."""

    def __init__(self, executor: Executor, hub: EventHub | None = None, *,
                 max_clients: int = MAX_CLIENTS, max_line: int = MAX_LINE,
                 idle_timeout: float = IDLE_TIMEOUT, quiet_s: float = QUIET_S,
                 max_queued: int = MAX_QUEUED, max_queued_total: int = MAX_QUEUED_TOTAL,
                 token: str | None = None) -> None:
        if max_queued < max_line or max_queued_total < max_queued:
            raise ValueError(f"queued bytes: {max_queued} per client and {max_queued_total} "
                             f"in total must hold a {max_line}-byte line")
        self.executor = executor
        self.hub = hub
        self.max_clients = max_clients
        self.max_line = max_line
        self.max_queued = max_queued  # bytes held per client (requests, replies)
        self.token = token  # what every socket client sends first (None: nothing)
        self.budget = Budget(max_queued_total)  # the same over all clients
        self.idle_timeout = idle_timeout  # 0: never
        self.quiet_s = quiet_s  # traffic this recent keeps a client's slot
        self._servers: list[asyncio.Server] = []
        self._connections: set[Connection] = set()
        self._sockets: set[Connection] = set()
        self._tasks: set[asyncio.Task[None]] = set()
        self._watch: asyncio.Task[None] | None = None
        self._count = 0

    @property
    def clients(self) -> int:
        """Clients served now."""
        return len(self._connections)

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
        if self.idle_timeout > 0 and self._watch is None:
            self._watch = asyncio.create_task(self._watch_idle())
        return server

    @staticmethod
    def address(server: asyncio.Server) -> str:
        sock = server.sockets[0]
        if sock.family == socket.AF_UNIX:
            return f"unix:{sock.getsockname()}"
        host, port = sock.getsockname()[:2]
        return str(Listen("tcp", host=host, port=port))

    async def serve_stdio(self) -> None:
        """Serve one client on stdin/stdout until the end of its input (reads and writes
        in daemon threads: a blocked terminal never holds up the end of the process)."""
        fd_in, fd_out = sys.stdin.fileno(), sys.stdout.fileno()

        async def read() -> bytes:
            try:
                return await off_loop(os.read, fd_in, 65536)
            except OSError:
                return b""

        async def write(data: bytes) -> None:
            view = memoryview(data)
            while view:
                n = await off_loop(os.write, fd_out, view)
                view = view[n:]

        await self.serve_stream(read, write, eof_cancels=False, name="stdio")

    async def serve_stream(self, read: Read, write: Write, *, eof_cancels: bool,
                           name: str = "stream") -> None:
        """Serve one client reading with ``read`` (b"" at the end) and writing with
        ``write`` (no idle time-out, no token: the process's own stdin, say).
        ``eof_cancels``: the end of input drops pending requests (sockets)."""
        await self._serve(self._connection(name, None), read, write, eof_cancels=eof_cancels)

    async def close(self) -> None:
        """Stop listening and drop every client at once (their transfers are aborted)."""
        for server in self._servers:
            server.close()
        if self._watch is not None:
            self._watch.cancel()
        for conn in list(self._connections):
            conn.drop("the gateway stops", logging.INFO)
        for task in list(self._tasks):
            task.cancel()
        for task in [*self._tasks, *([self._watch] if self._watch else [])]:
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
        for server in self._servers:
            with contextlib.suppress(Exception):
                await server.wait_closed()
        self._servers.clear()
        self._watch = None

    # ---- clients

    def _connection(self, name: str, token: str | None) -> Connection:
        return Connection(name, self.executor, self.hub, self.max_line,
                          Share(self.budget, self.max_queued), token=token)

    async def _serve(self, conn: Connection, read: Read, write: Write, *,
                     eof_cancels: bool) -> None:
        conn.task = asyncio.current_task()
        self._connections.add(conn)
        try:
            await conn.serve(read, write, eof_cancels=eof_cancels)
        finally:
            self._connections.discard(conn)
            self._sockets.discard(conn)

    def _peer(self, writer: asyncio.StreamWriter) -> str:
        self._count += 1
        peer = writer.get_extra_info("peername")
        if isinstance(peer, tuple) and len(peer) >= 2:
            host = f"[{peer[0]}]" if ":" in str(peer[0]) else peer[0]
            return f"client {self._count} ({host}:{peer[1]})"
        return f"client {self._count} (unix socket)"

    async def _socket_client(self, reader: asyncio.StreamReader,
                             writer: asyncio.StreamWriter) -> None:
        task = asyncio.current_task()
        assert task is not None
        self._tasks.add(task)
        name = self._peer(writer)
        conn: Connection | None = None
        try:
            live = [conn for conn in self._sockets if conn.dropped is None]
            if len(live) >= self.max_clients:
                chosen = victim(live, asyncio.get_running_loop().time(), self.quiet_s)
                if chosen is None:
                    log.warning("%s refused: all %d clients have a request running or "
                                "traffic within %g s", name, self.max_clients, self.quiet_s)
                    writer.write(f"{error_reply(0, GatewayError.INTERNAL_STATE)}\r\n".encode())
                    with contextlib.suppress(ConnectionError):
                        await writer.drain()
                    return
                loser, why = chosen
                loser.drop(f"{why}, its slot goes to {name}")

            async def read() -> bytes:
                try:
                    return await reader.read(65536)
                except ConnectionError:
                    return b""

            async def write(data: bytes) -> None:
                writer.write(data)
                await writer.drain()

            conn = self._connection(name, self.token)
            self._sockets.add(conn)
            await self._serve(conn, read, write, eof_cancels=True)
        except asyncio.CancelledError:
            pass  # dropped: the task ends here, not with an error
        finally:
            self._tasks.discard(task)
            if conn is not None and conn.dropped is not None:
                writer.transport.abort()  # what it did not read is not worth waiting for
            writer.close()
            with contextlib.suppress(Exception):
                await asyncio.wait_for(writer.wait_closed(), 1.0)

    async def _watch_idle(self) -> None:
        """Drop socket clients idle for ``idle_timeout`` (not those that wait for events)."""
        period = min(1.0, self.idle_timeout / 4)
        while True:
            await asyncio.sleep(period)
            now = asyncio.get_running_loop().time()
            for conn in list(self._sockets):
                idle = conn.idle_for(now)
                if idle is not None and idle >= self.idle_timeout and not conn.listening:
                    conn.drop(f"idle for {idle:.1f} s (time-out {self.idle_timeout:g} s)")
