# SPDX-License-Identifier: Apache-2.0
"""A software CAN bus: a hub that speaks the socketcand protocol (``canola bus serve``).

Clients (python-can's ``socketcand`` interface, canola's C socketcand client, ``canola``
commands) connect over TCP, ``< open CHANNEL >`` a channel and switch to ``< rawmode >``.
Every channel is its own bus: a frame one client sends reaches every other client in raw
mode on the same channel (not the sender itself), time-stamped with the hub's clock.

Robustness rules:

- A client that breaks the protocol gets ``< error ... >`` and is disconnected; a known
  socketcand command the hub does not offer (BCM jobs, filters, ISO-TP) gets an error and
  the connection stays.
- Nothing waits on a slow client, and no client grows the hub: each client has one bounded
  queue of outgoing elements. Frames for it are dropped and counted
  (``ClientStats.dropped``, logged) once ``queue_limit`` elements wait, as a CAN
  controller loses frames it has no room for. The hub's replies to the client's own
  commands (``< ok >``, ``< echo >``, ``< error >``) are never dropped: up to
  ``reply_limit`` more may wait; a client whose queue grows past ``queue_limit +
  reply_limit`` (it sends commands and does not read the replies) is disconnected at
  once, its queue released, and counted (``ClientStats.overflowed``,
  :attr:`Hub.overflows`, logged). Each client's kernel send buffer and the transport's
  buffer are fixed (``write_buffer`` bytes each), so a client costs at most about
  ``(queue_limit + reply_limit) * MAX_ELEMENT + 2 * write_buffer`` bytes of memory.
- Input is read in bounded chunks and an element is at most
  :data:`canola.bus.socketcand.MAX_ELEMENT` characters; after each chunk the hub lets the
  other clients run, and after each command whose reply finds the queue beyond
  ``queue_limit`` it lets the replies go out first: a client that reads its replies is
  never disconnected, however many commands it sends at once.
- Clients that do not open a channel within ``handshake_timeout`` seconds are closed.
- With a ``token`` (:mod:`canola.access`), a client's first element must be
  ``< auth TOKEN >`` (answered ``< ok >``); anything else, or another token, gets
  ``< error ... >`` and the connection is closed. Without one, ``< auth ... >`` is
  answered ``< ok >`` whatever it holds.
- It listens on loopback unless told otherwise; ``canola bus serve`` refuses an address
  that is not loopback (:func:`exposed_addresses`) without a token, and an empty one.

:class:`Hub` runs on an asyncio loop; :class:`HubThread` runs one in a background thread
(tests, embedding); :func:`serve` is the command's blocking entry point.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import signal
import socket
import threading
import time
from collections import deque
from dataclasses import dataclass, field

from canola.access import exposed_addresses, same_token
from canola.bus.socketcand import (
    Frame,
    ProtocolError,
    format_error,
    format_frame,
    parse_command,
    split_elements,
)

__all__ = ["DEFAULT_PORT", "ClientStats", "Hub", "HubThread", "exposed_addresses", "serve"]

log = logging.getLogger("canola.hub")

#: socketcand's usual port.
DEFAULT_PORT = 29536

#: Delay between the ``< ok >`` of ``< rawmode >`` and the first frame: python-can's client
#: reads the ok with a single recv() and compares it whole, so a frame must not share its
#: segment. Only a mitigation: a client run later than this still fails (canola's own
#: client, :mod:`canola.bus.socketcand_bus`, reads a stream and needs no delay).
RAW_SETTLE_S = 0.05


#: Replies (``< ok >``, ``< echo >``, ``< error >``) that may wait for a client beyond its
#: frame queue before it is disconnected for not reading them.
DEFAULT_REPLY_LIMIT = 1024


@dataclass
class ClientStats:
    """Counters of one client: frames in and out, frames dropped for a full queue, the
    longest its queue grew (``peak``), and whether it was disconnected for letting its
    replies pile up (``overflowed``)."""

    peer: str
    channel: str = ""
    received: int = 0
    delivered: int = 0
    dropped: int = 0
    peak: int = 0
    overflowed: bool = False


class _OverflowError(Exception):
    """A client's queue outgrew every bound: it does not read its replies."""


@dataclass(eq=False)
class _Client:
    writer: asyncio.StreamWriter
    stats: ClientStats
    limit: int
    reply_limit: int
    raw: bool = False
    authed: bool = False
    queue: deque[str] = field(default_factory=deque)
    wake: asyncio.Event = field(default_factory=asyncio.Event)
    closing: bool = False

    def push(self, text: str, *, control: bool = False) -> bool:
        """Queue an element. Frames are dropped (False) once ``limit`` elements wait; a
        reply past ``limit + reply_limit`` raises :class:`_OverflowError`."""
        waiting = len(self.queue)
        if not control and waiting >= self.limit:
            self.stats.dropped += 1
            if self.stats.dropped == 1 or self.stats.dropped % 1000 == 0:
                log.warning("%s: queue full, %d frame(s) dropped so far", self.stats.peer,
                            self.stats.dropped)
            return False
        if waiting >= self.limit + self.reply_limit:
            raise _OverflowError
        self.queue.append(text)
        self.stats.peak = max(self.stats.peak, waiting + 1)
        self.wake.set()
        return True


class Hub:
    """The socketcand hub. ``port`` 0 picks a free port (see :attr:`port` once started)."""

    def __init__(self, host: str = "127.0.0.1", port: int = DEFAULT_PORT, *,
                 queue_limit: int = 1024, reply_limit: int = DEFAULT_REPLY_LIMIT,
                 handshake_timeout: float = 10.0, read_chunk: int = 4096,
                 write_buffer: int = 16384, token: str | None = None) -> None:
        if not host:
            raise ValueError("an empty host means every address: give one (127.0.0.1: "
                             "this machine only)")
        if queue_limit < 1 or reply_limit < 1:
            raise ValueError("queue_limit and reply_limit must be at least 1")
        self.host = host
        self.port = port
        self.token = token  # every client sends it first (None: nobody needs to)
        self.queue_limit = queue_limit
        self.reply_limit = reply_limit
        #: Clients disconnected for not reading their replies (see the module's rules).
        self.overflows = 0
        self.handshake_timeout = handshake_timeout
        self.read_chunk = read_chunk
        self.write_buffer = write_buffer
        self._channels: dict[str, set[_Client]] = {}
        self._clients: set[_Client] = set()
        self._tasks: set[asyncio.Task[None]] = set()
        self._server: asyncio.Server | None = None
        #: Stats of clients that have left (most recent last, bounded).
        self.departed: deque[ClientStats] = deque(maxlen=256)
        self.frames = 0

    # ---- lifecycle

    async def start(self) -> None:
        self._server = await asyncio.start_server(self._serve_client, self.host, self.port,
                                                  limit=self.read_chunk)
        sock = self._server.sockets[0]
        self.port = int(sock.getsockname()[1])
        log.info("socketcand hub on %s:%d", self.host, self.port)

    async def close(self) -> None:
        if self._server is not None:
            self._server.close()
        for client in list(self._clients):
            client.closing = True
            client.wake.set()
            client.writer.transport.abort()  # no waiting for unread data
        tasks = list(self._tasks)
        if tasks:  # closed connections end their tasks; cancel only what lingers
            _, lingering = await asyncio.wait(tasks, timeout=2.0)
            for task in lingering:
                task.cancel()
            await asyncio.gather(*lingering, return_exceptions=True)
        if self._server is not None:
            with contextlib.suppress(Exception):
                await asyncio.wait_for(self._server.wait_closed(), 2.0)

    def clients(self) -> list[ClientStats]:
        """Stats of the connected clients."""
        return [c.stats for c in self._clients]

    # ---- one connection

    async def _serve_client(self, reader: asyncio.StreamReader,
                            writer: asyncio.StreamWriter) -> None:
        with contextlib.suppress(asyncio.CancelledError):  # cancelled: the hub is closing
            await self._session(reader, writer)

    async def _session(self, reader: asyncio.StreamReader,
                       writer: asyncio.StreamWriter) -> None:
        peer = writer.get_extra_info("peername")
        name = f"{peer[0]}:{peer[1]}" if isinstance(peer, tuple) else str(peer)
        writer.transport.set_write_buffer_limits(high=self.write_buffer)
        sock = writer.get_extra_info("socket")
        if sock is not None:  # a fixed kernel buffer: no autotuning to megabytes per client
            with contextlib.suppress(OSError):
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, self.write_buffer)
        task = asyncio.current_task()
        if task is not None:
            self._tasks.add(task)
        client = _Client(writer, ClientStats(name), self.queue_limit, self.reply_limit)
        self._clients.add(client)
        sender = asyncio.create_task(self._send_loop(client))
        try:
            client.push("< hi >", control=True)
            await self._read_loop(client, reader)
        except (ConnectionError, OSError):
            pass
        except _OverflowError:
            self._overflowed(client)
        except ProtocolError as exc:
            log.info("%s: %s; disconnected", name, exc)
            with contextlib.suppress(_OverflowError):
                client.push(format_error(str(exc)), control=True)
        finally:
            self._leave(client)
            client.closing = True
            client.wake.set()
            with contextlib.suppress(Exception):
                await asyncio.wait_for(sender, 1.0)
            sender.cancel()
            writer.close()
            with contextlib.suppress(Exception):
                await asyncio.wait_for(writer.wait_closed(), 1.0)
            self._clients.discard(client)
            if task is not None:
                self._tasks.discard(task)
            self.departed.append(client.stats)
            s = client.stats
            log.info("%s left %s: %d in, %d out, %d dropped%s", name,
                     s.channel or "(no channel)", s.received, s.delivered, s.dropped,
                     ", overflowed" if s.overflowed else "")

    async def _read_loop(self, client: _Client, reader: asyncio.StreamReader) -> None:
        pending = b""
        deadline = time.monotonic() + self.handshake_timeout
        while True:
            timeout = (None if client.stats.channel
                       else max(deadline - time.monotonic(), 0.0))
            try:
                chunk = await asyncio.wait_for(reader.read(self.read_chunk), timeout)
            except TimeoutError as exc:
                raise ProtocolError("handshake not finished in time") from exc
            if not chunk:
                return
            elements, pending = split_elements(pending + chunk)
            for element in elements:
                self._handle(client, element)
                if len(client.queue) > client.limit:
                    # replies pile up: let the sender pass them on before the next command
                    # (it can unless the client stops reading; then the queue overflows)
                    await asyncio.sleep(0)
            await asyncio.sleep(0)  # the other clients run between chunks

    def _overflowed(self, client: _Client) -> None:
        """Disconnect a client whose queue outgrew every bound: no waiting for it to read,
        its queue released at once."""
        self.overflows += 1
        client.stats.overflowed = True
        log.warning("%s: %d elements wait and it does not read them (queue %d + replies "
                    "%d); disconnected", client.stats.peer, len(client.queue), client.limit,
                    client.reply_limit)
        client.queue.clear()
        client.writer.transport.abort()

    def _handle(self, client: _Client, element: str) -> None:
        cmd = parse_command(element)
        if cmd.verb == "auth":
            if self.token is not None and not same_token(cmd.token, self.token):
                log.warning("%s: wrong token", client.stats.peer)
                raise ProtocolError("wrong token")
            client.authed = True
            client.push("< ok >", control=True)
            return
        if self.token is not None and not client.authed:
            raise ProtocolError("authentication required: < auth TOKEN > first")
        if cmd.verb == "open":
            if client.stats.channel:
                raise ProtocolError("a channel is already open")
            client.stats.channel = cmd.channel
            client.push("< ok >", control=True)
            return
        if not client.stats.channel:
            raise ProtocolError(f"'{cmd.verb}' before '< open CHANNEL >'")
        if cmd.verb == "rawmode":
            if not client.raw:
                client.raw = True
                self._channels.setdefault(client.stats.channel, set()).add(client)
                log.info("%s joined %s", client.stats.peer, client.stats.channel)  # gets frames
            client.push("< ok >", control=True)
            client.push("", control=True)  # marker: settle before frames (RAW_SETTLE_S)
        elif cmd.verb == "bcmmode":
            self._leave(client)
            client.raw = False
            client.push("< ok >", control=True)
        elif cmd.verb == "echo":
            client.push("< echo >", control=True)
        elif cmd.frame is not None:
            client.stats.received += 1
            self._forward(client, cmd.frame)
        else:
            client.push(format_error(f"'{cmd.verb}' is not offered by this hub"), control=True)

    def _forward(self, source: _Client, frame: Frame) -> None:
        self.frames += 1
        text = format_frame(frame, time.time())
        for peer in self._channels.get(source.stats.channel, ()):
            if peer is not source and not peer.closing and peer.push(text):
                peer.stats.delivered += 1

    def _leave(self, client: _Client) -> None:
        members = self._channels.get(client.stats.channel)
        if members is not None:
            members.discard(client)
            if not members:
                del self._channels[client.stats.channel]

    async def _send_loop(self, client: _Client) -> None:
        writer = client.writer
        while True:
            if not client.queue:
                if client.closing:
                    return
                client.wake.clear()
                await client.wake.wait()
                continue
            batch: list[str] = []
            settle = False
            while client.queue and len(batch) < 64:
                text = client.queue.popleft()
                if text == "":
                    settle = True
                    break
                batch.append(text)
            if batch:
                writer.write("".join(batch).encode("ascii"))
                await writer.drain()
            if settle:
                await asyncio.sleep(RAW_SETTLE_S)


class HubThread:
    """A :class:`Hub` on its own event loop in a daemon thread (``with HubThread() as hub``)."""

    def __init__(self, host: str = "127.0.0.1", port: int = 0,
                 **options: int | float | str | None) -> None:
        self.hub = Hub(host, port, **options)  # type: ignore[arg-type]
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._run, name="canola-hub", daemon=True)
        self._ready = threading.Event()
        self._error: BaseException | None = None

    @property
    def port(self) -> int:
        return self.hub.port

    def _run(self) -> None:
        asyncio.set_event_loop(self._loop)
        try:
            self._loop.run_until_complete(self.hub.start())
        except BaseException as exc:
            self._error = exc
            self._ready.set()
            return
        self._ready.set()
        self._loop.run_forever()
        self._loop.run_until_complete(self.hub.close())
        self._loop.close()

    def start(self) -> HubThread:
        self._thread.start()
        self._ready.wait(10)
        if self._error is not None:
            raise self._error
        return self

    def stop(self) -> None:
        if self._thread.is_alive():
            self._loop.call_soon_threadsafe(self._loop.stop)
            self._thread.join(5)

    def __enter__(self) -> HubThread:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()


def serve(host: str, port: int, *, queue_limit: int = 1024,
          reply_limit: int = DEFAULT_REPLY_LIMIT, ready: threading.Event | None = None,
          token: str | None = None) -> None:
    """Run a hub until SIGINT or SIGTERM (``canola bus serve``)."""

    async def main() -> None:
        hub = Hub(host, port, queue_limit=queue_limit, reply_limit=reply_limit, token=token)
        await hub.start()
        print(f"canola bus: socketcand hub on {host}:{hub.port} (Ctrl-C stops)", flush=True)
        if ready is not None:
            ready.set()
        stop = asyncio.Event()
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            with contextlib.suppress(NotImplementedError, RuntimeError, ValueError):
                loop.add_signal_handler(sig, stop.set)
        await stop.wait()
        await hub.close()

    asyncio.run(main())
