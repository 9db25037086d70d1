# SPDX-License-Identifier: Apache-2.0
"""The SDO client channels of a master's C node and the transfers on them: who uses them is
:class:`canola.master.SdoClient` (one channel per server it talks to), the CANopen manager
(one channel of its own) and program download. They share the node's engine and this
allocator, not the master.

A blocking transfer is waited for by the calling thread, which receives the answers itself
on python-can (``link.wait``, :mod:`canola._engine`: no hand-off between threads); an asyncio
one is completed by whichever thread receives; on a SimBus the caller runs the bus."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import threading
import time
from collections.abc import Callable
from typing import Any

from canola._c import CData, check, ffi, lib
from canola._engine import Engine
from canola.core import SimBus
from canola.errors import BusLostError, Error, SdoAbort, SdoTimeout

__all__ = ["CHANNELS", "XFER_DONE", "SdoChannels", "Transfer"]

log = logging.getLogger("canola")

#: SDO client channels of the C node (0x1280..0x128F; CO_SDO_CLIENTS_MAX in the extension).
CHANNELS = 16

#: 0x1280 + channel, sub-indices 1 and 2: COB-ID not valid.
_INVALID = (0x80000000).to_bytes(4, "little")

#: Abort code of a transfer that timed out (CiA 301).
_TIMED_OUT = 0x05040000

#: The completion of a Transfer (its ``x`` the ctx): records the end in C.
XFER_DONE: CData = ffi.addressof(lib, "canola_py_xfer_done")

#: Begins a transfer on (C node, channel, its canola_py_xfer_t): a co_err_t.
Begin = Callable[[CData, int, CData], int]


class Transfer:
    """One SDO transfer of a client channel, as its completion (``canola_py_xfer_done``, in
    C) leaves it in ``x``: ``done``, ``abort`` (0: none), ``length`` (bytes moved) and
    ``by_server`` (the server sent the abort). A thread waiting in C on a link that owns its
    bus sees the end without entering Python. ``wake_with(fn)``: ``fn`` runs at the end too
    (under the engine's lock)."""

    __slots__ = ("handle", "keep", "started_us", "waker", "x")

    def __init__(self, dev: CData | None = None, server_id: int = 0,
                 started_us: int = 0) -> None:
        self.x = ffi.new("canola_py_xfer_t *")
        if dev is not None:  # the client's dev: which side ended the transfer
            self.x.dev = dev
        self.x.request_id = 0x600 + server_id
        self.started_us = started_us  # the engine's clock: virtual time on a SimBus
        self.keep: Any = None  # what C points to until the completion
        self.waker: Callable[[], None] | None = None
        self.handle: Any = None

    def wake_with(self, waker: Callable[[], None]) -> None:
        self.waker = waker
        self.handle = ffi.new_handle(self)
        self.x.notify = self.handle

    @property
    def done(self) -> bool:
        return bool(self.x.done)

    @property
    def abort(self) -> int:
        return int(self.x.abort)

    @property
    def length(self) -> int:
        return int(self.x.len)

    @property
    def by_server(self) -> bool:
        return bool(self.x.by_server)


@ffi.def_extern(onerror=lambda *_: log.exception("canola: SDO completion failed"))
def canola_py_sdo_done(ctx: Any, channel: int, abort: int, length: int) -> None:
    del channel, abort, length  # in the transfer's x already
    t: Transfer = ffi.from_handle(ctx)
    if t.waker is not None:
        t.waker()


def server(node: CData, channel: int) -> int:
    """Whom client channel ``channel`` of the C node talks to now: node n, 0 for nobody,
    -1 for COB-IDs of someone else's choosing (see canola_py_sdo_client_server)."""
    return int(lib.canola_py_sdo_client_server(node, channel))


def unset(engine: Engine, channel: int) -> None:
    """Point client channel ``channel`` at no server (under the lock); co_sdo_client_setup()
    gives it one again."""
    for sub, data in ((1, _INVALID), (2, _INVALID), (3, b"\x00")):
        lib.canola_py_dev_write(engine.dev, 0x1280 + channel, sub, data, len(data))


class SdoChannels:
    """The channel of each server (a memo of the core's channels, checked on every use: a
    reset communication of the node reloads 0x1280.. from their power-on values, and an SDO
    client may write them), the manager's reserved channel, and one lock per server: one
    transfer at a time to a server, whoever starts it."""

    def __init__(self, engine: Engine) -> None:
        self.engine = engine
        self.table: dict[int, int] = {}  # server node-ID -> channel; 0: the manager's
        self._locks: dict[int, threading.Lock] = {}
        self._buffers: dict[int, CData] = {}  # server node-ID -> its upload buffer
        self._holders: dict[int, int] = {}  # server node-ID -> the thread in run() for it

    @property
    def node_id(self) -> int:
        """The node-ID of the C node whose channels these are."""
        return int(lib.co_node_id(self.engine.node))

    def lock_of(self, server_id: int) -> threading.Lock:
        """The lock a transfer to ``server_id`` holds from its start to its end."""
        lock = self._locks.get(server_id)
        if lock is None:
            lock = self._locks.setdefault(server_id, threading.Lock())
        return lock

    def channel(self, node: CData, server_id: int) -> int:
        """The client channel talking to ``server_id``, set up if needed (under the lock)."""
        channel = self.table.get(server_id)
        if channel is not None and server(node, channel) == server_id:
            return channel
        self.table = {n: c for n, c in self.table.items()
                      if n == 0 or server(node, c) == n}  # 0: the manager's channel
        used = set(self.table.values())
        servers = {c: server(node, c) for c in range(CHANNELS) if c not in used}
        for c, talks_to in servers.items():  # set up to it by someone else (0x1280 written)
            if talks_to == server_id:
                self.table[server_id] = c
                return c
        free = [c for c, talks_to in servers.items() if talks_to == 0]
        if not free:  # take the channel of a node that has no transfer open
            for other, c in list(self.table.items()):
                if not lib.co_sdo_client_busy(node, c):
                    del self.table[other]
                    free = [c]
                    break
        if not free:
            raise Error(f"all {CHANNELS} SDO client channels are busy")
        channel = free[0]
        check(int(lib.co_sdo_client_setup(node, channel, server_id)), "co_sdo_client_setup")
        self.table[server_id] = channel
        return channel

    def abort(self, server_id: int) -> None:
        """End the transfer to ``server_id`` in progress, if any, with 0x05040000 (its
        completion runs)."""
        channel = self.table.get(server_id)
        if channel is None:
            return
        with self.engine.locked() as node:
            if lib.co_sdo_client_busy(node, channel):
                lib.co_sdo_client_abort(node, channel, 0x05040000)

    def release(self, node: CData, server_ids: list[int]) -> None:
        """Free the channels to ``server_ids`` (under the lock): a server is talked to by
        one client channel at a time, and the manager needs its own."""
        for server_id in server_ids:
            channel = self.table.get(server_id)
            if channel is None:
                continue
            if lib.co_sdo_client_busy(node, channel):
                raise Error(f"an SDO transfer to node {server_id} is in progress")
            unset(self.engine, channel)
            del self.table[server_id]

    def reserve(self) -> int:
        """A channel for the manager (under the lock): the one kept under key 0 (no SDO
        server has node-ID 0), else a free one."""
        if 0 in self.table:
            return self.table[0]
        used = set(self.table.values())
        free = [c for c in range(CHANNELS) if c not in used]
        if not free:
            raise Error("no free SDO client channel for the manager")
        self.table[0] = free[-1]
        return free[-1]

    # ---- transfers (SdoClient's): one at a time per server, whoever starts it

    def upload(self, server_id: int, index: int, sub: int, *, block: bool, max_size: int,
               timeout: float | None, answer_ms: int, default_ms: int) -> bytes:
        """Read (index, sub) of ``server_id``: its wire bytes (see SdoClient.upload)."""
        t = self.run(server_id, self._upload(server_id, index, sub, block, max_size), timeout,
                     answer_ms, default_ms)
        return bytes(ffi.buffer(t.keep, t.length))

    def download(self, server_id: int, index: int, sub: int, data: bytes, *, block: bool,
                 timeout: float | None, answer_ms: int, default_ms: int) -> None:
        """Write ``data`` to (index, sub) of ``server_id`` (see SdoClient.download)."""
        self.run(server_id, self._download(index, sub, data, block), timeout, answer_ms,
                 default_ms)

    async def aupload(self, server_id: int, index: int, sub: int, *, block: bool,
                      max_size: int, timeout: float | None, answer_ms: int,
                      default_ms: int) -> bytes:
        t = await self.arun(server_id, self._upload(server_id, index, sub, block, max_size),
                            timeout, answer_ms, default_ms)
        return bytes(ffi.buffer(t.keep, t.length))

    async def adownload(self, server_id: int, index: int, sub: int, data: bytes, *,
                        block: bool, timeout: float | None, answer_ms: int,
                        default_ms: int) -> None:
        await self.arun(server_id, self._download(index, sub, data, block), timeout, answer_ms,
                        default_ms)

    def _upload(self, server_id: int, index: int, sub: int, block: bool,
                max_size: int) -> tuple[Begin, CData, str]:
        _check_address(index, sub)
        if not 1 <= max_size <= 0xFFFFFFFF:
            raise Error(f"max_size {max_size} is outside 1..2**32-1")
        buf = self._buffers.get(server_id)  # transfers to a server are one at a time
        if buf is None or len(buf) != max_size:
            buf = self._buffers[server_id] = ffi.new("uint8_t[]", max_size)
        mode = lib.CO_SDO_BLOCK if block else lib.CO_SDO_AUTO

        def begin(node: CData, channel: int, xfer: CData) -> int:
            return int(lib.co_sdo_upload(node, channel, index, sub, mode, buf, max_size,
                                         XFER_DONE, xfer))
        return begin, buf, f"SDO upload 0x{index:04X} sub {sub}"

    @staticmethod
    def _download(index: int, sub: int, data: bytes, block: bool) -> tuple[Begin, CData, str]:
        _check_address(index, sub)
        src = ffi.new("uint8_t[]", max(len(data), 1))
        ffi.memmove(src, data, len(data))
        mode = lib.CO_SDO_BLOCK if block else lib.CO_SDO_AUTO

        def begin(node: CData, channel: int, xfer: CData) -> int:
            return int(lib.co_sdo_download(node, channel, index, sub, mode, src, len(data),
                                           XFER_DONE, xfer))
        return begin, src, f"SDO download 0x{index:04X} sub {sub}"

    def _start(self, server_id: int, how: tuple[Begin, CData, str], answer_ms: int,
               waker: Callable[[], None] | None = None) -> Transfer:
        """A transfer begun on the channel of ``server_id``, its time-out per answer
        ``answer_ms`` (0: the node's); ``waker`` runs at its end."""
        begin, keep, what = how
        engine = self.engine
        t = Transfer(engine.dev, server_id, engine.now_us())
        t.keep = keep
        if waker is not None:
            t.wake_with(waker)

        def start(node: CData) -> int:
            channel = self.channel(node, server_id)
            check(int(lib.co_sdo_client_set_timeout(node, channel, answer_ms)),
                  "co_sdo_client_set_timeout")
            return begin(node, channel, t.x)
        check(engine.call(start), f"{what} of node {server_id}")
        return t

    def _ready(self, timeout: float | None) -> None:
        if timeout is not None and timeout <= 0:
            raise Error(f"timeout must be positive, got {timeout}")
        if not self.engine.running:
            raise Error("the master is not started: call start() first")

    def run(self, server_id: int, how: tuple[Begin, CData, str], timeout: float | None,
            answer_ms: int, default_ms: int) -> Transfer:
        """Start the transfer and wait for its end (``timeout``: the whole transfer's bound,
        seconds); raise its abort."""
        engine = self.engine
        engine.check_may_block()
        self._ready(timeout)
        busy = self.lock_of(server_id)
        me = threading.get_ident()
        if self._holders.get(server_id) == me:  # a callback run while this thread waits
            raise Error(f"a blocking SDO call to node {server_id} from a callback run during "
                        "one to the same node would wait for itself")
        if not busy.acquire(timeout=600):
            raise Error(f"SDO client of node {server_id} stays busy")
        self._holders[server_id] = me
        try:
            t = self._start(server_id, how, answer_ms)
            bus = engine.bus
            limit_ms = answer_ms or default_ms  # the time-out that ends it: one answer's
            if isinstance(bus, SimBus):
                begin = bus.now_us
                while not t.done:
                    if timeout is not None and bus.now_us - begin >= timeout * 1e6:
                        limit_ms = _whole_ms(timeout)
                        self.abort(server_id)
                        break
                    bus.run_until(bus.now_us + 1000)
            elif not t.done:  # else answered at once: a node of the same bus object
                link = engine.link
                assert link is not None
                end = None if timeout is None else time.monotonic() + timeout
                try:
                    if not link.wait(engine, lambda: t.done, end, t.x):
                        limit_ms = _whole_ms(timeout)
                        self.abort(server_id)  # completes the transfer with 0x05040000
                except (BusLostError, KeyboardInterrupt):
                    self.abort(server_id)  # the channel is free again, the bus or not
                    raise
                except Error:
                    self.abort(server_id)
                    raise Error("the master was stopped during an SDO transfer") from None
            return self._finish(t, server_id, limit_ms, (engine.now_us() - t.started_us) / 1e6)
        finally:
            del self._holders[server_id]
            busy.release()

    async def arun(self, server_id: int, how: tuple[Begin, CData, str], timeout: float | None,
                   answer_ms: int, default_ms: int) -> Transfer:
        """:meth:`run` as a coroutine: the thread that receives completes it."""
        engine = self.engine
        if isinstance(engine.bus, SimBus):
            return self.run(server_id, how, timeout, answer_ms, default_ms)  # virtual time
        self._ready(timeout)
        loop = asyncio.get_running_loop()
        busy = self.lock_of(server_id)
        while not busy.acquire(blocking=False):
            await asyncio.sleep(0.001)
        try:
            fut: asyncio.Future[None] = loop.create_future()

            def resolve() -> None:
                if not fut.done():
                    fut.set_result(None)

            def wake() -> None:
                with contextlib.suppress(RuntimeError):  # the loop is closed: nobody waits
                    loop.call_soon_threadsafe(resolve)

            t = self._start(server_id, how, answer_ms, wake)
            limit_ms = answer_ms or default_ms
            try:
                end = None if timeout is None else loop.time() + timeout
                while not t.done:
                    try:
                        await asyncio.wait_for(asyncio.shield(fut), 0.05)
                    except TimeoutError:
                        if end is not None and loop.time() >= end:
                            limit_ms = _whole_ms(timeout)
                            self.abort(server_id)  # completes it with 0x05040000
                            end = None
                        elif not engine.running:
                            self.abort(server_id)
                            raise Error("the master was stopped during an SDO transfer") \
                                from None
            except asyncio.CancelledError:
                self.abort(server_id)  # ends the transfer before the channel is reused
                raise
            return self._finish(t, server_id, limit_ms, (engine.now_us() - t.started_us) / 1e6)
        finally:
            busy.release()

    @staticmethod
    def _finish(t: Transfer, server_id: int, limit_ms: int, after: float) -> Transfer:
        """``t`` done after ``after`` seconds: its abort raised, telling the server's abort
        from the master's (``limit_ms``: the time-out that fired, the whole transfer's or
        one answer's)."""
        if not t.done:  # pragma: no cover -- the core always completes on abort
            raise SdoTimeout(server_id, limit_ms)
        if not t.abort:
            return t
        if t.abort == _TIMED_OUT and not t.by_server:
            raise SdoTimeout(server_id, limit_ms, after)
        raise SdoAbort(t.abort, node=server_id, by_server=t.by_server, after_s=after)


def _whole_ms(timeout: float | None) -> int:
    """A transfer's whole ``timeout`` (s), in ms."""
    assert timeout is not None
    return round(timeout * 1000)


def _check_address(index: int, sub: int) -> None:
    if not (isinstance(index, int) and 0 <= index <= 0xFFFF):
        raise Error(f"index {index!r} is outside 0x0000..0xFFFF")
    if not (isinstance(sub, int) and 0 <= sub <= 0xFF):
        raise Error(f"sub-index {sub!r} is outside 0..255")
