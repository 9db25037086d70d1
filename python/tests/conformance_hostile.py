# SPDX-License-Identifier: Apache-2.0
"""Hostile nodes for canola.conformance's tests: :class:`HostileNode` is a
:class:`~conformance_fakes.FakeNode` whose SDO server answers the uploads and block
transfers of its DOMAIN 0x2001 so that a client without bounds never ends (issue 35):

- ``huge``: a segmented upload announcing 1 GiB, each segment 7 bytes, never the last;
- ``unsized``: a segmented upload without size whose segments never end;
- ``endless_block``: a block upload whose sub-blocks never end (full, never the last);
- ``stalled_acks``: a block download whose every sub-block is acknowledged with ackseq 0;
- ``flood``: answers as FakeNode does, but sends :data:`FLOOD_PER_MS` frames every
  millisecond meanwhile: junk on its SDO answer COB-ID and heartbeats.
"""

from __future__ import annotations

from typing import Any

from conformance_fakes import FakeNode

from canola.core import SimBus

BLOB = (0x2001, 0)
GIB = 1 << 30
#: Frames a flooding node sends every millisecond (3000 frames/s).
FLOOD_PER_MS = 3
JUNK = bytes([0xEE, 0x01, 0x20, 0x00, 0xDE, 0xAD, 0xBE, 0xEF])
MODES = ("huge", "unsized", "endless_block", "stalled_acks", "flood")


class HostileNode(FakeNode):
    """Node ``node_id`` on ``bus`` in ``mode`` (one of :data:`MODES`)."""

    def __init__(self, bus: SimBus, node_id: int, mode: str) -> None:
        if mode not in MODES:
            raise ValueError(mode)
        super().__init__(bus, node_id)
        self.mode = mode
        self.served = 0  # frames answered in the hostile transfer
        self._hostile = False  # a hostile transfer is open
        self._toggle = 0
        self._blksize = 0
        self._timer: Any = None

    def start(self) -> None:
        super().start()
        if self.mode == "flood":
            self._timer = self.port._engine.add_timer(1000, self._flood)

    def stop(self) -> None:
        if self._timer is not None:
            self.port._engine.remove_timer(self._timer)
            self._timer = None

    def _flood(self) -> None:
        for n in range(FLOOD_PER_MS):
            if n % 3 == 2:
                self.port.send(0x700 + self.node_id, bytes([self.state]))
            else:
                self.port.send(0x580 + self.node_id, JUNK)

    def _sdo(self, frame: Any) -> None:
        data = frame.data
        if self.mode != "flood" and self.state != 0x04 and len(data) == 8:
            key = (int.from_bytes(data[1:3], "little"), data[3])
            if data[0] == 0x80:  # the client's abort
                self._hostile = False
            elif key == BLOB and _initiates(data) and self._hostile_open(data):
                return
            elif self._hostile:
                self._continue(data)
                return
        super()._sdo(frame)

    def _hostile_open(self, data: bytes) -> bool:
        """Open (and answer) a hostile transfer for the request, when it is the mode's."""
        ccs = data[0] >> 5
        mux = data[1:4]
        if ccs == 2 and self.mode == "huge":
            self._send(bytes([0x41]) + mux + GIB.to_bytes(4, "little"))
        elif ccs == 2 and self.mode == "unsized":
            self._send(bytes([0x40]) + mux)
        elif ccs == 5 and self.mode == "endless_block" and data[0] & 0x03 == 0:
            self._blksize = data[4]
            self._send(bytes([0xC4]) + mux)  # CRC, no size
        elif ccs == 6 and self.mode == "stalled_acks" and data[0] & 0x01 == 0:
            self._send(bytes([0xA4]) + mux + bytes([4]))  # CRC, block size 4
        else:
            return False
        self._hostile, self._toggle = True, 0
        return True

    def _continue(self, data: bytes) -> None:
        self.served += 1
        if self.mode in ("huge", "unsized") and data[0] >> 5 == 3:
            self._send(bytes([self._toggle << 4]) + b"1234567")  # 7 bytes, never the last
            self._toggle ^= 1
        elif self.mode == "endless_block" and data[0] in (0xA3, 0xA2):
            self._blksize = data[2] if data[0] == 0xA2 else self._blksize
            for seqno in range(1, max(1, self._blksize) + 1):
                self._send(bytes([seqno]) + b"7654321")  # never with the last flag
        elif self.mode == "stalled_acks" and (data[0] & 0x80 or data[0] & 0x7F == 4):
            self._send(bytes([0xA2, 0, 4]))  # the end of a sub-block: nothing taken


def _initiates(data: bytes) -> bool:
    """An initiate request: upload (ccs 2), block upload (ccs 5, cs 0), block download
    (ccs 6, cs 0)."""
    ccs = data[0] >> 5
    return ccs == 2 or (ccs == 5 and data[0] & 0x03 == 0) or (ccs == 6 and data[0] & 0x01 == 0)
