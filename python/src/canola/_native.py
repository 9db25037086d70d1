# SPDX-License-Identifier: Apache-2.0
"""The link of a bus whose socket canola owns in C (:class:`canola.bus.native.NativeBus`:
the SocketCAN and socketcand buses canola opens by URL). Not public.

C reads and writes the socket (``port/python/py_io.c``), with Python's GIL released, in
one of two threads: an application thread that waits for an answer (a blocking SDO
transfer, an LSS request, a boot, a program download: :meth:`NativeLink.wait`) reads the
bus itself while it waits, so the answer reaches it with no hand-off between threads and
no Python object per frame; while nobody waits, the link's own C thread does (and runs
the nodes' deadlines). Python is entered only for what it asked for: a waiting call's
end, and the callbacks the application subscribed, in batches (the frames a frame
listener wants are kept in C and handed over together, in order with the other
callbacks). The C thread enters Python (``canola_py_io_python``) to run them, as the bus
thread does on python-can; a blocking call from there raises, as it does there.

The nodes' lock is the C link's mutex (:class:`_CLock`): a Python thread waits for it
inside a cffi call, which released the GIL, so the C thread, which may need the GIL for a
node's callback while it holds the mutex, always gets it."""

from __future__ import annotations

import atexit
import logging
import os
import struct
import threading
import time
import weakref
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from canola._c import CData, ffi, lib
from canola._linkbase import NEVER, Frame, LinkBase, deliver_frames
from canola.errors import BusLostError, Error

if TYPE_CHECKING:
    import can

    from canola._engine import Engine

__all__ = ["NativeLink"]

log = logging.getLogger("canola")

#: A waiting thread comes back to Python at least this often (Ctrl-C, a stopped node).
_CHUNK_S = 0.05

_DRAIN = int(lib.CANOLA_PY_IO_DRAIN)
_DONE, _PYTHON, _FAILED = (int(lib.CANOLA_PY_IO_DONE), int(lib.CANOLA_PY_IO_PYTHON),
                           int(lib.CANOLA_PY_IO_FAILED))
_FRAME = struct.Struct("<IBB8s2x")  # co_frame_t
_EXT = int(lib.CO_FRAME_EXT)
_RTR = int(lib.CO_FRAME_RTR)

#: The links whose C thread may run: stopped before the interpreter goes.
_RUNNING: weakref.WeakSet[NativeLink] = weakref.WeakSet()


class _CLock:
    """The C link's mutex as a Python lock (``with``, acquire, release)."""

    __slots__ = ("_io",)

    def __init__(self, io: CData) -> None:
        self._io = io

    def acquire(self, blocking: bool = True, timeout: float = -1) -> bool:
        del blocking, timeout  # held only for short C calls: waiting is always right
        lib.canola_py_io_lock(self._io)
        return True

    def release(self) -> None:
        lib.canola_py_io_unlock(self._io)

    def __enter__(self) -> _CLock:
        lib.canola_py_io_lock(self._io)
        return self

    def __exit__(self, *exc: object) -> None:
        lib.canola_py_io_unlock(self._io)


class NativeLink(LinkBase):
    """The canola nodes on a :class:`~canola.bus.native.NativeBus` (see the module doc)."""

    def __init__(self, bus: can.BusABC, io: CData) -> None:
        super().__init__(bus, lib.canola_py_io_link(io))
        self.io = io
        self.lock = _CLock(io)
        self._handle = ffi.new_handle(self)
        #: Frames for listeners and queued callbacks go into ``events`` one thread at a
        #: time, in the order they happened.
        self._work = threading.RLock()
        self._seen = ffi.new("co_frame_t[]", _DRAIN)
        self._seen_us = ffi.new("uint64_t[]", _DRAIN)

    def now_us(self) -> int:
        return time.monotonic_ns() // 1000  # CLOCK_MONOTONIC, the C link's clock

    def error(self) -> str:
        return ffi.string(lib.canola_py_io_error(self.io)).decode("utf-8", "replace")

    # ---- the C thread

    def _start_thread(self) -> None:
        err = lib.canola_py_io_start(self.io, self._handle)
        if err:
            raise Error(f"cannot start the bus thread: {os.strerror(err)}")
        _RUNNING.add(self)

    def _stop_thread(self, engine: Engine, timeout: float) -> None:
        if self.engines:
            return
        if not lib.canola_py_io_stop(self.io, round(timeout * 1000)) and not self.in_thread():
            raise Error(f"{engine.name}: the bus thread did not stop within {timeout} s")

    def in_thread(self) -> bool:
        return bool(lib.canola_py_io_in_thread(self.io))

    # ---- applications' calls

    def enter_app(self, node: CData) -> int:
        now = int(lib.canola_py_io_enter(self.io, node))
        if self._retired:
            self.free_retired()
        return now

    def leave_app(self, now_us: int) -> None:
        lib.canola_py_io_leave(self.io, now_us)

    def listen(self, cob_id: int | None) -> None:
        lib.canola_py_io_listen(self.io, -1 if cob_id is None else cob_id)

    def timers_changed(self) -> None:
        lib.canola_py_io_set_py_due(self.io, self._next_timer())

    # ---- Python's work

    def later(self, fn: Callable[[], None]) -> None:
        with self._work:
            self._take_seen()  # the frames that came before it go first
            self.events.append(fn)
        lib.canola_py_io_note(self.io)

    def python_work(self) -> int:
        """The frames kept for listeners, the Python timers due, the callbacks queued: the
        next Python timer (NEVER: none)."""
        now = int(lib.canola_py_io_python_begin(self.io))
        with self._work:
            self._take_seen()
            for engine in self.timers:
                engine.run_timers(now)
        self.dispatch()
        return self._next_timer()

    def _next_timer(self) -> int:
        due = NEVER
        for engine in self.timers:
            timer = engine.next_timer_us()
            if timer is not None and timer < due:
                due = timer
        return due

    def _take_seen(self) -> None:
        n = int(lib.canola_py_io_take_seen(self.io, self._seen, self._seen_us, _DRAIN))
        if not n:
            return
        listeners = [fn for engine in self.engines for fn in engine.frame_listeners]
        if not listeners:
            return
        frames = [Frame(can_id, b"" if flags & _RTR else data[:length], rtr=bool(flags & _RTR),
                        extended=bool(flags & _EXT), timestamp=stamp / 1e6)
                  for (can_id, flags, length, data), stamp in
                  zip(_FRAME.iter_unpack(ffi.buffer(self._seen, n * _FRAME.size)),
                      self._seen_us[0:n], strict=True)]
        self.events.append(lambda: deliver_frames(listeners, frames))

    # ---- waiting

    def wait(self, engine: Engine, done: Callable[[], bool], end: float | None,
             xfer: CData | None = None) -> bool:
        io, x = self.io, ffi.NULL if xfer is None else xfer
        while True:
            if xfer is None and done():
                return True
            now = time.monotonic()
            if end is not None and now >= end:
                return bool(xfer.done) if xfer is not None else done()
            until = now + _CHUNK_S if end is None else min(end, now + _CHUNK_S)
            rc = lib.canola_py_io_wait(io, x, int(until * 1e6))
            if rc == _DONE:
                return True
            if rc == _PYTHON:
                self.python_work()
            elif rc == _FAILED:
                raise BusLostError(f"the bus failed: {self.error()}")
            if not engine.running:
                raise Error(f"{engine.name} was stopped while a call waited for it")


@ffi.def_extern(error=NEVER, onerror=lambda *_: log.exception("canola: the bus thread's work"))
def canola_py_io_python(user: Any, now_us: int) -> int:
    del now_us  # python_work takes the clock itself
    link: NativeLink = ffi.from_handle(user)
    return link.python_work()


@atexit.register
def _stop_threads() -> None:
    for link in list(_RUNNING):
        lib.canola_py_io_stop(link.io, 1000)
