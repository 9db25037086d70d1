"""One C node and what drives it: a simulated bus (virtual time) or a python-can bus
(a background thread, real time). Shared by :class:`canola.Device` and
:class:`canola.Master`; not public.

Threading (python-can): one lock guards every call into the C node. The bus thread
receives with a time-out equal to the node's next deadline (``co_node_poll``'s return),
capped at :data:`MAX_WAIT_S` so that deadlines that application calls move earlier are
met within that cap. Callbacks of the C node only record events; the application's
callbacks run afterwards in the bus thread (python-can) or inside :meth:`SimBus.run_until`
(simulated bus), never under the lock, in the order the events happened, and may call
any method of the node. They must not block: a blocking SDO call of the same master from
its callback raises :class:`~canola.errors.Error`; one that waits for another node whose
answer needs the calling thread (a device's callback reading that device through a
master) only ends with the SDO time-out.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator
from typing import Any

import can

from canola._core import ffi, lib
from canola.core import Od, SimBus, _check
from canola.errors import Error

__all__ = ["MAX_WAIT_S", "Bus", "Engine", "Frame"]

log = logging.getLogger("canola")

#: Longest the bus thread waits for a frame before polling the node again (seconds).
MAX_WAIT_S = 0.01

Bus = SimBus | can.BusABC


class Frame:
    """A CAN frame as callbacks see it: ``can_id``, ``data``, ``rtr``, ``extended``,
    ``timestamp`` (seconds: the bus's clock for python-can, virtual time on a SimBus)."""

    __slots__ = ("can_id", "data", "extended", "rtr", "timestamp")

    def __init__(self, can_id: int, data: bytes, *, rtr: bool = False, extended: bool = False,
                 timestamp: float = 0.0) -> None:
        self.can_id = can_id
        self.data = data
        self.rtr = rtr
        self.extended = extended
        self.timestamp = timestamp

    def __repr__(self) -> str:
        return f"Frame(0x{self.can_id:03X}, {self.data.hex()})"


class _Timer:
    __slots__ = ("due_us", "fn", "period_us")

    def __init__(self, due_us: int, period_us: int, fn: Callable[[], None]) -> None:
        self.due_us = due_us
        self.period_us = period_us
        self.fn = fn


def _frame_in(frame: Any, timestamp: float) -> Frame:
    return Frame(int(frame.id), bytes(frame.data[0:frame.len]),
                 rtr=bool(frame.flags & lib.CO_FRAME_RTR),
                 extended=bool(frame.flags & lib.CO_FRAME_EXT), timestamp=timestamp)


class Engine:
    """A C node (``canola_py_dev_t``) on ``bus``; ``owner`` gets the C callbacks through
    its ``_on_*`` methods (called under the lock; they queue work with :meth:`later`)."""

    def __init__(self, bus: Bus, od: Od, node_id: int, owner: Any, *, sdo_timeout_ms: int,
                 store_dir: str | None, raw_frames: bool, name: str,
                 quiet: bool = False) -> None:
        if not isinstance(bus, SimBus | can.BusABC):
            raise Error(f"bus must be a canola.core.SimBus or a python-can BusABC, not "
                        f"{type(bus).__name__}")
        if not 1 <= node_id <= 127 and node_id != 0xFF:  # 0xFF: none yet (LSS)
            raise Error(f"node-ID {node_id} is outside 1..127")
        self.bus = bus
        self.od = od
        self.owner = owner
        self.name = name
        self.sim = isinstance(bus, SimBus)
        self._lock = threading.Lock()
        self._events: deque[Callable[[], None]] = deque()
        self._handle = ffi.new_handle(self)
        self._frame_listeners: list[Callable[[Frame], None]] = []
        self.app_writing = False
        err = ffi.new("co_err_t *")
        store = ffi.new("char[]", store_dir.encode()) if store_dir is not None else ffi.NULL
        raw = lib.canola_py_dev_new(bus._bus if isinstance(bus, SimBus) else ffi.NULL,
                                    od.entries, od.count, node_id, sdo_timeout_ms, store,
                                    raw_frames, self._handle, err)
        if raw == ffi.NULL:
            if store_dir is not None:
                raise Error(f"parameter storage folder {store_dir!r} cannot be used")
            _check(int(err[0]), "create the node")
        if isinstance(bus, SimBus):
            bus._nodes.append((raw, od))  # ports stay attached: freed with the bus
            bus._nodes.append((self._handle, self))
            bus._engines.append(self)
            self._dev = raw
        else:
            self._dev = ffi.gc(raw, lib.canola_py_dev_free)
        if int(err[0]) != lib.CO_OK:
            if store_dir is not None and int(err[0]) == lib.CO_ERR_ARG:
                raise Error(f"parameter storage folder {store_dir!r} cannot be used")
            _check(int(err[0]), "co_node_init")
        self.node = lib.canola_py_dev_node(raw)
        lib.canola_py_dev_set_quiet(raw, quiet)  # before the start: its boot-up stays off
        self._timers: list[_Timer] = []
        self._t0 = time.monotonic_ns()
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._started = False

    # ---- time and locking

    def now_us(self) -> int:
        if isinstance(self.bus, SimBus):
            return self.bus.now_us
        return (time.monotonic_ns() - self._t0) // 1000

    @contextlib.contextmanager
    def locked(self) -> Iterator[Any]:
        """The C node, under the lock, its clock brought to now first. On a SimBus the
        frames sent inside are delivered (at the same virtual instant) afterwards."""
        if isinstance(self.bus, SimBus):
            with self._lock:
                yield self.node
                lib.canola_py_dev_touch(self._dev)
            self.bus.run_until(self.bus.now_us)
        else:
            with self._lock:
                lib.co_node_poll(self.node, self.now_us())
                yield self.node

    def later(self, fn: Callable[[], None]) -> None:
        """Run ``fn`` after the current C call, outside the lock (see the module doc)."""
        self._events.append(fn)

    def dispatch(self) -> None:
        while self._events:
            fn = self._events.popleft()
            try:
                fn()
            except Exception:
                log.exception("%s: a callback raised", self.name)

    # ---- periodic work of the Python side (e.g. TIME production), in the node's time

    def add_timer(self, period_us: int, fn: Callable[[], None]) -> _Timer:
        """Run ``fn`` every ``period_us`` (first one period from now), like a callback."""
        timer = _Timer(self.now_us() + period_us, period_us, fn)
        self._timers.append(timer)
        return timer

    def remove_timer(self, timer: _Timer) -> None:
        if timer in self._timers:
            self._timers.remove(timer)

    def next_timer_us(self) -> int | None:
        return min((t.due_us for t in self._timers), default=None)

    def run_timers(self, now_us: int) -> None:
        for timer in list(self._timers):
            if timer.due_us <= now_us:
                timer.due_us += timer.period_us
                if timer.due_us <= now_us:  # fell behind (a slow machine): skip, no burst
                    timer.due_us = now_us + timer.period_us
                self.later(timer.fn)

    def in_bus_thread(self) -> bool:
        return self._thread is not None and threading.current_thread() is self._thread

    def check_may_block(self) -> None:
        if self.in_bus_thread():
            raise Error("a blocking call from a callback would wait for itself: "
                        "use the asyncio form or do it from another thread")

    def add_frame_listener(self, fn: Callable[[Frame], None]) -> None:
        self._frame_listeners.append(fn)

    def frame_seen(self, frame: Frame) -> None:
        for fn in self._frame_listeners:
            self.later(lambda fn=fn: fn(frame))  # type: ignore[misc]

    # ---- life cycle

    def start(self) -> None:
        if not self._started:
            with self._lock:
                _check(lib.co_node_start(self.node, self.now_us()), "co_node_start")
            self._started = True
            if isinstance(self.bus, SimBus):
                self.bus.run_until(self.bus.now_us)
        if isinstance(self.bus, can.BusABC) and self._thread is None:
            self._stop.clear()
            self._thread = threading.Thread(target=self._run, name=self.name, daemon=True)
            self._thread.start()

    def stop(self, timeout: float = 2.0) -> None:
        thread = self._thread
        if thread is None:
            return
        self._stop.set()
        if thread is not threading.current_thread():
            thread.join(timeout)
            if thread.is_alive():
                raise Error(f"{self.name}: the bus thread did not stop within {timeout} s")
        self._thread = None

    @property
    def running(self) -> bool:
        return self._started and (self.sim or self._thread is not None)

    # ---- the python-can side

    def send_can(self, frame: Any) -> int:
        """tx of the driver: hand one frame to python-can (called under the lock)."""
        assert isinstance(self.bus, can.BusABC)
        msg = can.Message(arbitration_id=int(frame.id),
                          is_extended_id=bool(frame.flags & lib.CO_FRAME_EXT),
                          is_remote_frame=bool(frame.flags & lib.CO_FRAME_RTR),
                          dlc=int(frame.len),
                          data=b"" if frame.flags & lib.CO_FRAME_RTR
                          else bytes(frame.data[0:frame.len]))
        try:
            self.bus.send(msg, timeout=0.05)
        except can.CanOperationError:
            return int(lib.CO_ERR_BUSY)
        except can.CanError as exc:
            log.warning("%s: send failed: %s", self.name, exc)
            return int(lib.CO_ERR_ARG)
        return int(lib.CO_OK)

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                self._loop()
            except Exception:  # never let the bus thread die silently
                log.exception("%s: bus thread error", self.name)
                self._stop.wait(0.05)

    def _loop(self) -> None:
        bus = self.bus
        assert isinstance(bus, can.BusABC)
        frame = ffi.new("co_frame_t *")
        while not self._stop.is_set():
            with self._lock:
                due = int(lib.co_node_poll(self.node, self.now_us()))
            self.run_timers(self.now_us())
            self.dispatch()
            timer = self.next_timer_us()
            if timer is not None:
                due = min(due, timer)
            wait = MAX_WAIT_S
            if due != lib.CO_TIME_NEVER:
                wait = min(MAX_WAIT_S, max(0.0, (due - self.now_us()) / 1e6))
            try:
                msg = bus.recv(wait)
            except can.CanError as exc:
                log.warning("%s: receive failed: %s", self.name, exc)
                self._stop.wait(0.05)
                continue
            if msg is None or msg.is_error_frame or msg.is_fd or msg.dlc > 8:
                continue
            frame.id = msg.arbitration_id
            frame.flags = ((lib.CO_FRAME_EXT if msg.is_extended_id else 0)
                           | (lib.CO_FRAME_RTR if msg.is_remote_frame else 0))
            frame.len = msg.dlc
            data = b"" if msg.is_remote_frame else bytes(msg.data)
            ffi.memmove(frame.data, data.ljust(8, b"\0")[:8], 8)
            if self._frame_listeners:
                self.frame_seen(Frame(msg.arbitration_id, data, rtr=msg.is_remote_frame,
                                      extended=msg.is_extended_id,
                                      timestamp=msg.timestamp))
            with self._lock:
                lib.co_node_ingest(self.node, self.now_us(), frame)
            self.dispatch()


# ---------------------------------------------------------------------------------------
# C callbacks -> the owner (under the lock)


def _engine(ctx: Any) -> Engine:
    engine: Engine = ffi.from_handle(ctx)
    return engine


@ffi.def_extern(onerror=lambda *_: log.exception("canola: tx callback failed"))  # type: ignore[untyped-decorator]
def canola_py_tx(ctx: Any, frame: Any) -> int:
    return _engine(ctx).send_can(frame)


def _call(ctx: Any, method: str, *args: Any) -> None:
    engine = _engine(ctx)
    fn = getattr(engine.owner, method, None)
    if fn is not None:
        fn(*args)


@ffi.def_extern()  # type: ignore[untyped-decorator]
def canola_py_on_state(user: Any, state: int) -> None:
    try:
        _call(user, "_on_state", int(state))
    except Exception:
        log.exception("canola: state callback")


@ffi.def_extern()  # type: ignore[untyped-decorator]
def canola_py_on_errctl(user: Any, event: Any) -> None:
    try:
        _call(user, "_on_errctl", int(event.kind), int(event.node_id), int(event.state),
              int(event.previous))
    except Exception:
        log.exception("canola: error control callback")


@ffi.def_extern()  # type: ignore[untyped-decorator]
def canola_py_on_error(user: Any, error: int) -> None:
    try:
        _call(user, "_on_error", int(error))
    except Exception:
        log.exception("canola: node error callback")


@ffi.def_extern()  # type: ignore[untyped-decorator]
def canola_py_on_emcy(user: Any, emcy: Any) -> None:
    try:
        _call(user, "_on_emcy", int(emcy.cob_id), int(emcy.code), int(emcy.reg),
              bytes(emcy.manufacturer))
    except Exception:
        log.exception("canola: EMCY callback")


@ffi.def_extern()  # type: ignore[untyped-decorator]
def canola_py_on_sync(user: Any, counter: int) -> None:
    try:
        _call(user, "_on_sync", int(counter))
    except Exception:
        log.exception("canola: SYNC callback")


@ffi.def_extern()  # type: ignore[untyped-decorator]
def canola_py_on_time(user: Any, tod: Any) -> None:
    try:
        _call(user, "_on_time", int(tod.ms), int(tod.days))
    except Exception:
        log.exception("canola: TIME callback")


@ffi.def_extern()  # type: ignore[untyped-decorator]
def canola_py_on_rpdo(user: Any, rpdo: int) -> None:
    try:
        _call(user, "_on_rpdo", int(rpdo))
    except Exception:
        log.exception("canola: RPDO callback")


@ffi.def_extern()  # type: ignore[untyped-decorator]
def canola_py_written(ctx: Any, entry: Any) -> None:
    try:
        engine = _engine(ctx)
        if not engine.app_writing:
            _call(ctx, "_on_written", int(entry.index), int(entry.sub))
    except Exception:
        log.exception("canola: write callback")


@ffi.def_extern()  # type: ignore[untyped-decorator]
def canola_py_raw_rx(ctx: Any, now_us: int, frame: Any) -> None:
    try:
        engine = _engine(ctx)
        if engine._frame_listeners:
            engine.frame_seen(_frame_in(frame, now_us / 1e6))
    except Exception:
        log.exception("canola: frame callback")
