# SPDX-License-Identifier: Apache-2.0
"""Nodes for canola.conformance's tests to fail on purpose.

:class:`FakeNode` is a hand-written responder on the simulated bus (its frames go through
a canola.Master used as a raw port): an SDO server for expedited and segmented transfer and
the NMT commands, over a dictionary of plain values (:data:`FAKE_EDS`). It deviates from
CiA 301 exactly where its switches say, and lacks what it lacks: no block transfer (aborts
it with 0x05040001), no SDO server time-out, no heartbeat, no PDO, EMCY, SYNC or TIME.
"""

from __future__ import annotations

from dataclasses import dataclass

from canola import Master
from canola.core import SimBus
from canola.master import Frame

FAKE_EDS = """[FileInfo]
FileName=fake.eds
EDSVersion=4.0
[DeviceInfo]
VendorNumber=0x12345
ProductNumber=0x77
[MandatoryObjects]
SupportedObjects=3
1=0x1000
2=0x1001
3=0x1018
[OptionalObjects]
SupportedObjects=1
1=0x1008
[ManufacturerObjects]
SupportedObjects=2
1=0x2000
2=0x2001
[1000]
ParameterName=Device type
ObjectType=0x7
DataType=0x0007
AccessType=ro
DefaultValue=0x191
[1001]
ParameterName=Error register
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=0
[1008]
ParameterName=Manufacturer device name
ObjectType=0x7
DataType=0x0009
AccessType=const
DefaultValue=a fake responder
[1018]
ParameterName=Identity
ObjectType=0x9
SubNumber=3
[1018sub0]
ParameterName=Highest sub-index supported
ObjectType=0x7
DataType=0x0005
AccessType=const
DefaultValue=2
[1018sub1]
ParameterName=Vendor-ID
ObjectType=0x7
DataType=0x0007
AccessType=ro
DefaultValue=0x12345
[1018sub2]
ParameterName=Product code
ObjectType=0x7
DataType=0x0007
AccessType=ro
DefaultValue=0x77
[2000]
ParameterName=A number
ObjectType=0x7
DataType=0x0007
AccessType=rw
DefaultValue=7
[2001]
ParameterName=A blob
ObjectType=0x7
DataType=0x000F
AccessType=rw
"""

_SIZES = {(0x1000, 0): 4, (0x1001, 0): 1, (0x1018, 0): 1, (0x1018, 1): 4, (0x1018, 2): 4,
          (0x2000, 0): 4}
_READ_ONLY = {(0x1000, 0), (0x1001, 0), (0x1008, 0), (0x1018, 0), (0x1018, 1), (0x1018, 2)}


@dataclass
class _Transfer:
    key: tuple[int, int]
    upload: bool
    data: bytes = b""
    toggle: int = 0


def _abort(index: int, sub: int, code: int) -> bytes:
    return bytes([0x80]) + index.to_bytes(2, "little") + bytes([sub]) + code.to_bytes(4, "little")


class FakeNode:
    """Node ``node_id`` on ``bus``, answering through a Master at ``port_id``.
    ``checks_toggle=False``: download segments are taken whatever their toggle bit.
    ``late_abort``: an abort 0x05040001 naming no entry (0x0000:0) goes before each answer,
    initiate or segment (as the late abort of a request that reached the server after its
    time-out would over a slow link).
    ``accepts_read_only``: a write to a read-only entry is answered with success (and the
    value kept). ``missing_object_code``: the abort code for an object it does not have."""

    def __init__(self, bus: SimBus, node_id: int, *, port_id: int = 100,
                 checks_toggle: bool = True, late_abort: bool = False,
                 accepts_read_only: bool = False,
                 missing_object_code: int = 0x06020000) -> None:
        self.node_id = node_id
        self.checks_toggle = checks_toggle
        self.late_abort = late_abort
        self.accepts_read_only = accepts_read_only
        self.missing_object_code = missing_object_code
        self.values = {(0x1000, 0): (0x191).to_bytes(4, "little"), (0x1001, 0): b"\0",
                       (0x1008, 0): b"a fake responder", (0x1018, 0): b"\x02",
                       (0x1018, 1): (0x12345).to_bytes(4, "little"),
                       (0x1018, 2): (0x77).to_bytes(4, "little"),
                       (0x2000, 0): (7).to_bytes(4, "little"), (0x2001, 0): b"blob"}
        self.state = 0x7F
        self._transfer: _Transfer | None = None
        self.port = Master(bus, port_id)
        self.port.on_frame(self._nmt, cob_id=0x000)
        self.port.on_frame(self._sdo, cob_id=0x600 + node_id)

    def start(self) -> None:
        self.port.start()
        self._boot()

    def _boot(self) -> None:
        self.state = 0x7F
        self._transfer = None
        self.port.send(0x700 + self.node_id, b"\0")

    def _send(self, data: bytes) -> None:
        self.port.send(0x580 + self.node_id, data.ljust(8, b"\0"))

    def _nmt(self, frame: Frame) -> None:
        if len(frame.data) != 2 or frame.data[1] not in (0, self.node_id):
            return
        command = frame.data[0]
        if command in (0x81, 0x82):
            self._boot()
        else:
            self.state = {0x01: 0x05, 0x02: 0x04, 0x80: 0x7F}.get(command, self.state)

    def _sdo(self, frame: Frame) -> None:
        data = frame.data
        if self.state == 0x04 or len(data) != 8:
            return
        ccs = data[0] >> 5
        if ccs == 4:  # abort from the client
            self._transfer = None
            return
        if self.late_abort:
            self._send(_abort(0, 0, 0x05040001))
        if self._transfer is not None and ccs in (0, 3):
            self._segment(data, ccs)
            return
        index, sub = int.from_bytes(data[1:3], "little"), data[3]
        key = (index, sub)
        if ccs not in (1, 2):
            self._send(_abort(index, sub, 0x05040001))
            return
        if key not in self.values:
            known = any(i == index for i, _ in self.values)
            self._send(_abort(index, sub, 0x06090011 if known else self.missing_object_code))
            return
        if ccs == 2:
            self._upload(index, sub)
        else:
            self._download(index, sub, data)

    def _upload(self, index: int, sub: int) -> None:
        value = self.values[(index, sub)]
        mux = index.to_bytes(2, "little") + bytes([sub])
        if len(value) <= 4:
            self._send(bytes([0x43 | (4 - len(value)) << 2]) + mux + value)
            return
        self._transfer = _Transfer((index, sub), upload=True, data=value)
        self._send(bytes([0x41]) + mux + len(value).to_bytes(4, "little"))

    def _download(self, index: int, sub: int, data: bytes) -> None:
        key = (index, sub)
        mux = index.to_bytes(2, "little") + bytes([sub])
        if key in _READ_ONLY and not self.accepts_read_only:
            self._send(_abort(index, sub, 0x06010002))
            return
        if data[0] & 0x02:  # expedited
            value = data[4:8 - ((data[0] >> 2) & 3)] if data[0] & 0x01 else data[4:8]
            if not self._fits(key, value):
                return
            self._store(key, value)
            self._send(bytes([0x60]) + mux)
            return
        self._transfer = _Transfer(key, upload=False)
        self._send(bytes([0x60]) + mux)

    def _store(self, key: tuple[int, int], value: bytes) -> None:
        if key not in _READ_ONLY:  # a read-only one answered with success keeps its value
            self.values[key] = value

    def _fits(self, key: tuple[int, int], value: bytes) -> bool:
        size = _SIZES.get(key)
        if size is not None and len(value) != size:
            self._send(_abort(key[0], key[1], 0x06070010))
            return False
        return True

    def _segment(self, data: bytes, ccs: int) -> None:
        t = self._transfer
        assert t is not None
        index, sub = t.key
        if (ccs == 3) != t.upload:
            self._transfer = None
            self._send(_abort(index, sub, 0x05040001))
            return
        toggle = (data[0] >> 4) & 1
        if toggle != t.toggle and (t.upload or self.checks_toggle):
            self._transfer = None
            self._send(_abort(index, sub, 0x05030000))
            return
        t.toggle = toggle ^ 1
        if t.upload:
            piece, t.data = t.data[:7], t.data[7:]
            if not t.data:
                self._transfer = None
            self._send(bytes([toggle << 4 | (7 - len(piece)) << 1 | int(not t.data)]) + piece)
            return
        t.data += data[1:8 - ((data[0] >> 1) & 7)]
        if data[0] & 1:  # the last segment: the value is stored (or refused) now
            self._transfer = None
            if not self._fits(t.key, t.data):
                return
            self._store(t.key, t.data)
        self._send(bytes([0x20 | toggle << 4]))
