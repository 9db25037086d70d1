# SPDX-License-Identifier: Apache-2.0
"""The C nodes and what drives them: a simulated bus (virtual time) or a python-can bus
(real time). Shared by :class:`canola.Device` and :class:`canola.Master`; not public.

python-can: one link per bus object drives every canola node on it, with one lock and one
receiving thread (not one per node). A frame one node sends reaches the other canola nodes
of the same bus object at once, in C (``port/python/py_link.c``), in the thread that caused
it: an SDO request of a :class:`~canola.Master` to a :class:`~canola.Device` of the same
bus object is answered before the call that sent it returns, with no thread hand-off. Two
kinds of link (:class:`canola._linkbase.LinkBase`): :class:`canola._pylink.Link` for a bus
object canola does not own (frames through python-can's ``recv``/``send``, in Python), and
:class:`canola._native.NativeLink` for a :class:`canola.bus.native.NativeBus` (SocketCAN
and socketcand opened by URL), whose socket C reads and writes with the GIL released.

A thread that waits for an answer (a blocking SDO transfer, an LSS request, a boot, a
program download) receives it itself (``link.wait``) while the link's thread stands aside,
so the answer needs no hand-off between threads.

Callbacks of the C nodes only record events; the application's callbacks run afterwards,
never under the lock, in the order the events happened, by the thread that released the
lock (the link's thread, a thread that waits for an answer, or the application's thread
whose call made the nodes work), one thread at a time; on a SimBus inside
:meth:`SimBus.run_until`. They may call any method of the nodes. They must not block on a
node that only the link's thread can answer: a blocking SDO call run by the link's thread
raises :class:`~canola.errors.Error`, and so does one to the node a waiting thread is
waiting for.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
import weakref
from collections import deque
from collections.abc import Callable, Iterator
from typing import Any, Protocol, TypeVar

import can

from canola._c import check as _check
from canola._c import ffi, lib
from canola._linkbase import Frame, LinkBase
from canola._pylink import MAX_WAIT_S, Link
from canola.core import Od, SimBus
from canola.errors import Error

__all__ = ["MAX_WAIT_S", "Bus", "Engine", "Frame", "Link", "NodeEvents", "link_of"]

log = logging.getLogger("canola")

Bus = SimBus | can.BusABC
T = TypeVar("T")


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


#: id(bus object) -> its link, while the link lives (its nodes hold it).
_LINKS: weakref.WeakValueDictionary[int, LinkBase] = weakref.WeakValueDictionary()
_LINKS_LOCK = threading.Lock()


def link_of(bus: can.BusABC) -> LinkBase:
    """The link of ``bus`` (made on first use; it holds the bus while it lives): a
    NativeLink when canola owns the bus's socket, else a python-can Link."""
    with _LINKS_LOCK:
        link = _LINKS.get(id(bus))
        if link is None or link.bus is not bus:
            native = getattr(bus, "native_link", None)
            link = _LINKS[id(bus)] = native() if native is not None else Link(bus)
        return link


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
        self.link = link_of(bus) if isinstance(bus, can.BusABC) else None
        self.lock: Any = self.link.lock if self.link is not None else threading.Lock()
        self._events: deque[Callable[[], None]] = deque()  # on a SimBus
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
        now = link.enter_app(self.node)
        try:
            yield self.node
        finally:
            link.leave_app(now)
        if link.events:
            link.dispatch()

    def call(self, fn: Callable[[Any], T]) -> T:
        """``fn(node)`` as inside :meth:`locked` (the short way, for the hot paths)."""
        link = self.link
        if link is None:
            with self.locked() as node:
                return fn(node)
        now = link.enter_app(self.node)
        try:
            result = fn(self.node)
        finally:
            link.leave_app(now)
        if link.events:
            link.dispatch()
        return result

    def later(self, fn: Callable[[], None]) -> None:
        """Run ``fn`` after the current C call, outside the lock (see the module doc)."""
        if self.link is not None:
            self.link.later(fn)
        else:
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
        if self.link is not None:
            if self not in self.link.timers:
                self.link.timers = [*self.link.timers, self]
            self.link.timers_changed()
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
            self.link.listen(None)

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
