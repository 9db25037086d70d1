# SPDX-License-Identifier: Apache-2.0
"""The link of a python-can bus object that canola does not own (virtual, pcan, kvaser,
...): frames come from python-can's ``recv`` and go to its ``send``. Not public.

One :class:`Link` per bus object drives every canola node on it, with one lock and one
thread. Receiving: one thread at a time holds the receive token (:attr:`Link.rx`). The bus
thread does, waiting for frames up to the nodes' next deadline, capped at
:data:`MAX_WAIT_S` so that deadlines that application calls move earlier are met within
that cap. A thread that waits for an answer (a blocking SDO transfer, an LSS request, a
boot, a program download) receives it itself (:meth:`Link.wait`) while the bus thread
stands aside, so the answer needs no hand-off between threads. Whoever receives takes
every frame python-can holds, ingests each at its bus time and only then polls the timers
(:meth:`Link.pump`): a time-out is judged after the frames that arrived before it.
Callbacks run as :mod:`canola._engine` says, by the thread that released the lock."""

from __future__ import annotations

import logging
import struct
import threading
import time
import weakref
from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import can

from canola._c import CData, ffi, lib
from canola._linkbase import NEVER, Frame, LinkBase
from canola.errors import Error

if TYPE_CHECKING:
    from canola._engine import Engine

__all__ = ["MAX_WAIT_S", "Link"]

log = logging.getLogger("canola")

#: Longest the bus thread waits for a frame before polling the node again (seconds).
MAX_WAIT_S = 0.01

#: Frames python-can refused that wait for the next flush, at most.
_UNSENT_MAX = 4096

#: How long the bus thread stays aside after an application thread waited (a next transfer
#: then finds the receive token free); frames wait in python-can meanwhile.
_ASIDE_NS = int(MAX_WAIT_S * 1e9)

#: Frames taken from python-can in one go before the nodes are polled, at most.
_DRAIN_MAX = 256

_FRAME = struct.Struct("<IBB8s2x")  # co_frame_t: id, flags, len, data (and padding)
assert ffi.sizeof("co_frame_t") == _FRAME.size and ffi.offsetof("co_frame_t", "data") == 6
_EXT = int(lib.CO_FRAME_EXT)
_RTR = int(lib.CO_FRAME_RTR)


def _free_link(raw: Any, retired: deque[Any]) -> None:
    while retired:
        lib.canola_py_dev_free(retired.popleft())
    lib.canola_py_link_free(raw)


class Link(LinkBase):
    """One python-can bus object and the canola nodes on it (see the module doc)."""

    def __init__(self, bus: can.BusABC) -> None:
        raw = lib.canola_py_link_new()
        if raw == ffi.NULL:
            raise Error("out of memory for a python-can link")
        super().__init__(bus, raw)
        self.lock = threading.Lock()
        self._unsent: deque[can.Message] = deque()
        self._t0 = time.monotonic_ns()
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._frame = ffi.new("co_frame_t *")
        #: The receive token: its holder alone takes frames from python-can (pump).
        self.rx = threading.Lock()
        #: Application threads in :meth:`wait` (the bus thread stands aside meanwhile); a
        #: set: adding and discarding are atomic, no lock needed.
        self.waiting: set[object] = set()
        self._waited_ns = 0  # when the last of them left (time.monotonic_ns)
        self._clock_us = 0  # the latest time handed to the nodes
        weakref.finalize(self, _free_link, raw, self._retired)

    def now_us(self) -> int:
        return (time.monotonic_ns() - self._t0) // 1000

    # ---- the bus thread

    def _start_thread(self) -> None:
        with self.lock:
            if self._thread is not None:
                self._thread.name = self.thread_name()
                return
            self._stop = threading.Event()
            self._thread = threading.Thread(target=self._run, args=(self._stop,),
                                            name=self.thread_name(), daemon=True)
        self._thread.start()

    def _stop_thread(self, engine: Engine, timeout: float) -> None:
        with self.lock:
            thread = self._thread if not self.engines else None
            if thread is not None:
                self._stop.set()
                self._thread = None
            elif self._thread is not None:
                self._thread.name = self.thread_name()
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout)
            if thread.is_alive():
                raise Error(f"{engine.name}: the bus thread did not stop within {timeout} s")

    def in_thread(self) -> bool:
        return self._thread is not None and threading.current_thread() is self._thread

    # ---- under the lock

    def app_clock(self) -> int:
        """First thing under the lock for an application's call: the time now, but short of
        the nodes' next deadline, which the receiving thread judges once the frames received
        before it count (:meth:`pump`), never an application's call."""
        self.free_retired()
        now = self.now_us()
        due = int(self.c.due_us)
        if now >= due != NEVER:
            now = max(self._clock_us, due - 1)
        self._clock_us = now
        return now

    def enter_app(self, node: CData) -> int:
        self.lock.acquire()
        try:
            now = self.app_clock()
            lib.co_node_poll(node, now)
        except BaseException:
            self.lock.release()
            raise
        return now

    def leave_app(self, now_us: int) -> None:
        try:
            self.flush(now_us)
        finally:
            self.lock.release()

    def flush(self, now_us: int) -> None:
        """Deliver what the nodes sent to the others, then hand it to python-can (under
        the lock, so that python-can sees the frames in order)."""
        c = self.c
        n = int(lib.canola_py_link_run(c, now_us))
        if not n and self._unsent:
            self._send(b"")
        while n:
            self._send(bytes(ffi.buffer(c.frames, n * _FRAME.size)))
            if not lib.canola_py_link_clear(c):
                break
            lib.canola_py_link_poll(c, now_us)  # refused frames wait in the cores' queues
            n = int(c.count)

    def _send(self, frames: bytes) -> None:
        """Hand ``frames`` (co_frame_t's bytes) to python-can after those it refused."""
        unsent, bus = self._unsent, self.bus
        for can_id, flags, length, data in _FRAME.iter_unpack(frames):
            rtr = bool(flags & _RTR)
            unsent.append(can.Message(arbitration_id=can_id, is_extended_id=bool(flags & _EXT),
                                      is_remote_frame=rtr, dlc=length,
                                      data=b"" if rtr else data[:length]))
        while unsent:
            try:
                bus.send(unsent[0], timeout=0.05)
            except can.CanOperationError:  # full: the rest waits for the next flush
                if len(unsent) > _UNSENT_MAX:
                    log.warning("python-can refuses frames: %d dropped", len(unsent))
                    unsent.clear()
                return
            except can.CanError as exc:
                log.warning("send failed: %s", exc)
            unsent.popleft()

    # ---- receiving: the bus thread, or an application thread that waits for an answer

    def pump(self, wait_s: float) -> int:
        """Holding :attr:`rx`: take every frame python-can has received (waiting up to
        ``wait_s`` for the first; the rest under the lock, so that what arrived while the
        lock was busy counts too), ingest each at its bus time, then poll: a time-out is
        judged only once the frames that arrived before it count. Returns the earliest
        deadline of the nodes (their clock). Callbacks are left queued (:meth:`dispatch`)."""
        first = self._receive(wait_s)
        c, frame = self.c, self._frame
        msgs: list[can.Message] = []
        with self.lock:
            self.free_retired()
            now = (time.monotonic_ns() - self._t0) // 1000
            if first is not None:
                msgs.append(first)
                while len(msgs) < _DRAIN_MAX:
                    more = self._receive(0)
                    if more is None:
                        break
                    msgs.append(more)
                offset = now - time.time() * 1e6  # python-can's clock (s) -> ours (us)
                for msg in msgs:
                    if msg.is_error_frame or msg.is_fd or msg.dlc > 8:
                        continue
                    # its bus time, never before what the nodes saw already nor after now
                    at = min(now, max(self._clock_us, int(msg.timestamp * 1e6 + offset)))
                    self._clock_us = at
                    frame.id = msg.arbitration_id
                    frame.flags = (_EXT if msg.is_extended_id else 0) | \
                        (_RTR if msg.is_remote_frame else 0)
                    frame.len = msg.dlc
                    if not msg.is_remote_frame:
                        ffi.memmove(frame.data, msg.data, min(len(msg.data), 8))
                    lib.canola_py_link_ingest(c, at, frame)
            self._clock_us = now
            due = int(lib.canola_py_link_poll(c, now))
            self.flush(now)
        if msgs and self.listening:
            self._listen(msgs)
        for engine in self.timers:
            engine.run_timers(now)
            timer = engine.next_timer_us()
            due = min(due, timer) if timer is not None else due
        return due

    def _receive(self, wait_s: float) -> can.Message | None:
        """The next frame from python-can (waiting up to ``wait_s``), None without one."""
        try:
            return self.bus.recv(wait_s)
        except can.CanError as exc:
            log.warning("%s: receive failed: %s", self.thread_name(), exc)
            time.sleep(0.05)
            return None

    def _listen(self, msgs: list[can.Message]) -> None:
        listening = [e for e in self.engines if e.frame_listeners]
        for msg in msgs if listening else ():
            if msg.is_error_frame or msg.is_fd or msg.dlc > 8:
                continue
            seen = Frame(msg.arbitration_id, b"" if msg.is_remote_frame else bytes(msg.data),
                         rtr=msg.is_remote_frame, extended=msg.is_extended_id,
                         timestamp=msg.timestamp)
            for engine in listening:
                engine.frame_seen(seen)

    def wait(self, engine: Engine, done: Callable[[], bool], end: float | None,
             xfer: CData | None = None) -> bool:
        del xfer  # done() says it
        me = object()
        self.waiting.add(me)
        rx, c = self.rx, self.c
        try:
            while not done():
                left = 0.05 if end is None else min(0.05, end - time.monotonic())
                if left <= 0:
                    return False
                if not engine.running:
                    raise Error(f"{engine.name} was stopped while a call waited for it")
                if not rx.acquire(True, left):
                    continue
                try:
                    if done():
                        break
                    due = c.due_us
                    self.pump(left if due == NEVER else
                              min(left, max(0.0, (due - self.now_us()) / 1e6)))
                finally:
                    rx.release()
                if self.events:
                    self.dispatch()
            return True
        finally:
            self._waited_ns = time.monotonic_ns()
            self.waiting.discard(me)

    def _wait_s(self, due: int, cap_s: float) -> float:
        if due == NEVER:
            return cap_s
        return min(cap_s, max(0.0, (due - self.now_us()) / 1e6))

    def _run(self, stop: threading.Event) -> None:
        while not stop.is_set():
            try:
                self._loop(stop)
            except Exception:  # never let the bus thread die silently
                log.exception("%s: bus thread error", self.thread_name())
                stop.wait(0.05)

    def _loop(self, stop: threading.Event) -> None:
        rx, due = self.rx, NEVER
        while not stop.is_set():
            if self.waiting or time.monotonic_ns() - self._waited_ns < _ASIDE_NS:
                stop.wait(MAX_WAIT_S)  # an application thread receives (wait): stand aside,
                continue  # and a while after it, for its next transfer
            if not rx.acquire(timeout=MAX_WAIT_S):
                continue
            try:
                due = self.pump(self._wait_s(due, MAX_WAIT_S))
            finally:
                rx.release()
            self.dispatch()
