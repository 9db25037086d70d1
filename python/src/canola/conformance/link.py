# SPDX-License-Identifier: Apache-2.0
"""Raw frames to and from the node under test, through a :class:`canola.Master`.

:class:`Link` sends frames (``Master.send``) and sees every frame of the other nodes
(``Master.on_frame``). It keeps the frames of the current check, to wait for one
(:meth:`Link.wait_frame`) or look back (:meth:`Link.frames_since`), and a bounded trace of
the latest frames in both directions (:meth:`Link.trace`), which a failure quotes.

Time is the bus's: virtual on a :class:`canola.core.SimBus` (waiting runs the simulated
bus, so every wait is exact and costs no wall time), the monotonic clock on python-can
(waiting blocks until the bus thread delivered a frame or the time is up).
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from canola import Master
from canola.core import SimBus
from canola.decode import Decoder
from canola.master import Frame

__all__ = ["TRACE_FRAMES", "Link", "Seen"]

#: Frames a trace keeps (both directions).
TRACE_FRAMES = 40

_SIM_STEP_US = 1000
#: Longest wait for a frame between two looks at the clock (python-can).
_WAIT_SLICE_S = 0.05
#: python-can buses that cannot send a remote frame (the socketcand client sends every
#: frame as data).
_NO_REMOTE_FRAMES = ("SocketCanDaemonBus",)


@dataclass(frozen=True)
class Seen:
    """A frame on the bus: ``sent`` by the tester or received, at ``t`` (link time, s);
    ``pos`` is its place among the frames of the check (the mark just after it is
    ``pos + 1``)."""

    t: float
    frame: Frame
    sent: bool
    pos: int


class Link:
    """The tester's frames on ``master``'s bus."""

    def __init__(self, master: Master) -> None:
        self.master = master
        bus = master.bus
        self.sim: SimBus | None = bus if isinstance(bus, SimBus) else None
        #: False when the bus cannot send remote frames (RTR).
        self.remote_frames = type(bus).__name__ not in _NO_REMOTE_FRAMES
        self._cond = threading.Condition()
        self._frames: list[Seen] = []
        self._trace: deque[Seen] = deque(maxlen=TRACE_FRAMES)
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
        seconds have passed; ``done()``'s last answer. On the wall clock only the time the
        tester ran counts: a stall of its own process (a slice of the wait that overran)
        extends the wait by the overrun, so the frames the bus kept meanwhile are read
        before the time is up."""
        end = self.now() + timeout
        if self.sim is not None:
            while not done():
                if self.now() >= end:
                    return False
                step = min(_SIM_STEP_US, max(1, round((end - self.now()) * 1e6)))
                self.sim.run_for(step)
            return True
        with self._cond:
            while not done():
                left = end - self.now()
                if left <= 0:
                    return done()
                slice_s = min(left, _WAIT_SLICE_S)
                before = self.now()
                self._cond.wait(slice_s)
                end += max(0.0, self.now() - before - slice_s)  # the tester's own stall
            return True

    # ---- frames

    def _received(self, frame: Frame) -> None:
        with self._cond:
            seen = Seen(self.now() - self._t0, frame, False, len(self._frames))
            self._frames.append(seen)
            self._trace.append(seen)
            self._cond.notify_all()

    def send(self, can_id: int, data: bytes = b"", *, rtr: bool = False) -> None:
        """Send one frame (recorded in the trace first)."""
        with self._cond:
            seen = Seen(self.now() - self._t0, Frame(can_id, bytes(data), rtr=rtr), True,
                        len(self._frames))
            self._frames.append(seen)
            self._trace.append(seen)
        self.master.send(can_id, data, rtr=rtr)

    def mark(self) -> int:
        """A position in the frames of this check, for :meth:`wait_frame` and
        :meth:`frames_since`."""
        with self._cond:
            return len(self._frames)

    def frames_since(self, mark: int, match: Callable[[Frame], bool] | None = None,
                     *, sent: bool = False) -> list[Seen]:
        """The received (or, with ``sent``, the sent) frames after ``mark`` that ``match``."""
        with self._cond:
            seen = self._frames[mark:]
        return [s for s in seen if s.sent == sent and (match is None or match(s.frame))]

    def wait_frame(self, match: Callable[[Frame], bool], timeout: float,
                   since: int) -> Seen | None:
        """The first received frame after ``since`` that ``match``es, waiting up to
        ``timeout`` seconds for it; None when none came."""
        found: list[Seen] = []

        def look() -> bool:
            found[:] = self.frames_since(since, match)[:1]
            return bool(found)

        self.wait_until(look, timeout)
        return found[0] if found else None

    def forget(self) -> None:
        """Drop the frames kept for waiting (a new check begins); the trace stays."""
        with self._cond:
            self._frames.clear()

    def trace(self, last: int = TRACE_FRAMES) -> list[str]:
        """The latest frames as text lines, oldest first, each with its CANopen meaning:
        ``+1.2345 s  -> 605  40 00 10 00 00 00 00 00   SDO ...``. A run of one frame
        received again and again (heartbeats) is one line with its count, so that the
        frames that matter stay in view."""
        with self._cond:
            seen = list(self._trace)
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
            more = f" (x{len(run)} until {run[-1].t:+.4f} s)" if len(run) > 1 else ""
            lines.append(f"{s.t:+10.4f} s {arrow} {f.can_id:03X}  {body:<23}  {meaning}{more}")
        return lines
