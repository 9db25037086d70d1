# SPDX-License-Identifier: Apache-2.0
"""Two CANopenNode devices as scripted nodes on the simulated bus, for the tests of
canola.conformance: ``canopend`` (CANopenNode/CANopenLinux) and CANopenDemo's ``demoDevice``.

MODELLED, NOT RECORDED: for live interaction (the tester's waits and requests as they come).
canopend's real frames are in data/traces/canopend.log (canopennode_traces.py,
test_conformance_traces.py); where the real device differs from this model: its dictionary is
CANopenNode's DS301 profile (no manufacturer objects, so no string and no entry longer than 4
bytes: the segmented checks are skipped there), NMT reset node ends canopend's process (a
supervisor restarts it; no boot-up without one), and with its storage files missing it
reports EMCY 0x5000 (generic error) at start and, as CO_NMT_ERR_ON_ERR_REG asks, stays
PRE-OPERATIONAL whatever NMT says. demoDevice's real frames are in data/traces/demodevice.log;
where it differs from this model: its dictionary is demoDevice.eds's (canopennode_dictionaries.py:
the CiA 401 I/O objects, 0x2100..0x2120, RPDO1 mapped to 0x6200:1..2), its "String long"
0x2121:2 has room for 1000 bytes (here 64, so that a length refusal gets exercised), it
goes OPERATIONAL by itself at start, its 0x100A is empty when built outside a tagged
checkout (a read is aborted with 0x06040047), and NMT reset node ends its process as
canopend's; its 3-byte string and its DOMAIN answer the probes as modelled here
(demodevice_short_string.log, demodevice_domain.log). Each model
reproduces what issue 34 observed when ``canola conformance`` ran against the two devices on
vcan0 (frames and timings quoted there), and what the devices' public descriptions say
(CANopenDemo's demo/demoDevice.md and demo/domainDemo.c): a :class:`canola.Device` (a
complete CiA 301 device, canola's C core) with a dictionary of the device's kind, and the
behaviours where CANopenNode differs from it, applied where the device meets the bus:

- its mainline: an NMT command takes effect :data:`MAINLINE_US` after it came (issue 34: the
  node entered OPERATIONAL 20-44 ms after the command); SDO requests that come meanwhile
  are served after it, in the same pass; RPDOs and SYNC (its realtime thread) at once;
- reset communication keeps every value of the communication area (CANopenLinux loads its
  defaults and stored parameters only once, at its start): 0x1017 stays at a written 1000;
- the error register of a communication error is 0x10, without bit 0 (generic error), in
  0x1001 and in the EMCY's register byte;
- 0x1003 above its number of errors answers 0x08000024 (as canola's core does since);
  ``history_reads_zero`` makes it answer the value 0 instead (canola's core before);
- demoDevice: strings in 0x2121 ("str", 3 bytes of room; a longer one; an OCTET_STRING of 3
  bytes) and the DOMAIN 0x2122, which reads 1024 bytes of the sequence 0, 1, .. 255, 0, ..
  and takes only that sequence (any other byte: 0x06090030), as domainDemo.c does.
"""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import Any

import pytest

from canola import Device, Master, SdoAbort
from canola.conformance.link import Link
from canola.core import SimBus
from canola.domain import DomainStream
from canola.formats import eds
from canola.master import Frame

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "example_od.eds"
NODE = 5
#: When an NMT command takes effect after it came (the device's next mainline pass).
MAINLINE_US = 30_000
NO_DATA = 0x08000024
_VALUE_REFUSED = 0x06090030

_DEMO_OBJECTS = """[FileInfo]
FileName=demo_objects.eds
[2121]
ParameterName=Demo strings
ObjectType=0x9
SubNumber=4
[2121sub0]
ParameterName=Highest sub-index supported
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=3
[2121sub1]
ParameterName=String short
ObjectType=0x7
DataType=0x0009
AccessType=rw
DefaultValue=str
[2121sub2]
ParameterName=String long
ObjectType=0x7
DataType=0x0009
AccessType=rw
DefaultValue=A string whose room is its default's: sixty-four bytes, no more.
[2121sub3]
ParameterName=Octet string
ObjectType=0x7
DataType=0x000A
AccessType=rw
DefaultValue=C8 3D BB
[2122]
ParameterName=Demo domain
ObjectType=0x7
DataType=0x000F
AccessType=rw
"""


def canopend_od() -> eds.ObjectDictionary:
    """canopend's kind of dictionary: canola-node's example, its heartbeat off (0x1017 0)."""
    od = eds.parse(EXAMPLE, node_id=NODE)
    var = od.objects[0x1017].subs[0]
    var.default, var.default_value = 0, "0"
    return od


def demo_od() -> eds.ObjectDictionary:
    """demoDevice's kind of dictionary: canopend's, its strings and DOMAIN those of 0x2121
    and 0x2122."""
    od = canopend_od()
    for index in (0x2002, 0x2003):  # the example's own string and DOMAIN
        del od.objects[index]
    od.objects.update(eds.parse(_DEMO_OBJECTS, node_id=NODE).objects)
    return od


class SequenceDomain(DomainStream):
    """CANopenDemo's 0x2122: reads the sequence 0, 1, .. 255, 0, .. (1024 bytes, or as many
    as the last download wrote) and takes only that sequence."""

    def __init__(self, device: Device, index: int) -> None:
        super().__init__(device, index, value=bytes(i % 256 for i in range(1024)))

    def write(self, offset: int, data: bytes, total: int | None, last: bool) -> int:
        if any(b != (offset + i) % 256 for i, b in enumerate(data)):
            return _VALUE_REFUSED
        return super().write(offset, data, total, last)


class CanopenNodeModel:
    """A CANopenNode device (:func:`canopend_od` or :func:`demo_od`) as node :data:`NODE`
    on ``bus``; :meth:`install` puts its behaviours between it and the tester."""

    def __init__(self, bus: SimBus, od: eds.ObjectDictionary, *, store_dir: Path | None = None,
                 history_reads_zero: bool = False) -> None:
        self.bus = bus
        self.device = Device(od, NODE, bus, store_dir=store_dir, string_size=1)
        if 0x2122 in od.objects:
            self.domain = SequenceDomain(self.device, 0x2122)
        self.history_reads_zero = history_reads_zero
        self._pending: list[tuple[int, bytes, bool]] = []  # for the next mainline pass
        self._snapshot: dict[tuple[int, int], bytes] | None = None
        self._emcy = 0x80 + NODE  # 0x1014's COB-ID, followed from the device's side
        self.device.on_state(self._state)
        self.device.on_write(self._written)
        self.device.start()

    # ---- between the tester and the device

    def install(self, monkeypatch: pytest.MonkeyPatch) -> None:
        """The tester's frames reach the device through :meth:`_to_device`; the device's
        reach the tester through :meth:`_to_tester`."""
        send, received = Master.send, Link._received
        model = self

        def to_device(master: Master, can_id: int, data: bytes = b"", *,
                      rtr: bool = False) -> None:
            model._to_device(master, send, can_id, bytes(data), rtr)

        def to_tester(link: Link, frame: Frame) -> None:
            received(link, model._to_tester(frame))

        monkeypatch.setattr(Master, "send", to_device)
        monkeypatch.setattr(Link, "_received", to_tester)

    def _to_device(self, master: Master, send: Any, can_id: int, data: bytes,
                   rtr: bool) -> None:
        nmt = can_id == 0 and len(data) == 2 and data[1] in (0, NODE)
        if not nmt and not (self._pending and can_id == 0x600 + NODE):
            send(master, can_id, data, rtr=rtr)  # RPDOs, SYNC: the realtime thread
            return
        if not self._pending:
            engine = master._engine
            timers: list[Any] = []

            def mainline_pass() -> None:
                engine.remove_timer(timers[0])
                pending, self._pending = self._pending, []
                for cob, payload, remote in pending:
                    if cob == 0 and payload[0] == 0x82:
                        self._snapshot = self._communication_values()
                    send(master, cob, payload, rtr=remote)

            timers.append(engine.add_timer(MAINLINE_US, mainline_pass))
        self._pending.append((can_id, data, rtr))

    def _to_tester(self, frame: Frame) -> Frame:
        data = frame.data
        if frame.can_id == self._emcy and len(data) == 8 and data[2] & 0x10:
            return _with(frame, data[:2] + bytes([data[2] & ~1]) + data[3:])
        if frame.can_id == 0x580 + NODE and len(data) == 8:
            if data[:4] == bytes([0x4F, 0x01, 0x10, 0x00]) and data[4] & 0x10:
                return _with(frame, data[:4] + bytes([data[4] & ~1]) + data[5:])
            if (self.history_reads_zero and data[0] == 0x80 and data[1:3] == b"\x03\x10"
                    and int.from_bytes(data[4:8], "little") == NO_DATA):
                return _with(frame, bytes([0x43, 0x03, 0x10, data[3], 0, 0, 0, 0]))
        return frame

    # ---- the device's side (its callbacks may use it; the tester's must not: a call into
    # the device from there delivers the tester's next frames before the one at hand)

    def _written(self, index: int, sub: int, value: object) -> None:
        if (index, sub) == (0x1014, 0) and isinstance(value, int):
            self._emcy = value & 0x7FF

    # ---- reset communication keeps the communication area

    def _communication_values(self) -> dict[tuple[int, int], bytes]:
        return {(i, s): self.device.od.read(i, s) for i, s in self.device.od
                if 0x1000 <= i <= 0x1FFF and i not in (0x1001, 0x1003, 0x1010, 0x1011)}

    def _state(self, state: str) -> None:
        if state != "PRE-OPERATIONAL":
            return
        self._emcy = int.from_bytes(self.device.od.read(0x1014, 0), "little") & 0x7FF
        if self._snapshot is None:
            return
        before, self._snapshot = self._snapshot, None
        for key, value in before.items():
            if self.device.od.read(*key) != value:
                with contextlib.suppress(SdoAbort):
                    self.device.od.write(*key, value)


def _with(frame: Frame, data: bytes) -> Frame:
    return Frame(frame.can_id, data, rtr=frame.rtr, timestamp=frame.timestamp)
