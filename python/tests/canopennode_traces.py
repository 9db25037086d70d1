# SPDX-License-Identifier: Apache-2.0
"""Recorded traces of real CANopenNode devices (python/tests/data/traces/*.log), for the tests
of canola.conformance: RECORDED, NOT MODELLED (canopennode_models.py is the model).

A trace is ``candump -L`` of vcan0 while ``canola conformance`` ran against the device (the
header of each file says which device, which upstream commits, how it was run). Two uses:

- :func:`load` gives the frames, for tests that assert from them what the device did (the
  abort code it sent, the state in its heartbeat after NMT start and when, 0x1017 after
  reset communication, the register byte of its EMCY);
- :class:`ReplayNode` answers the tester's SDO requests on the simulated bus with what the
  real device answered to the same request in the trace (the n-th time a request comes, the
  n-th recorded answer to it), so the tester's own judging logic runs on the device's frames;
  the abort of the device's own SDO time-out (0x05040000) comes as late as it came on the bus.
  Between requests it keeps only what the tester needs to see the node: its NMT state and
  a heartbeat at the 0x1017 period the replayed answers accepted.

The devices' dictionaries, which the tester is given for a replay, are in
canopennode_dictionaries.py.
"""

from __future__ import annotations

import re
from collections import defaultdict, deque
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from canola import Master
from canola.core import SimBus
from canola.master import Frame

TRACES = Path(__file__).resolve().parent / "data" / "traces"
NODE = 5
TESTER = 127
_LINE = re.compile(r"^\((\d+\.\d+)\) \S+ ([0-9A-Fa-f]{3})#([0-9A-Fa-f]*)$")
_STATES = {0x01: 0x05, 0x02: 0x04, 0x80: 0x7F}
_SERVER_TIMEOUT = (0x05040000).to_bytes(4, "little")


@dataclass(frozen=True, slots=True)
class Recorded:
    """A frame of a trace: its bus time (s), COB-ID and data."""

    t: float
    cob: int
    data: bytes

    @property
    def text(self) -> str:
        return f"{self.cob:03X}#{self.data.hex().upper()}"


def load(name: str) -> list[Recorded]:
    """The frames of ``data/traces/NAME.log`` (lines starting with ``#`` are its header)."""
    frames = []
    for number, line in enumerate((TRACES / f"{name}.log").read_text().splitlines(), 1):
        if not line or line.startswith("#"):
            continue
        match = _LINE.match(line)
        if match is None:
            raise ValueError(f"{name}.log:{number}: not a candump -L line: {line!r}")
        frames.append(Recorded(float(match[1]), int(match[2], 16), bytes.fromhex(match[3])))
    return frames


def header(name: str) -> str:
    """The comment lines at the top of the trace."""
    lines = (TRACES / f"{name}.log").read_text().splitlines()
    return "\n".join(line for line in lines if line.startswith("#"))


def from_tester(frame: Recorded) -> bool:
    """A frame the tester sent (requests, NMT, SYNC, TIME, RPDOs, its heartbeat)."""
    return frame.cob in (0x000, 0x080, 0x100, 0x600 + NODE, 0x700 + TESTER) or (
        0x200 <= frame.cob < 0x580 and (frame.cob & 0x7F) == NODE and frame.cob >> 7 in (
            4, 6, 8, 10))


def answers(frames: list[Recorded]) -> dict[bytes, deque[list[bytes]]]:
    """For each SDO request of the tester, the device's SDO frames that followed it (before
    the tester's next SDO request), once per time it was sent, in order."""
    table: dict[bytes, deque[list[bytes]]] = defaultdict(deque)
    current: list[bytes] | None = None
    for frame in frames:
        if frame.cob == 0x600 + NODE:
            current = []
            table[frame.data].append(current)
        elif frame.cob == 0x580 + NODE and current is not None:
            current.append(frame.data)
    return table


def server_timeout_s(frames: list[Recorded]) -> float | None:
    """How long after its last SDO frame the device aborted a transfer the client left
    (0x05040000) the first time it did; None if it never did."""
    last = None
    for frame in frames:
        if frame.cob == 0x580 + NODE:
            if frame.data[0] == 0x80 and frame.data[4:8] == _SERVER_TIMEOUT and last:
                return frame.t - last
            last = frame.t
    return None


class ReplayNode:
    """Node :data:`NODE` on ``bus`` answering SDO requests as the recorded device did.
    ``missed`` lists the requests the trace has no (more) answer for: they stay unanswered,
    as a request a device ignores would."""

    def __init__(self, bus: SimBus, frames: list[Recorded]) -> None:
        self.table = answers(frames)
        self.timeout_s = server_timeout_s(frames)
        self.missed: list[bytes] = []
        self.state = 0x7F
        self.period_ms = 0
        self._timer: Any = None
        self.port = Master(bus, 100)
        self.port.on_frame(self._sdo, cob_id=0x600 + NODE)
        self.port.on_frame(self._nmt, cob_id=0x000)

    def start(self) -> None:
        self.port.start()
        self.port.send(0x700 + NODE, b"\0")

    def _sdo(self, frame: Frame) -> None:
        request = bytes(frame.data)
        queue = self.table.get(request)
        if not queue:
            self.missed.append(request)
            return
        replies = queue.popleft()
        for reply in replies:
            if reply[0] == 0x80 and reply[4:8] == _SERVER_TIMEOUT and self.timeout_s:
                self._later(self.timeout_s, reply)
            else:
                self.port.send(0x580 + NODE, reply)
        if request[:4] == b"\x2b\x17\x10\x00" and replies and replies[-1][0] == 0x60:
            self._heartbeat(int.from_bytes(request[4:6], "little"))

    def _later(self, after_s: float, reply: bytes) -> None:
        engine = self.port._engine
        timers: list[Any] = []

        def send() -> None:
            engine.remove_timer(timers[0])
            self.port.send(0x580 + NODE, reply)

        timers.append(engine.add_timer(round(after_s * 1e6), send))

    def _nmt(self, frame: Frame) -> None:
        if len(frame.data) != 2 or frame.data[1] not in (0, NODE):
            return
        if frame.data[0] in (0x81, 0x82):
            self.state = 0x7F
            self.port.send(0x700 + NODE, b"\0")
        else:
            self.state = _STATES.get(frame.data[0], self.state)

    def _heartbeat(self, period_ms: int) -> None:
        engine = self.port._engine
        if self._timer is not None:
            engine.remove_timer(self._timer)
            self._timer = None
        self.period_ms = period_ms
        if period_ms:
            self._timer = engine.add_timer(period_ms * 1000, self._beat)

    def _beat(self) -> None:
        self.port.send(0x700 + NODE, bytes([self.state]))
        self._heartbeat(self.period_ms)
