# SPDX-License-Identifier: Apache-2.0
"""One client of the gateway: its session, and the three small tasks that serve it.

The reader splits the client's bytes into lines (at most ``max_line`` bytes each; a longer
line is answered ``ERROR:600`` and skipped, the connection stays usable) and parses them
in order: every parse takes time linear in the line's length, and a line longer than
:data:`INLINE_PARSE` characters is parsed in a thread of its own, so that no line holds up
the event loop and the other clients. The worker runs the requests one after the other;
the writer sends replies and events.

Every line gets exactly one reply, ended by one CR LF (a reply of several lines has LF
between them, as CANopenNode's gateway does): an empty or comment-only line gets an empty
reply, and a line without a readable ``[seq]`` is answered with the sequence number of
this client's last line that had one (0 before any), as CANopenNode's gateway does too.

With a token (:mod:`canola.access`), a client's first line must be ``[seq] auth <token>``
(answered ``[seq] OK``) and come within :data:`AUTH_S` seconds; any other line, a wrong
token or silence gets ``ERROR:102`` (``#`` and why) and the connection is closed. Until
then its lines count as no traffic. Without a token, ``auth`` lines are answered OK.

For the idle time-out: a client is active when a complete line comes in or a reply has
been written to it, and while one of its requests is running (a long transfer); the bytes
of a line that does not end do not count. The same times, and whether a reply waits to be
written, decide whose slot goes to a newcomer (:mod:`canola.gateway.slots`).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import threading
from collections.abc import Awaitable, Callable
from typing import TypeVar

from canola.access import same_token
from canola.gateway.budget import Budget, Share
from canola.gateway.codes import GatewayError
from canola.gateway.events import EventHub
from canola.gateway.executor import Executor, error_reply
from canola.gateway.parser import ParseError, parse_line, read_seq
from canola.gateway.requests import Auth, Request

__all__ = ["AUTH_S", "INLINE_PARSE", "Connection", "LineSplitter", "Read", "Write",
           "off_loop"]

#: Lines up to this many bytes are parsed on the event loop (microseconds); longer ones in
#: a thread.
INLINE_PARSE = 4096
_QUEUED_LINES = 1024  # per client: replies and events not yet sent
_QUEUED_REQUESTS = 64  # per client: lines read, not yet run (and their bytes: the share)
_FLUSH_S = 5.0  # the last replies to a client that left, unless it does not read them
#: Seconds a client has to prove its token (where one is asked for).
AUTH_S = 10.0
_AUTH_LINE = 256  # the longest line read before the token is proved
_NO_ROOM = "too many bytes queued: wait for the replies"

log = logging.getLogger("canola.gateway")
T = TypeVar("T")
Read = Callable[[], Awaitable[bytes]]
Write = Callable[[bytes], Awaitable[None]]


def off_loop(fn: Callable[..., T], *args: object) -> asyncio.Future[T]:
    """``fn(*args)`` in a daemon thread of its own: awaitable, and never in the way of the
    process's exit (unlike the default executor, which the end of asyncio.run waits for)."""
    loop = asyncio.get_running_loop()
    future: asyncio.Future[T] = loop.create_future()

    def settle(result: T | None, error: BaseException | None) -> None:
        if future.done():  # cancelled meanwhile
            return
        if error is not None:
            future.set_exception(error)
        else:
            future.set_result(result)  # type: ignore[arg-type]

    def run() -> None:
        try:
            result, error = fn(*args), None
        except BaseException as exc:  # handed to the awaiting task
            result, error = None, exc
        with contextlib.suppress(RuntimeError):  # the loop is closed: nobody waits
            loop.call_soon_threadsafe(settle, result, error)

    threading.Thread(target=run, name=f"gateway-{getattr(fn, '__name__', 'call')}",
                     daemon=True).start()
    return future


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

    @property
    def pending(self) -> int:
        """Bytes of a line collected so far (not yet complete)."""
        return len(self._buf)

    def tail(self) -> bytes | None:
        """What is left at the end of the stream (a last line without line feed)."""
        if self._skipping or not self._buf:
            return None
        data = bytes(self._buf)
        self._buf.clear()
        return data


def _parse(raw: bytes) -> Request | ParseError | None:
    try:
        return parse_line(raw.decode("utf-8", "replace"))
    except ParseError as exc:
        return exc


#: Long lines parsed at once, over all clients: a parse holds a few copies of its line
#: (its text, the value's bytes) for a moment; these copies stay within this many lines.
_LONG_PARSES = threading.BoundedSemaphore(2)


def _parse_long(raw: bytes) -> Request | ParseError | None:
    """:func:`_parse` in turn with the other long lines (in the parse's own thread)."""
    with _LONG_PARSES:
        return _parse(raw)


class Connection:
    """One client: ``name`` (for the log), its session, its activity, ``share``: the
    bytes it may have held at once (:mod:`canola.gateway.budget`), and ``token``: what it
    must send first (None: nothing)."""

    def __init__(self, name: str, executor: Executor, hub: EventHub | None,
                 max_line: int, share: Share | None = None, *,
                 token: str | None = None) -> None:
        self.name = name
        self.token = token
        self.authed = token is None
        self.executor = executor
        self.hub = hub
        self.max_line = max_line
        self.share = share if share is not None else Share(Budget())
        self.session = executor.new_session()
        self.last_seq = 0
        self.connected_at = self.last_active = self._now()
        self.last_line_at: float | None = None  # its last complete line
        self.last_reply_at: float | None = None  # the last reply or event written to it
        self.unwritten_since: float | None = None  # a reply or event waits since then
        self.running = False  # a request of this client is being executed
        self.dropped: str | None = None
        self.task: asyncio.Task[None] | None = None
        # replies and events on their way out (with the bytes each holds of the share); a
        # client that does not read fills it, then its own requests wait (and its events
        # are dropped), nobody else's
        self._out: asyncio.Queue[tuple[str, int] | None] = asyncio.Queue(maxsize=_QUEUED_LINES)
        self._requests: asyncio.Queue[tuple[Request, int] | str | None] = asyncio.Queue(
            maxsize=_QUEUED_REQUESTS)

    @property
    def listening(self) -> bool:
        """Whether the client asked for events (it may stay silent, waiting for them)."""
        return bool(self.session.events)

    def idle_for(self, now: float) -> float | None:
        """Seconds since the client was last active; None while a request runs."""
        return None if self.running else now - self.last_active

    def drop(self, reason: str, level: int = logging.WARNING) -> None:
        """Close the connection now (its request, if any, is cancelled); logs why."""
        if self.dropped is not None:
            return
        self.dropped = reason
        log.log(level, "%s dropped: %s", self.name, reason)
        if self.task is not None:
            self.task.cancel()

    @staticmethod
    def _now() -> float:
        return asyncio.get_running_loop().time()

    def _touch(self) -> None:
        self.last_active = self._now()

    def _seq_of(self, head: bytes) -> int:
        seq = read_seq(head[:32].decode("latin-1"))
        if seq is not None:
            self.last_seq = seq
        return self.last_seq

    async def _request(self, item: bytes | tuple[int | None], *,
                       short: bool) -> tuple[Request, int] | str:
        """A line's request and the bytes it holds, or the reply it gets without running
        (errors, empty lines, no room). ``short``: the lines were collected up to the room
        left in the share, shorter than ``max_line``."""
        if isinstance(item, tuple):
            if item[0] is not None:
                self.last_seq = item[0]
            return error_reply(self.last_seq, GatewayError.OUT_OF_MEMORY,
                               note=_NO_ROOM if short else "")
        if not self.share.accept(len(item)):
            return error_reply(self._seq_of(item), GatewayError.OUT_OF_MEMORY, note=_NO_ROOM)
        parsed = (_parse(item) if len(item) <= INLINE_PARSE
                  else await off_loop(_parse_long, item))
        if not isinstance(parsed, Request):
            self.share.ran(len(item))
        if parsed is None:
            return ""
        if isinstance(parsed, ParseError):
            if parsed.seq is not None:
                self.last_seq = parsed.seq
            return error_reply(self.last_seq, parsed.code)
        self.last_seq = parsed.seq
        if isinstance(parsed, Auth):
            self.share.ran(len(item))
            if self.token is None or same_token(parsed.token, self.token):
                return f"[{parsed.seq}] OK"
            return error_reply(parsed.seq, GatewayError.INTERNAL_STATE, note="wrong token")
        return parsed, len(item)

    def _prove(self, item: bytes | tuple[int | None]) -> tuple[str, str | None]:
        """The reply to a line that must prove the token, and why it did not (None: it
        did)."""
        why = "authentication required: send '[<seq>] auth <token>' first"
        parsed: Request | ParseError | None = None
        if isinstance(item, bytes) and len(item) <= _AUTH_LINE:
            parsed = _parse(item)
        seq = self._seq_of(item) if isinstance(item, bytes) else (item[0] or 0)
        if isinstance(parsed, Auth):
            assert self.token is not None
            if same_token(parsed.token, self.token):
                self.authed = True
                return f"[{parsed.seq}] OK", None
            why = "wrong token"
        return error_reply(seq, GatewayError.INTERNAL_STATE, note=why), why

    def _waiting(self) -> None:
        if self.unwritten_since is None:
            self.unwritten_since = self._now()

    def _event(self, line: str) -> None:
        if not self._out.full():  # a client that does not read loses its events
            self._out.put_nowait((line, 0))
            self._waiting()

    async def _reply(self, line: str) -> None:
        self.share.reply(len(line))
        await self._out.put((line, len(line)))
        self._waiting()

    async def _writer(self, write: Write) -> None:
        while (item := await self._out.get()) is not None:
            line, held = item
            try:
                await write(line.encode("utf-8") + b"\r\n")
            except (ConnectionError, OSError):
                return
            finally:
                if held:
                    self.share.written(held)
            self._touch()
            self.last_reply_at = self.last_active
            self.unwritten_since = None if self._out.empty() else self.last_active

    async def _worker(self) -> None:
        while (item := await self._requests.get()) is not None:
            if isinstance(item, str):
                await self._reply(item)
                continue
            request, held = item
            await self.share.room_for_replies()
            self.running = True
            try:
                answer = await self.executor.execute(self.session, request)
            finally:
                self.running = False
                self.share.ran(held)
                self._touch()
                del item, request  # its value: not held while the next one is awaited
            await self._reply(answer)

    async def serve(self, read: Read, write: Write, *, eof_cancels: bool) -> None:
        """Serve the client reading with ``read`` (b"" at the end) and writing with
        ``write``. ``eof_cancels``: the end of input drops pending requests (sockets)."""
        token = None
        if self.hub is not None:
            hub = self.hub
            token = hub.add_sink(self._event)
            self.session.on_events_changed = lambda kinds: hub.set_kinds(token, kinds)
        write_task = asyncio.create_task(self._writer(write))
        work_task = asyncio.create_task(self._worker())
        splitter = LineSplitter(self.max_line)
        refused = False
        try:
            while not refused:
                chunk = await self._read(read)
                self.share.hold_partial(0)
                splitter.limit = min(self.max_line, self.share.room())  # collect what fits
                short = splitter.limit < self.max_line
                items = splitter.feed(chunk) if chunk else []
                self.share.hold_partial(splitter.pending)  # a line still coming holds room
                if not chunk and (last := splitter.tail()) is not None:
                    items.append(last)
                for item in items:
                    if not self.authed:
                        reply, why = self._prove(item)
                        await self._requests.put(reply)
                        if why is not None:
                            log.warning("%s refused: %s", self.name, why)
                            refused = True
                            break
                        continue
                    self._touch()
                    self.last_line_at = self.last_active
                    await self._requests.put(await self._request(item, short=short))
                if not chunk:
                    break
            if eof_cancels and not refused:
                work_task.cancel()
            else:
                await self._requests.put(None)
            with contextlib.suppress(asyncio.CancelledError):
                await work_task
        finally:
            work_task.cancel()  # the client is gone: abort what it was doing
            with contextlib.suppress(asyncio.CancelledError):
                await work_task
            if token is not None and self.hub is not None:
                self.hub.remove_sink(token)
            await self._finish(write_task)
            self.share.release()

    async def _read(self, read: Read) -> bytes:
        """The next bytes; until the token is proved, only within :data:`AUTH_S` of the
        connection (then b"": the end)."""
        if self.authed:
            return await read()
        try:
            return await asyncio.wait_for(read(), self.connected_at + AUTH_S - self._now())
        except TimeoutError:
            log.warning("%s refused: no token within %g s", self.name, AUTH_S)
            return b""

    async def _finish(self, write_task: asyncio.Task[None]) -> None:
        """The last replies to a client that left on its own; none to a dropped one."""
        if self.dropped is not None:
            write_task.cancel()
        else:
            try:
                self._out.put_nowait(None)
            except asyncio.QueueFull:
                write_task.cancel()
        try:
            await asyncio.wait_for(write_task, _FLUSH_S)
        except (TimeoutError, asyncio.CancelledError):
            write_task.cancel()
