# SPDX-License-Identifier: Apache-2.0
"""What every link of a python-can bus object shares (:class:`LinkBase`): the canola nodes
on it (their C devs in one ``canola_py_link_t``, which delivers what one sends to the
others at once, in C), their callbacks queued in order and run outside the lock, one
thread at a time. Two kinds: :class:`canola._pylink.Link` takes the frames from python-can
and hands it the frames the nodes send; :class:`canola._native.NativeLink` owns the bus's
socket in C (:class:`canola.bus.native.NativeBus`). :class:`Frame` is a frame as callbacks
see it. Not public."""

from __future__ import annotations

import abc
import logging
import threading
import weakref
from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import can

from canola._c import CData, ffi, lib
from canola.errors import Error

if TYPE_CHECKING:
    from canola._engine import Engine

__all__ = ["NEVER", "Frame", "LinkBase", "deliver_frames"]

log = logging.getLogger("canola")

#: CO_TIME_NEVER: no deadline.
NEVER = int(lib.CO_TIME_NEVER)


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


def deliver_frames(listeners: list[Callable[[Frame], None]], frames: list[Frame]) -> None:
    """Each frame to each listener, in order; one that raises is logged, the rest go on."""
    for frame in frames:
        for fn in listeners:
            try:
                fn(frame)
            except Exception:
                log.exception("canola: a frame callback raised")


class LinkBase(abc.ABC):
    """The canola nodes of one python-can bus object: the C link ``c``, the lock, the
    engines that run (``engines``, in attach order) and those with Python timers
    (``timers``), the callbacks of all of them in order (``events``). A kind that leaves
    out one of the abstract methods fails when it is made, not on its first frame."""

    def __init__(self, bus: can.BusABC, c: CData) -> None:
        self.bus = bus
        self.c = c
        self.events: deque[Callable[[], None]] = deque()
        self.engines: list[Engine] = []
        self.timers: list[Engine] = []
        #: Some engine of the link has frame listeners.
        self.listening = False
        self._dispatching = threading.Lock()
        self._retired: deque[Any] = deque()  # devs of engines that are gone: freed here

    # ---- what each kind does its own way

    lock: Any  #: the nodes' lock (a context manager with acquire/release)

    @abc.abstractmethod
    def now_us(self) -> int:
        raise NotImplementedError

    @abc.abstractmethod
    def in_thread(self) -> bool:
        """True in the link's own thread (a blocking call there would wait for itself)."""
        raise NotImplementedError

    @abc.abstractmethod
    def enter_app(self, node: CData) -> int:
        """An application's call on ``node``: takes the lock and returns the nodes' clock
        (now, but short of their next deadline, which the receiving thread judges once the
        frames received before it count), ``node`` polled at it."""
        raise NotImplementedError

    @abc.abstractmethod
    def leave_app(self, now_us: int) -> None:
        """The call's end: what the nodes sent delivered and sent, the lock released."""
        raise NotImplementedError

    @abc.abstractmethod
    def wait(self, engine: Engine, done: Callable[[], bool], end: float | None,
             xfer: CData | None = None) -> bool:
        """Until ``done()`` (or transfer ``xfer`` ended) or time.monotonic() passes ``end``:
        this thread receives meanwhile when nobody else does. False at ``end``. Raises
        Error when ``engine`` is stopped or the bus fails meanwhile."""
        raise NotImplementedError

    @abc.abstractmethod
    def _start_thread(self) -> None:
        raise NotImplementedError

    @abc.abstractmethod
    def _stop_thread(self, engine: Engine, timeout: float) -> None:
        """The thread stops once no engine is left (a name says who is left else)."""
        raise NotImplementedError

    def listen(self, cob_id: int | None) -> None:  # noqa: B027 (a default: nothing to do)
        """Frames on ``cob_id`` (None: every frame) are wanted by a frame listener."""

    def timers_changed(self) -> None:  # noqa: B027 (a default: nothing to do)
        """A Python timer was added: the receiving thread runs it in time."""

    # ---- nodes

    def free_retired(self) -> None:
        """Under the lock: free the devs of engines that are gone."""
        while self._retired:
            lib.canola_py_dev_free(self._retired.popleft())

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
        """``engine`` receives and is polled; the link's thread runs while one is."""
        with self.lock:
            if engine not in self.engines:
                self.engines.append(engine)
                lib.canola_py_dev_set_active(engine.dev, True)
        self._start_thread()

    def deactivate(self, engine: Engine, timeout: float) -> None:
        """``engine`` is left alone; the link's thread stops with the last one (waits up to
        ``timeout`` s unless called from it). The callbacks queued before run before it
        returns: what a node did before it stopped (an EMCY it sent) is still told."""
        with self.lock:
            if engine in self.engines:
                self.engines.remove(engine)
                lib.canola_py_dev_set_active(engine.dev, False)
        self._stop_thread(engine, timeout)
        self.dispatch()

    def thread_name(self) -> str:
        return "canola-" + "+".join(e.name.removeprefix("canola-") for e in self.engines)

    # ---- callbacks, outside the lock

    def later(self, fn: Callable[[], None]) -> None:
        """Queue ``fn`` to run after the current C call, outside the lock, in order."""
        self.events.append(fn)

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
