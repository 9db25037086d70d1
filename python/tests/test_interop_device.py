# SPDX-License-Identifier: Apache-2.0
"""python-canopen (an independent implementation) against canola.Device over python-can.

python-canopen's RemoteNode is the master here: SDO in every form and size, abort codes,
NMT and heartbeat, PDO re-mapping and data, SYNC, TIME, EMCY, the network scanner. The bus
is python-can's ``virtual`` interface, or SocketCAN with CANOLA_VCAN set (see conftest).
"""

from __future__ import annotations

import io
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import can
import canopen
import pytest
from canopen.sdo.exceptions import SdoAbortedError
from conftest import SDO_TIMEOUT_MS, wait_until

from canola import Device
from canola.formats.values import TimeOfDay

pytestmark = [pytest.mark.realtime, pytest.mark.vcan]

INTEROP = Path(__file__).parent / "data" / "interop.eds"
NODE = 5


class Peer:
    def __init__(self, device: Device, network: canopen.Network, node: Any) -> None:
        self.device = device
        self.network = network
        self.node = node


@pytest.fixture
def peer(can_bus: Callable[[], can.BusABC]) -> Iterator[Peer]:
    device = Device(INTEROP, NODE, can_bus(), sdo_timeout_ms=SDO_TIMEOUT_MS)
    network = canopen.Network(can_bus())
    network.connect()
    node = network.add_node(NODE, str(INTEROP))
    node.sdo.RESPONSE_TIMEOUT = SDO_TIMEOUT_MS / 1000 + 1
    device.start()
    try:
        yield Peer(device, network, node)
    finally:
        network.disconnect()
        device.stop()


# ---- SDO: every data type

#: index 0x2000 + type code -> a new value as python-canopen's .raw takes it
TYPED = {
    0x01: True, 0x02: -100, 0x03: -30000, 0x04: -2_000_000_000, 0x05: 200, 0x06: 60000,
    0x07: 4_000_000_000, 0x08: -1.25, 0x09: "visible string", 0x0A: b"\x09\x08\x07",
    0x0B: "unicode ż", 0x0F: b"\x00domain\xff",
    0x10: -8_000_000, 0x11: 3.0e100, 0x12: -(2**39), 0x13: 2**47 - 1, 0x14: -(2**55),
    0x15: -(2**63), 0x16: 2**24 - 1, 0x18: 2**40 - 1, 0x19: 2**48 - 1, 0x1A: 2**56 - 1,
    0x1B: 2**64 - 1,
}


def test_sdo_every_type(peer: Peer) -> None:
    sdo, od = peer.node.sdo, peer.device.od
    for code, value in TYPED.items():
        index = 0x2000 + code
        before = sdo[index].raw
        assert before == od[index][0], hex(index)
        sdo[index].raw = value
        assert od[index][0] == value, hex(index)
        assert sdo[index].raw == value, hex(index)
    for code in (0x0C, 0x0D):  # TIME_OF_DAY / TIME_DIFFERENCE as wire bytes
        index = 0x2000 + code
        sdo.download(index, 0, b"\x10\x27\x00\x00\x05\x00")
        assert od[index][0] == TimeOfDay(10000, 5)
        assert sdo.upload(index, 0) == b"\x10\x27\x00\x00\x05\x00"
    assert sdo[0x1018][1].raw == 0xCA0
    assert sdo[0x1008].raw == "canola interop"


SIZES = sorted({*range(9), 13, 14, 15, 21, 28, 126, 127, 128, 7 * 127 - 1, 7 * 127,
                7 * 127 + 1, 2 * 7 * 127, 2 * 7 * 127 + 1, 4000})


@pytest.mark.parametrize("size", SIZES)
def test_sdo_sizes_every_protocol(peer: Peer, size: int) -> None:
    sdo, od = peer.node.sdo, peer.device.od
    data = bytes((i * 7 + size) & 0xFF for i in range(size))
    # an empty block download has no segment to send: python-canopen sends none and ends
    # with "7 bytes unused", which CiA 301 does not provide for; not tested
    for method in ("auto", "segmented", "block") if size else ("auto", "segmented"):
        od[0x200F][0] = b"old"
        if method == "block":
            with sdo.open(0x200F, 0, "wb", size=size, block_transfer=True) as fp:
                fp.write(data)
        else:
            sdo.download(0x200F, 0, data, force_segment=method == "segmented")
        assert od[0x200F][0] == data, method
        if method == "block":
            with sdo.open(0x200F, 0, "rb", block_transfer=True) as fp:
                assert isinstance(fp, io.IOBase)
                assert fp.read() == data, method
        else:
            assert sdo.upload(0x200F, 0) == data, method
        if 0 < size <= 4:  # device-initiated expedited upload of a short value
            assert sdo.upload(0x200F, 0) == data


@pytest.mark.parametrize(("index", "sub", "write", "code"), [
    (0x5555, 0, None, 0x06020000),  # no object
    (0x1018, 9, None, 0x06090011),  # no sub-index
    (0x2101, 0, None, 0x06010001),  # write-only
    (0x1018, 1, b"\0\0\0\0", 0x06010002),  # read-only
    (0x2007, 0, b"\1\2\3", 0x06070013),  # too short
    (0x2007, 0, b"\1\2\3\4\5", 0x06070012),  # too long
    (0x2102, 0, b"\x65\x00", 0x06090031),  # above the high limit
    (0x5555, 0, b"\1", 0x06020000),
])
def test_sdo_aborts(peer: Peer, index: int, sub: int, write: bytes | None, code: int) -> None:
    with pytest.raises(SdoAbortedError) as exc:
        if write is None:
            peer.node.sdo.upload(index, sub)
        else:
            peer.node.sdo.download(index, sub, write)
    assert exc.value.code == code


# ---- NMT and heartbeat


def test_nmt_and_heartbeat(peer: Peer) -> None:
    nmt, device = peer.node.nmt, peer.device
    assert nmt.wait_for_heartbeat(2.0) == "PRE-OPERATIONAL"
    for command, state in (("OPERATIONAL", "OPERATIONAL"), ("STOPPED", "STOPPED"),
                           ("PRE-OPERATIONAL", "PRE-OPERATIONAL")):
        nmt.state = command
        assert wait_until(lambda state=state: device.nmt_state == state)  # type: ignore[misc]
        assert wait_until(lambda state=state: nmt.wait_for_heartbeat(1.0) == state)  # type: ignore[misc]
    # Listening before the command: python-canopen's wait_for_bootup waits for the next
    # state frame, and misses a boot-up that comes before it starts (a fast device).
    bootups: list[bytes] = []

    def heard(_cob: int, data: bytearray, _stamp: float) -> None:
        if bytes(data) == b"\x00":
            bootups.append(bytes(data))

    peer.network.subscribe(0x700 + NODE, heard)
    try:
        nmt.state = "RESET"
        assert wait_until(lambda: len(bootups) == 1)
    finally:
        peer.network.unsubscribe(0x700 + NODE, heard)
    assert wait_until(lambda: device.nmt_state == "PRE-OPERATIONAL")


def test_scanner_finds_the_device(peer: Peer) -> None:
    peer.network.scanner.search(limit=10)
    assert wait_until(lambda: NODE in peer.network.scanner.nodes)


# ---- PDOs


def test_tpdo_remap_and_data(peer: Peer) -> None:
    node, device = peer.node, peer.device
    node.tpdo.read()
    tpdo = node.tpdo[1]
    assert [v.index for v in tpdo.map] == [0x2100, 0x2005]  # the EDS default mapping
    tpdo.clear()
    tpdo.add_variable(0x2003)  # INTEGER16
    tpdo.add_variable(0x2008)  # REAL32
    tpdo.add_variable(0x2001)  # BOOLEAN (python-canopen maps it as 8 bits)
    tpdo.trans_type = 254
    tpdo.enabled = True
    tpdo.save()
    node.tpdo.read()  # what the device now reports
    assert [(v.index, v.length) for v in node.tpdo[1].map] == [(0x2003, 16), (0x2008, 32),
                                                              (0x2001, 8)]
    tpdo = node.tpdo[1]
    tpdo.subscribe()
    node.nmt.state = "OPERATIONAL"
    assert wait_until(lambda: device.nmt_state == "OPERATIONAL")
    device.od[0x2008][0] = 2.5
    device.od[0x2001][0] = True
    device.od[0x2003][0] = -42  # each write sends the PDO (event-driven)
    assert wait_until(lambda: tpdo[0].raw == -42)
    assert tpdo[1].raw == 2.5
    assert tpdo[2].raw is True or tpdo[2].raw == 1


def test_rpdo_applied(peer: Peer) -> None:
    node, device = peer.node, peer.device
    node.rpdo.read()
    rpdo = node.rpdo[1]
    assert [v.index for v in rpdo.map] == [0x2005, 0x2006]
    applied: list[int] = []
    device.on_rpdo(applied.append)
    node.nmt.state = "OPERATIONAL"
    assert wait_until(lambda: device.nmt_state == "OPERATIONAL")
    rpdo[0].raw = 0x5A
    rpdo[1].raw = 0xBEEF
    rpdo.transmit()
    assert wait_until(lambda: device.od[0x2006][0] == 0xBEEF)
    assert device.od[0x2005][0] == 0x5A
    assert wait_until(lambda: applied == [0])


def test_event_timer_tpdo(peer: Peer) -> None:
    node = peer.node
    node.tpdo.read()
    tpdo = node.tpdo[2]
    tpdo.trans_type = 254
    tpdo.event_timer = 20  # ms
    tpdo.enabled = True
    tpdo.save()
    got: list[float] = []
    tpdo.add_callback(lambda m: got.append(time.monotonic()))
    peer.device.od[0x2006][0] = 0x1234
    node.nmt.state = "OPERATIONAL"
    assert wait_until(lambda: len(got) >= 5)
    assert tpdo[0].raw == 0x1234


def test_sync_tpdo_and_counter(peer: Peer) -> None:
    node, device = peer.node, peer.device
    node.sdo[0x1019].raw = 4  # SYNC counter 1..4
    counters: list[int] = []
    device.on_sync(counters.append)
    node.tpdo.read()
    tpdo = node.tpdo[2]
    tpdo.trans_type = 2  # every second SYNC
    tpdo.enabled = True
    tpdo.save()
    tpdo.subscribe()
    got: list[int] = []
    tpdo.add_callback(lambda m: got.append(m[0].raw))
    node.nmt.state = "OPERATIONAL"
    assert wait_until(lambda: device.nmt_state == "OPERATIONAL")
    for i in range(8):
        device.od[0x2006][0] = 100 + i
        time.sleep(0.02)
        peer.network.sync.transmit(i % 4 + 1)
        assert wait_until(lambda i=i: len(counters) == i + 1)  # type: ignore[misc]
    assert counters == [1, 2, 3, 4, 1, 2, 3, 4]
    assert wait_until(lambda: len(got) == 4)
    assert got == [101, 103, 105, 107]  # sampled at every second SYNC


def test_time(peer: Peer) -> None:
    times: list[TimeOfDay] = []
    peer.device.on_time(times.append)
    moment = 441763200.0 + 86400 * 3 + 3723.5  # 1984-01-01 00:00 UTC + 3 d 1 h 2 m 3.5 s
    peer.network.time.transmit(moment)
    assert wait_until(lambda: len(times) == 1)
    assert times[0] == TimeOfDay(3723500, 3)


def test_emcy(peer: Peer) -> None:
    node, device = peer.node, peer.device
    # python-canopen's log, not its emcy.wait(): a waiter started just before the EMCY may
    # start waiting after it (a busy machine), and wait() only sees later ones
    device.emcy_raise(0x5000, b"\x01\x02\x03")
    assert wait_until(lambda: any(e.code == 0x5000 for e in node.emcy.log))
    err = next(e for e in node.emcy.log if e.code == 0x5000)
    assert (err.code, err.register, err.data) == (0x5000, 0x01, b"\x01\x02\x03\x00\x00")
    assert node.sdo[0x1003][1].raw & 0xFFFF == 0x5000  # bits 16..31: additional information
    device.emcy_clear(0x5000)
    assert wait_until(lambda: any(e.code == 0 for e in node.emcy.log))
    assert not node.emcy.active
