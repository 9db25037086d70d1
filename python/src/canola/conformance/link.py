# SPDX-License-Identifier: Apache-2.0
"""Raw frames to and from the node under test, through a :class:`canola.Master`.

:class:`Link` sends frames (``Master.send``) and sees every frame of the other nodes
(``Master.on_frame``). It keeps the latest frames of the current check (at most
:data:`FRAMES_KEPT`), to wait for one (:meth:`Link.wait_frame`, :meth:`Link.wait_count`) or
look back (:meth:`Link.frames_since`), and a bounded trace of the latest frames of the node
and the tester (:meth:`Link.trace`), which a failure quotes with the bus's timestamps.

Time is the bus's: virtual on a :class:`canola.core.SimBus` (waiting runs the simulated
bus, so every wait is exact and costs no wall time), the monotonic clock on python-can
(waiting blocks until the bus thread delivered a frame or the time is up).

Memory stays bounded whatever the bus carries: a flood keeps at most :data:`FRAMES_KEPT`
frames, every wait looks at each frame once (:class:`Watch`), and a wait ends by its time
limit however busy the tester is (a stall of its own process extends it once, at most).
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from canola import Master
from canola.conformance.starvation import Starvation, host_cpu_wait
from canola.core import SimBus
from canola.decode import Decoder
from canola.master import Frame

__all__ = ["FRAMES_KEPT", "TRACE_FRAMES", "Link", "Seen", "Since", "Watch"]

#: Frames a trace keeps (both directions).
TRACE_FRAMES = 40
#: Frames kept for waiting and looking back, at most (a flood drops the oldest).
FRAMES_KEPT = 20_000
#: A stall of the tester's own process longer than this is remembered (:meth:`Link.stalled`).
STALL_NOTED_S = 0.02

_SIM_STEP_US = 1000
#: Longest wait for a frame between two looks at the clock (python-can).
_WAIT_SLICE_S = 0.05
#: python-can buses that cannot send a remote frame (the socketcand client sends every
#: frame as data).
_NO_REMOTE_FRAMES = ("SocketCanDaemonBus",)
Match = Callable[[Frame], bool]


@dataclass(frozen=True, slots=True)
class Since:
    """A point to measure starvation from (:meth:`Link.since`, :meth:`Link.starved`): link
    time and the host's CPU wait then (None: not counted)."""

    t: float
    cpu_wait: float | None


@dataclass(frozen=True, slots=True)
class Seen:
    """A frame on the bus: ``sent`` by the tester or received, read by the tester at ``t``
    (link time, s: when it went out, for a sent one); ``pos`` is its place among the frames
    of the check (the mark just after it is ``pos + 1``)."""

    t: float
    frame: Frame
    sent: bool
    pos: int


class Watch:
    """The frames after a mark that ``match`` (received ones, or sent ones with ``sent``),
    gathered as they come: each :meth:`update` looks only at the frames that came since
    the last one, so a wait costs one look per frame however long the check runs."""

    def __init__(self, link: Link, match: Match | None, since: int, *,
                 sent: bool = False) -> None:
        self.link = link
        self.match = match
        self.sent = sent
        self.cursor = since
        self.found: list[Seen] = []

    def update(self) -> list[Seen]:
        """The matching frames so far."""
        new, self.cursor = self.link._after(self.cursor)
        self.found += [s for s in new if s.sent == self.sent
                       and (self.match is None or self.match(s.frame))]
        return self.found


class Link:
    """The tester's frames on ``master``'s bus; ``node_id``: the node under test (its
    frames, and those on the COB-IDs in :attr:`cobs`, make the trace)."""

    def __init__(self, master: Master, node_id: int | None = None) -> None:
        self.master = master
        self.node_id = node_id
        #: COB-IDs of the node beyond its predefined ones (a PDO's, EMCY's, SYNC's).
        self.cobs: set[int] = set()
        bus = master.bus
        self.sim: SimBus | None = bus if isinstance(bus, SimBus) else None
        #: False when the bus cannot send remote frames (RTR).
        self.remote_frames = type(bus).__name__ not in _NO_REMOTE_FRAMES
        self._cond = threading.Condition()
        self._frames: list[Seen] = []
        self._base = 0  # the position of _frames[0]
        self._trace: deque[Seen] = deque(maxlen=TRACE_FRAMES)
        self._stalls: deque[tuple[float, float]] = deque(maxlen=256)
        #: Passed over in the trace: frames of other nodes.
        self.others = 0
        # the bus's clock minus the link's, the least seen: a received frame's bus time
        self._offset: float | None = None
        self._t0 = self.now()
        master.on_frame(self._received)

    # ---- time

    def now(self) -> float:
        """Seconds on the bus's clock."""
        if self.sim is not None:
            return self.sim.now_us / 1e6
        return time.monotonic()

    def wait(self, seconds: float) -> None:
        """Let ``seconds`` pass (frames keep arriving)."""
        self.wait_until(lambda: False, seconds)

    def wait_until(self, done: Callable[[], bool], timeout: float) -> bool:
        """Wait until ``done()`` is true (checked whenever a frame arrives) or ``timeout``
        seconds have passed; ``done()``'s last answer. On the wall clock a stall of the
        tester's own process (a slice of the wait that overran) extends the wait by the
        overrun, so that the frames the bus kept meanwhile are read before the time is up;
        by ``timeout`` once more at most, so that a wait always ends."""
        end = self.now() + timeout
        if self.sim is not None:
            while not done():
                if self.now() >= end:
                    return False
                step = min(_SIM_STEP_US, max(1, round((end - self.now()) * 1e6)))
                self.sim.run_for(step)
            return True
        granted = 0.0
        with self._cond:
            while not done():
                left = end - self.now()
                if left <= 0:
                    return done()
                slice_s = min(left, _WAIT_SLICE_S)
                before = self.now()
                self._cond.wait(slice_s)
                stall = self.now() - before - slice_s
                if stall > 0:
                    self.note_stall(stall)
                    extend = min(stall, timeout - granted)
                    granted += extend
                    end += extend
            return True

    def note_stall(self, seconds: float) -> None:
        """The tester's own process did not run for ``seconds`` (a starved host)."""
        if seconds > STALL_NOTED_S:
            self._stalls.append((self.now(), seconds))

    def stalled(self, since: float) -> float:
        """The longest stall of the tester's own process since ``since`` (link time), in
        seconds; 0 when it ran on time."""
        return max((s for t, s in self._stalls if t >= since), default=0.0)

    def since(self) -> Since:
        """Now, to measure starvation from: the host's counts only on a real bus."""
        return Since(self.now(), None if self.sim is not None else host_cpu_wait())

    def starved(self, since: Since) -> Starvation:
        """How starved the tester and its host were since ``since``."""
        cpu_wait = 0.0
        if since.cpu_wait is not None:
            now = host_cpu_wait()
            cpu_wait = max(0.0, now - since.cpu_wait) if now is not None else 0.0
        return Starvation(self.stalled(since.t), cpu_wait)

    # ---- frames

    def _append(self, seen: Seen) -> None:  # under the lock
        self._frames.append(seen)
        if len(self._frames) > 2 * FRAMES_KEPT:  # amortised: half the list at a time
            drop = len(self._frames) - FRAMES_KEPT
            del self._frames[:drop]
            self._base += drop
        if seen.sent or self._ours(seen.frame):
            self._trace.append(seen)
        else:
            self.others += 1

    def _ours(self, frame: Frame) -> bool:
        """A frame of the node under test: of its predefined COB-IDs, or of :attr:`cobs`."""
        cob = frame.can_id
        if self.node_id is None or cob in self.cobs:
            return True
        return 0x80 < cob < 0x800 and cob & 0x7F == self.node_id

    def _received(self, frame: Frame) -> None:
        with self._cond:
            now = self.now()
            if frame.timestamp:
                offset = frame.timestamp - now
                if self._offset is None or offset > self._offset:
                    self._offset = offset  # the frame that came soonest after the bus
            self._append(Seen(now - self._t0, frame, False, self._base + len(self._frames)))
            self._cond.notify_all()

    def send(self, can_id: int, data: bytes = b"", *, rtr: bool = False) -> None:
        """Send one frame (recorded in the trace first)."""
        with self._cond:
            self._append(Seen(self.now() - self._t0, Frame(can_id, bytes(data), rtr=rtr), True,
                              self._base + len(self._frames)))
        self.master.send(can_id, data, rtr=rtr)

    def mark(self) -> int:
        """A position in the frames of this check, for :meth:`wait_frame` and
        :meth:`frames_since`."""
        with self._cond:
            return self._base + len(self._frames)

    def _after(self, mark: int) -> tuple[list[Seen], int]:
        """The frames kept after ``mark`` (those a flood dropped are gone), and the mark
        after them."""
        with self._cond:
            return self._frames[max(0, mark - self._base):], self._base + len(self._frames)

    def frames_since(self, mark: int, match: Match | None = None, *,
                     sent: bool = False) -> list[Seen]:
        """The received (or, with ``sent``, the sent) frames after ``mark`` that ``match``."""
        return Watch(self, match, mark, sent=sent).update()

    def watch(self, match: Match | None, since: int) -> Watch:
        """A :class:`Watch` of the received frames after ``since`` that ``match``."""
        return Watch(self, match, since)

    def wait_count(self, match: Match, count: int, timeout: float, since: int) -> list[Seen]:
        """The received frames after ``since`` that ``match``, waiting up to ``timeout``
        seconds until there are ``count``; fewer when the time was up first."""
        watch = self.watch(match, since)
        self.wait_until(lambda: len(watch.update()) >= count, timeout)
        return watch.update()

    def wait_frame(self, match: Match, timeout: float, since: int) -> Seen | None:
        """The first received frame after ``since`` that ``match``es, waiting up to
        ``timeout`` seconds for it; None when none came."""
        found = self.wait_count(match, 1, timeout, since)
        return found[0] if found else None

    def forget(self) -> None:
        """Drop the frames kept for waiting (a new check begins); the trace stays."""
        with self._cond:
            self._base += len(self._frames)
            self._frames.clear()

    def bus_time(self, seen: Seen) -> float:
        """When ``seen`` was on the bus, in link time: a received frame's bus timestamp (on
        the link's clock), a sent frame's time of sending."""
        stamp = seen.frame.timestamp
        if seen.sent or not stamp or self._offset is None:
            return seen.t
        return stamp - self._offset - self._t0

    def trace(self, last: int = TRACE_FRAMES) -> list[str]:
        """The latest frames of the node and the tester as text lines, in bus order, each at
        its bus time and with its CANopen meaning:
        ``+1.2345 s  -> 605  40 00 10 00 00 00 00 00   SDO ...``. A run of one frame
        received again and again (heartbeats) is one line with its count, so that the
        frames that matter stay in view."""
        with self._cond:
            seen = sorted(self._trace, key=self.bus_time)
        runs: list[list[Seen]] = []
        for s in seen:
            prev = runs[-1][-1] if runs else None
            if (prev is not None and not s.sent and not prev.sent
                    and (s.frame.can_id, s.frame.data, s.frame.rtr)
                    == (prev.frame.can_id, prev.frame.data, prev.frame.rtr)):
                runs[-1].append(s)
            else:
                runs.append([s])
        decoder = Decoder()
        lines = []
        for run in runs[-last:]:
            s = run[0]
            f = s.frame
            arrow = "->" if s.sent else "<-"
            body = "RTR" if f.rtr else (f.data.hex(" ").upper() or "(no data)")
            meaning = decoder.decode(f.can_id, f.data, rtr=f.rtr).text
            more = (f" (x{len(run)} until {self.bus_time(run[-1]):+.4f} s)" if len(run) > 1
                    else "")
            lines.append(f"{self.bus_time(s):+10.4f} s {arrow} {f.can_id:03X}  {body:<23}  "
                         f"{meaning}{more}")
        return lines
