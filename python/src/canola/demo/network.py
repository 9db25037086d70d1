# SPDX-License-Identifier: Apache-2.0
"""Where the demo runs: the simulated bus in virtual time, or python-can buses.

Both transports give the demo the same four things: a bus for each node, ``wait(seconds)``
(time passing, with every frame and event shown as it comes), ``drain()`` (the frames seen
since the last call, in order, with their time in seconds since the start) and ``now()``.

- :class:`SimNetwork`: one :class:`canola.core.SimBus`; time is virtual, so the demo takes
  as long as the computer needs (``pace=True`` sleeps to keep virtual time with the wall
  clock, to watch it live). The trace is the bus's own candump trace.
- :class:`CanNetwork`: one python-can connection per node on the bus the user named
  (``--iface`` / ``--bus``), and one more that only listens: the trace. Time is real.
"""

from __future__ import annotations

import abc
import time
from collections.abc import Callable
from dataclasses import dataclass

import can

from canola.bus.candump import parse_line
from canola.core import SimBus
from canola.errors import Error

__all__ = ["CanNetwork", "Network", "SimNetwork", "TraceFrame"]

#: The step of virtual time between two looks at the trace (seconds).
SIM_STEP_S = 0.001


@dataclass(frozen=True)
class TraceFrame:
    """One frame on the bus: ``t`` seconds since the demo started."""

    t: float
    can_id: int
    data: bytes
    rtr: bool = False


class Network(abc.ABC):
    """What the scenario needs from a transport (see the module text)."""

    virtual = False
    description = ""

    @abc.abstractmethod
    def node_bus(self) -> SimBus | can.BusABC:
        raise NotImplementedError

    @abc.abstractmethod
    def now(self) -> float:
        raise NotImplementedError

    @abc.abstractmethod
    def drain(self) -> list[TraceFrame]:
        raise NotImplementedError

    @abc.abstractmethod
    def wait(self, seconds: float, tick: Callable[[], None]) -> None:
        """Let ``seconds`` pass, calling ``tick`` often (it prints what happened)."""
        raise NotImplementedError

    def close(self) -> None:  # noqa: B027 (a default: most networks hold nothing)
        """Release the buses (python-can)."""


class SimNetwork(Network):
    """The simulated bus (``bitrate`` 0: no timing model)."""

    virtual = True

    def __init__(self, *, pace: bool = False, bitrate: int = 500_000) -> None:
        self.bus = SimBus(bitrate)
        self.pace = pace
        self._seen = 0
        self._wall0 = time.monotonic()
        self.description = (f"the simulated bus ({bitrate // 1000} kbit/s), "
                            + ("paced to the wall clock" if pace else "virtual time"))

    def node_bus(self) -> SimBus:
        return self.bus

    def now(self) -> float:
        return self.bus.now_us / 1e6

    def drain(self) -> list[TraceFrame]:
        lines = self.bus.trace[self._seen:]
        self._seen += len(lines)
        out = []
        for line in lines:
            frame = parse_line(line)
            if frame is not None:
                out.append(TraceFrame(frame.timestamp or 0.0, frame.can_id, frame.data,
                                      frame.rtr))
        return out

    def wait(self, seconds: float, tick: Callable[[], None]) -> None:
        end = self.bus.now_us + round(seconds * 1e6)
        while self.bus.now_us < end:
            self.bus.run_until(min(end, self.bus.now_us + round(SIM_STEP_S * 1e6)))
            tick()
            if self.pace:
                ahead = self._wall0 + self.now() - time.monotonic()
                if ahead > 0:
                    time.sleep(ahead)


class CanNetwork(Network):
    """python-can buses from ``opener`` (called once per node and once for the trace)."""

    def __init__(self, opener: Callable[[], can.BusABC], where: str) -> None:
        self._opener = opener
        self._buses: list[can.BusABC] = []
        self._t0 = time.time()  # python-can time-stamps frames with the epoch clock
        self.listener = self.node_bus()
        self.description = f"{where} (real time)"

    def node_bus(self) -> can.BusABC:
        bus = self._opener()
        self._buses.append(bus)
        return bus

    def now(self) -> float:
        return time.time() - self._t0

    def _receive(self, timeout: float) -> TraceFrame | None:
        try:
            msg = self.listener.recv(timeout)
        except can.CanError as exc:
            raise Error(f"the bus went away: {exc}") from None
        if msg is None or msg.is_error_frame or msg.is_fd:
            return None
        stamp = msg.timestamp - self._t0 if msg.timestamp else self.now()
        return TraceFrame(stamp, msg.arbitration_id,
                          b"" if msg.is_remote_frame else bytes(msg.data), msg.is_remote_frame)

    def drain(self) -> list[TraceFrame]:
        out = []
        while (frame := self._receive(0.0)) is not None:
            out.append(frame)
        return out

    def wait(self, seconds: float, tick: Callable[[], None]) -> None:
        end = time.monotonic() + seconds
        while (left := end - time.monotonic()) > 0:
            time.sleep(min(left, 0.005))
            tick()

    def close(self) -> None:
        for bus in self._buses:
            bus.shutdown()
        self._buses.clear()
