# SPDX-License-Identifier: Apache-2.0
"""The C nodes and what drives them: a simulated bus (virtual time) or a python-can bus
(real time). Shared by :class:`canola.Device` and :class:`canola.Master`; not public.

python-can: one :class:`Link` per bus object drives every canola node on it, with one
lock and one thread (not one per node). A frame one node sends reaches the other canola
nodes of the same bus object at once, in C (``port/python/py_link.c``), in the thread
that caused it: an SDO request of a :class:`~canola.Master` to a :class:`~canola.Device`
of the same bus object is answered before the call that sent it returns, with no thread
hand-off. Python hands the same frames to python-can, for every other listener.

Receiving: one thread at a time holds the link's receive token (:attr:`Link.rx`). The bus
thread does, waiting for frames up to the nodes' next deadline, capped at
:data:`MAX_WAIT_S` so that deadlines that application calls move earlier are met within
that cap. A thread that waits for an answer (a blocking SDO transfer, an LSS request, a
boot, a program download) receives it itself (:meth:`Link.wait`) while the bus thread
stands aside, so the answer needs no hand-off between threads. Whoever receives takes
every frame python-can holds, ingests each at its bus time and only then polls the timers
(:meth:`Link.pump`): a time-out is judged after the frames that arrived before it.

Callbacks of the C nodes only record events; the application's callbacks run afterwards,
never under the lock, in the order the events happened, by the thread that released the
lock (the bus thread, a thread that waits for an answer, or the application's thread whose
call made the nodes work), one thread at a time; on a SimBus inside
:meth:`SimBus.run_until`. They may call any method of the nodes. They must not block on a
node that only the bus thread can answer: a blocking SDO call run by the bus thread raises
:class:`~canola.errors.Error`, and so does one to the node a waiting thread is waiting for.
"""

from __future__ import annotations

import contextlib
import logging
import struct
import threading
import time
import weakref
from collections import deque
from collections.abc import Callable, Iterator
from typing import Any, Protocol, TypeVar

import can

from canola._c import check as _check
from canola._c import ffi, lib
from canola.core import Od, SimBus
from canola.errors import Error

__all__ = ["MAX_WAIT_S", "Bus", "Engine", "Frame", "Link", "NodeEvents"]

log = logging.getLogger("canola")

#: Longest the bus thread waits for a frame before polling the node again (seconds).
MAX_WAIT_S = 0.01

Bus = SimBus | can.BusABC
T = TypeVar("T")


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
    """A periodic Python job of an engine: ``live`` until removed; ``running_in``: the
    threads running ``fn`` now (one each; a run may nest in another on a SimBus)."""

    __slots__ = ("due_us", "fn", "live", "period_us", "running_in")

    def __init__(self, due_us: int, period_us: int, fn: Callable[[], None]) -> None:
        self.due_us = due_us
        self.period_us = period_us
        self.fn = fn
        self.live = True
        self.running_in: list[int] = []


def _frame_in(frame: Any, timestamp: float) -> Frame:
    return Frame(int(frame.id), bytes(frame.data[0:frame.len]),
                 rtr=bool(frame.flags & lib.CO_FRAME_RTR),
                 extended=bool(frame.flags & lib.CO_FRAME_EXT), timestamp=timestamp)


_FRAME = struct.Struct("<IBB8s2x")  # co_frame_t: id, flags, len, data (and padding)
assert ffi.sizeof("co_frame_t") == _FRAME.size and ffi.offsetof("co_frame_t", "data") == 6
_EXT = int(lib.CO_FRAME_EXT)
_RTR = int(lib.CO_FRAME_RTR)
_NEVER = int(lib.CO_TIME_NEVER)


def _free_link(raw: Any, retired: deque[Any]) -> None:
    while retired:
        lib.canola_py_dev_free(retired.popleft())
    lib.canola_py_link_free(raw)


#: id(bus object) -> its link, while the link lives (its nodes hold it).
_LINKS: weakref.WeakValueDictionary[int, Link] = weakref.WeakValueDictionary()
_LINKS_LOCK = threading.Lock()


class Link:
    """One python-can bus object and the canola nodes on it (see the module doc): the C
    link, the lock, the bus thread, the events of every node on it in order."""

    @classmethod
    def of(cls, bus: can.BusABC) -> Link:
        """The link of ``bus`` (made on first use; it holds the bus while it lives)."""
        with _LINKS_LOCK:
            link = _LINKS.get(id(bus))
            if link is None or link.bus is not bus:
                link = _LINKS[id(bus)] = cls(bus)
            return link

    def __init__(self, bus: can.BusABC) -> None:
        raw = lib.canola_py_link_new()
        if raw == ffi.NULL:
            raise Error("out of memory for a python-can link")
        self.bus = bus
        self.c = raw
        self.lock = threading.Lock()
        self.events: deque[Callable[[], None]] = deque()
        self.engines: list[Engine] = []  # the active ones (running), in attach order
        self.timers: list[Engine] = []  # engines with Python timers (running or not)
        self._dispatching = threading.Lock()
        self._retired: deque[Any] = deque()  # devs of engines that are gone: freed here
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
        #: Some engine of the link has frame listeners (pump hands them the frames).
        self.listening = False
        weakref.finalize(self, _free_link, raw, self._retired)

    def now_us(self) -> int:
        return (time.monotonic_ns() - self._t0) // 1000

    # ---- nodes

    def new_dev(self, engine: Engine, make: Callable[[Any], Any]) -> Any:
        """``make(c_link)``: a dev attached to this link (NULL when refused), under the
        lock; a dev made is freed by the link once ``engine`` is gone."""
        with self.lock:
            dev = make(self.c)
        if dev != ffi.NULL:
            weakref.finalize(engine, self._retired.append, dev)
        elif int(self.c.dev_count) >= lib.CANOLA_PY_LINK_DEVS:
            raise Error(f"a python-can bus object holds at most {lib.CANOLA_PY_LINK_DEVS} "
                        "canola nodes")
        return dev

    def activate(self, engine: Engine) -> None:
        """``engine`` receives and is polled; the bus thread runs while one is."""
        with self.lock:
            if engine not in self.engines:
                self.engines.append(engine)
                lib.canola_py_dev_set_active(engine.dev, True)
            self._name_thread()
        if self._thread is None:
            self._stop = threading.Event()
            self._thread = threading.Thread(target=self._run, args=(self._stop,),
                                            name=self._thread_name(), daemon=True)
            self._thread.start()

    def deactivate(self, engine: Engine, timeout: float) -> None:
        """``engine`` is left alone; the bus thread stops with the last one (waits up to
        ``timeout`` s unless called from it)."""
        with self.lock:
            if engine in self.engines:
                self.engines.remove(engine)
                lib.canola_py_dev_set_active(engine.dev, False)
            self._name_thread()
            thread = self._thread if not self.engines else None
            if thread is not None:
                self._stop.set()
                self._thread = None
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout)
            if thread.is_alive():
                raise Error(f"{engine.name}: the bus thread did not stop within {timeout} s")

    def _thread_name(self) -> str:
        return "canola-" + "+".join(e.name.removeprefix("canola-") for e in self.engines)

    def _name_thread(self) -> None:
        if self._thread is not None and self.engines:
            self._thread.name = self._thread_name()

    def in_thread(self) -> bool:
        return self._thread is not None and threading.current_thread() is self._thread

    # ---- under the lock

    def enter(self) -> int:
        """First thing under the lock: free the devs of engines gone; the time now."""
        while self._retired:
            lib.canola_py_dev_free(self._retired.popleft())
        return self.now_us()

    def app_clock(self) -> int:
        """First thing under the lock for an application's call: the time now, but short of
        the nodes' next deadline, which the receiving thread judges once the frames received
        before it count (:meth:`pump`), never an application's call."""
        now = self.enter()
        due = int(self.c.due_us)
        if now >= due != _NEVER:
            now = max(self._clock_us, due - 1)
        self._clock_us = now
        return now

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

    # ---- callbacks, outside the lock

    def dispatch(self) -> None:
        """Run the queued callbacks in order, one thread at a time: another thread that
        is running them takes these too."""
        events = self.events
        while events:
            if not self._dispatching.acquire(blocking=False):
                return
            try:
                while events:
                    fn = events.popleft()
                    try:
                        fn()
                    except Exception:
                        log.exception("canola: a callback raised")
            finally:
                self._dispatching.release()

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
            while self._retired:
                lib.canola_py_dev_free(self._retired.popleft())
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
            log.warning("%s: receive failed: %s", self._thread_name(), exc)
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

    def wait(self, engine: Engine, done: Callable[[], bool], end: float | None) -> bool:
        """Until ``done()`` or time.monotonic() passes ``end``: this thread receives and runs
        the link while it waits (the bus thread stands aside: no hand-off between threads
        for an answer), or waits for the thread that receives now to let go. False at
        ``end``. Raises Error when ``engine`` is stopped meanwhile."""
        me = object()
        self.waiting.add(me)
        rx, c = self.rx, self.c
        try:
            while not done():
                left = 0.05 if end is None else min(0.05, end - time.monotonic())
                if left <= 0:
                    return False
                if not engine._active and not engine.sim:
                    raise Error(f"{engine.name} was stopped while a call waited for it")
                if not rx.acquire(True, left):
                    continue
                try:
                    if done():
                        break
                    due = c.due_us
                    self.pump(left if due == _NEVER else
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
        if due == _NEVER:
            return cap_s
        return min(cap_s, max(0.0, (due - self.now_us()) / 1e6))

    def _run(self, stop: threading.Event) -> None:
        while not stop.is_set():
            try:
                self._loop(stop)
            except Exception:  # never let the bus thread die silently
                log.exception("%s: bus thread error", self._thread_name())
                stop.wait(0.05)

    def _loop(self, stop: threading.Event) -> None:
        rx, due = self.rx, _NEVER
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


#: Frames python-can refused that wait for the next flush, at most.
_UNSENT_MAX = 4096

#: How long the bus thread stays aside after an application thread waited (a next transfer
#: then finds the receive token free); frames wait in python-can meanwhile.
_ASIDE_NS = int(MAX_WAIT_S * 1e9)

#: Frames taken from python-can in one go before the nodes are polled, at most.
_DRAIN_MAX = 256


class NodeEvents(Protocol):
    """What an engine's owner hears from its C node, called under the lock (queue the work
    for after it with :meth:`Engine.later`). :class:`canola._nodebase.NodeBase` is one."""

    def _on_state(self, state: int) -> None: ...
    def _on_reset(self, what: int) -> None: ...
    def _on_errctl(self, kind: int, node_id: int, state: int, previous: int) -> None: ...
    def _on_error(self, error: int) -> None: ...
    def _on_emcy(self, cob_id: int, code: int, reg: int, manufacturer: bytes) -> None: ...
    def _on_sync(self, counter: int) -> None: ...
    def _on_time(self, ms: int, days: int) -> None: ...
    def _on_rpdo(self, rpdo: int) -> None: ...
    def _on_written(self, index: int, sub: int, by_app: bool) -> None: ...


class Engine:
    """A C node (``canola_py_dev_t``) on ``bus``; ``owner`` hears the C node's events
    (:class:`NodeEvents`)."""

    def __init__(self, bus: Bus, od: Od, node_id: int, owner: NodeEvents, *, sdo_timeout_ms: int,
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
        self.link = Link.of(bus) if isinstance(bus, can.BusABC) else None
        self.lock = self.link.lock if self.link is not None else threading.Lock()
        self._events = self.link.events if self.link is not None else deque()
        self._handle = ffi.new_handle(self)
        self.frame_listeners: list[Callable[[Frame], None]] = []
        self.sent_listeners: list[Callable[[Frame], None]] = []
        err = ffi.new("co_err_t *")
        store = ffi.new("char[]", store_dir.encode()) if store_dir is not None else ffi.NULL

        def make(link: Any) -> Any:
            return lib.canola_py_dev_new(bus._bus if isinstance(bus, SimBus) else ffi.NULL,
                                         link, od.entries, od.count, node_id, sdo_timeout_ms,
                                         store, raw_frames, self._handle, err)

        raw = self.link.new_dev(self, make) if self.link is not None else make(ffi.NULL)
        if raw == ffi.NULL:
            if store_dir is not None:
                raise Error(f"parameter storage folder {store_dir!r} cannot be used")
            _check(int(err[0]), "create the node")
        self.dev = raw
        if isinstance(bus, SimBus):
            # its ports stay attached to the bus: the dev is freed with the bus
            bus._nodes.append((ffi.gc(raw, lib.canola_py_dev_free), od))
            bus._nodes.append((self._handle, self))
            bus._engines.append(self)
        if int(err[0]) != lib.CO_OK:
            if store_dir is not None and int(err[0]) == lib.CO_ERR_ARG:
                raise Error(f"parameter storage folder {store_dir!r} cannot be used")
            _check(int(err[0]), "co_node_init")
        self.node = lib.canola_py_dev_node(raw)
        lib.canola_py_dev_set_quiet(raw, quiet)  # before the start: its boot-up stays off
        self._timers: list[_Timer] = []
        self._timer_runs = threading.Condition()  # guards live / running_in of the timers
        self._started = False
        self._active = False

    # ---- time and locking

    def now_us(self) -> int:
        if isinstance(self.bus, SimBus):
            return self.bus.now_us
        assert self.link is not None
        return self.link.now_us()

    @contextlib.contextmanager
    def locked(self) -> Iterator[Any]:
        """The C node, under the lock, its clock brought to now first. The frames sent
        inside reach the other nodes afterwards: on a SimBus at the same virtual instant,
        on python-can's link at once (and python-can). The callbacks run after the lock."""
        if isinstance(self.bus, SimBus):
            with self.lock:
                yield self.node
                lib.canola_py_dev_touch(self.dev)
            self.bus.run_until(self.bus.now_us)
            return
        link = self.link
        assert link is not None
        with link.lock:
            now = link.app_clock()
            lib.co_node_poll(self.node, now)
            try:
                yield self.node
            finally:
                link.flush(now)
        if link.events:
            link.dispatch()

    def call(self, fn: Callable[[Any], T]) -> T:
        """``fn(node)`` as inside :meth:`locked` (the short way, for the hot paths)."""
        link = self.link
        if link is None:
            with self.locked() as node:
                return fn(node)
        with link.lock:
            now = link.app_clock()
            lib.co_node_poll(self.node, now)
            try:
                result = fn(self.node)
            finally:
                link.flush(now)
        if link.events:
            link.dispatch()
        return result

    def later(self, fn: Callable[[], None]) -> None:
        """Run ``fn`` after the current C call, outside the lock (see the module doc)."""
        self._events.append(fn)

    def dispatch(self) -> None:
        if self.link is not None:
            self.link.dispatch()
            return
        while self._events:
            fn = self._events.popleft()
            try:
                fn()
            except Exception:
                log.exception("%s: a callback raised", self.name)

    # ---- periodic work of the Python side (e.g. TIME production), in the node's time

    def add_timer(self, period_us: int, fn: Callable[[], None]) -> _Timer:
        """Run ``fn`` every ``period_us`` (first one period from now), like a callback
        (queued when due, run after the lock; a run queued but not begun when the timer
        is removed is skipped)."""
        timer = _Timer(self.now_us() + period_us, period_us, fn)
        self._timers.append(timer)
        if self.link is not None and self not in self.link.timers:
            self.link.timers = [*self.link.timers, self]
        return timer

    def remove_timer(self, timer: _Timer) -> None:
        """Stop ``timer``: when this returns, ``fn`` runs no more and a run begun in
        another thread has ended (so have the frames it sent). From ``fn`` itself it
        returns at once. Not under the lock: a run in another thread may need it."""
        with self._timer_runs:
            timer.live = False
            if timer in self._timers:
                self._timers.remove(timer)
            me = threading.get_ident()
            self._timer_runs.wait_for(lambda: all(t == me for t in timer.running_in))

    def _run_timer(self, timer: _Timer) -> None:
        runs = self._timer_runs
        with runs:
            if not timer.live:
                return
            me = threading.get_ident()
            timer.running_in.append(me)
        try:
            timer.fn()
        finally:
            with runs:
                timer.running_in.remove(me)
                runs.notify_all()

    def next_timer_us(self) -> int | None:
        if not self._active and not self.sim:
            return None
        return min((t.due_us for t in self._timers), default=None)

    def run_timers(self, now_us: int) -> None:
        if not self._active and not self.sim:
            return
        for timer in list(self._timers):
            if timer.due_us <= now_us:
                timer.due_us += timer.period_us
                if timer.due_us <= now_us:  # fell behind (a slow machine): skip, no burst
                    timer.due_us = now_us + timer.period_us
                self.later(lambda timer=timer: self._run_timer(timer))  # type: ignore[misc]

    def in_bus_thread(self) -> bool:
        return self.link is not None and self.link.in_thread()

    def check_may_block(self) -> None:
        if self.in_bus_thread():
            raise Error("a blocking call from a callback would wait for itself: "
                        "use the asyncio form or do it from another thread")

    def add_frame_listener(self, fn: Callable[[Frame], None]) -> None:
        """``fn(Frame)`` for every frame other nodes send (outside the lock, in order)."""
        self.frame_listeners.append(fn)
        if self.link is not None:
            with self.lock:
                lib.canola_py_dev_set_raw(self.dev, True)
            self.link.listening = True

    def frame_seen(self, frame: Frame) -> None:
        for fn in self.frame_listeners:
            self.later(lambda fn=fn: fn(frame))  # type: ignore[misc]

    def add_sent_listener(self, fn: Callable[[Frame], None]) -> None:
        """``fn(Frame)`` for every frame this node puts on the bus (outside the lock, in
        the order sent)."""
        with self.lock:
            self.sent_listeners.append(fn)
            lib.canola_py_dev_set_sent(self.dev, True)

    def frame_sent(self, frame: Frame) -> None:
        for fn in self.sent_listeners:
            self.later(lambda fn=fn: fn(frame))  # type: ignore[misc]

    # ---- life cycle

    def start(self) -> None:
        if self.link is not None:
            self.link.activate(self)  # it receives its own boot-up's answers
            self._active = True
        if not self._started:
            with self.locked() as node:
                _check(lib.co_node_start(node, self.now_us()), "co_node_start")
            self._started = True

    def stop(self, timeout: float = 2.0) -> None:
        if self.link is None or not self._active:
            return
        self._active = False
        self.link.deactivate(self, timeout)

    @property
    def running(self) -> bool:
        return self._started and (self.sim or self._active)



# ---------------------------------------------------------------------------------------
# C callbacks -> the owner (under the lock)


def _logged(what: str) -> Callable[..., None]:
    """A callback's onerror: the exception logged, never into C."""
    def onerror(kind: Any, exc: Any, tb: Any) -> None:
        log.error("canola: %s", what, exc_info=(kind, exc, tb))
    return onerror


def _engine(ctx: Any) -> Engine:
    engine: Engine = ffi.from_handle(ctx)
    return engine


def _owner(ctx: Any) -> NodeEvents:
    return _engine(ctx).owner


@ffi.def_extern(onerror=_logged("state callback"))
def canola_py_on_state(user: Any, state: int) -> None:
    _owner(user)._on_state(int(state))


@ffi.def_extern(onerror=_logged("reset callback"))
def canola_py_on_reset(user: Any, what: int) -> None:
    _owner(user)._on_reset(int(what))


@ffi.def_extern(onerror=_logged("error control callback"))
def canola_py_on_errctl(user: Any, event: Any) -> None:
    _owner(user)._on_errctl(int(event.kind), int(event.node_id), int(event.state),
                            int(event.previous))


@ffi.def_extern(onerror=_logged("node error callback"))
def canola_py_on_error(user: Any, error: int) -> None:
    _owner(user)._on_error(int(error))


@ffi.def_extern(onerror=_logged("EMCY callback"))
def canola_py_on_emcy(user: Any, emcy: Any) -> None:
    _owner(user)._on_emcy(int(emcy.cob_id), int(emcy.code), int(emcy.reg),
                          bytes(emcy.manufacturer))


@ffi.def_extern(onerror=_logged("SYNC callback"))
def canola_py_on_sync(user: Any, counter: int) -> None:
    _owner(user)._on_sync(int(counter))


@ffi.def_extern(onerror=_logged("TIME callback"))
def canola_py_on_time(user: Any, tod: Any) -> None:
    _owner(user)._on_time(int(tod.ms), int(tod.days))


@ffi.def_extern(onerror=_logged("RPDO callback"))
def canola_py_on_rpdo(user: Any, rpdo: int) -> None:
    _owner(user)._on_rpdo(int(rpdo))


@ffi.def_extern(onerror=_logged("write callback"))
def canola_py_written(user: Any, entry: Any, origin: int) -> None:
    _owner(user)._on_written(int(entry.index), int(entry.sub),
                             origin == lib.CANOLA_PY_BY_APP)


@ffi.def_extern()
def canola_py_sent(ctx: Any, frame: Any) -> None:
    try:
        engine = _engine(ctx)
        engine.frame_sent(_frame_in(frame, engine.bus.now_us / 1e6
                                    if isinstance(engine.bus, SimBus) else time.time()))
    except Exception:
        log.exception("canola: sent-frame callback")


@ffi.def_extern()
def canola_py_raw_rx(ctx: Any, now_us: int, frame: Any) -> None:
    try:
        engine = _engine(ctx)
        if engine.frame_listeners:  # a frame of another canola node: python-can's clock
            engine.frame_seen(_frame_in(frame, now_us / 1e6 if engine.sim else time.time()))
    except Exception:
        log.exception("canola: frame callback")
