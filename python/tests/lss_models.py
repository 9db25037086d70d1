# SPDX-License-Identifier: Apache-2.0
"""A model of an LSS slave that behaves like CANopenNode's (CO_LSSslave.c, read for its
behaviour): once a fastscan matched its whole address it is in LSS configuration, and
there it answers every fastscan request, whatever it asks. A raw node on the bus (a
canola.Master used as a frame port) plays it; enough LSS for fastscan and a node-ID."""

from __future__ import annotations

from canola import Master
from canola._engine import Bus, Frame

LSS_MASTER = 0x7E5
LSS_SLAVE = 0x7E4


class ChattyLssSlave:
    """An unconfigured LSS slave with ``address`` (vendor, product, revision, serial)."""

    def __init__(self, bus: Bus, address: tuple[int, int, int, int], port_id: int) -> None:
        self.address = address
        self.configuration = False
        self.pos = 0
        self.pending_id = 0xFF
        self.node_id = 0xFF
        self.fastscan_answers = 0
        self._port = Master(bus, node_id=port_id)
        self._port.on_frame(self._rx, cob_id=LSS_MASTER)
        self._port.start()

    def stop(self) -> None:
        self._port.stop()

    def _answer(self, data: bytes) -> None:
        self._port.send(LSS_SLAVE, data.ljust(8, b"\0"))

    def _rx(self, frame: Frame) -> None:
        d = frame.data
        if len(d) != 8:
            return
        if d[0] == 0x04:  # switch state global
            if d[1] == 0 and self.configuration and self.pending_id != 0xFF:
                self.node_id = self.pending_id  # it boots with its node-ID
            self.configuration = d[1] == 1
            return
        if self.configuration:
            if d[0] == 0x51:  # every fastscan request answered
                self.fastscan_answers += 1
                self._answer(b"\x4f")
            elif d[0] == 0x11:  # configure node-ID
                self.pending_id = d[1]
                self._answer(b"\x11\x00")
            return
        if d[0] == 0x51 and self.node_id == 0xFF:
            self._fastscan(d)

    def _fastscan(self, d: bytes) -> None:
        bit, sub, nxt = d[5], d[6], d[7]
        if bit == 0x80:
            self.pos = 0
            self._answer(b"\x4f")
            return
        if bit > 31 or sub > 3 or nxt > 3 or sub != self.pos:
            return
        mask = (0xFFFFFFFF << bit) & 0xFFFFFFFF
        if (int.from_bytes(d[1:5], "little") ^ self.address[sub]) & mask:
            return
        self._answer(b"\x4f")
        self.pos = nxt
        if bit == 0 and nxt < sub:
            self.configuration = True  # the whole address matched
