# SPDX-License-Identifier: Apache-2.0
"""canola.Master against python-canopen's LocalNode (an independent SDO server and NMT
slave) over python-can: SDO expedited and segmented, aborts, time-outs, NMT, heartbeat,
boot-up and EMCY events, SYNC and TIME production, raw PDO frames, asyncio."""

from __future__ import annotations

import asyncio
import datetime as dt
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import can
import canopen
import pytest
from conftest import SDO_TIMEOUT_MS, wait_until

from canola import Device, Master, SdoAbort, SdoTimeout
from canola.master import EmcyEvent, Frame, HeartbeatEvent

pytestmark = [pytest.mark.realtime, pytest.mark.vcan]

INTEROP = Path(__file__).parent / "data" / "interop.eds"
LOCAL = 10


class Net:
    def __init__(self, master: Master, network: canopen.Network, local: Any) -> None:
        self.master = master
        self.network = network
        self.local = local


@pytest.fixture
def net(can_bus: Callable[[], can.BusABC]) -> Iterator[Net]:
    network = canopen.Network(can_bus())
    network.connect()
    local = canopen.LocalNode(LOCAL, str(INTEROP))
    network.add_node(local)
    # python-canopen's answers in the SocketCAN tier's emulated VM may take over a second
    master = Master(can_bus(), node_id=1, sdo_timeout_ms=SDO_TIMEOUT_MS)
    master.start()
    try:
        yield Net(master, network, local)
    finally:
        master.stop()
        local.nmt.stop_heartbeat()
        network.disconnect()


def test_sdo_expedited_and_segmented(net: Net) -> None:
    sdo, local = net.master.sdo(LOCAL), net.local
    assert sdo.read(0x1018, 1, "u32") == 0xCA0  # expedited
    assert sdo.read(0x1008, 0, "vs") == "canola interop"  # segmented
    sdo.write(0x2007, 0, "u32", 0xDEADBEEF)  # expedited download
    assert local.sdo[0x2007].raw == 0xDEADBEEF
    sdo.write(0x2009, 0, "vs", "a visible string longer than one segment")
    assert local.sdo[0x2009].raw == "a visible string longer than one segment"
    data = bytes(range(200))
    sdo.download(0x200F, 0, data)
    assert local.sdo.upload(0x200F, 0) == data
    assert sdo.upload(0x200F, 0) == data
    sdo.write(0x2004, 0, "i32", -5)
    assert sdo.read(0x2004, 0, "i32") == -5


def test_sdo_abort_from_python_canopen(net: Net) -> None:
    with pytest.raises(SdoAbort) as exc:
        net.master.sdo(LOCAL).upload(0x5555, 0)
    assert exc.value.code == 0x06020000
    with pytest.raises(SdoAbort) as exc:
        net.master.sdo(LOCAL).download(0x5555, 0, b"\1")
    assert exc.value.code == 0x06020000
    assert net.master.sdo(LOCAL).read(0x1018, 2, "u32") == 0x1E0  # the channel still works


@pytest.mark.slow
def test_sdo_timeout(net: Net) -> None:
    began = time.monotonic()
    with pytest.raises(SdoTimeout) as exc:
        net.master.sdo(99).upload(0x1000, 0)
    assert exc.value.code == 0x05040000
    assert str(exc.value).startswith(
        f"no response from node 99 (SDO time-out {SDO_TIMEOUT_MS} ms, after ")
    assert exc.value.by_server is False
    assert time.monotonic() - began >= SDO_TIMEOUT_MS / 1000 * 0.9  # never before it
    began = time.monotonic()
    with pytest.raises(SdoTimeout, match="SDO time-out 150 ms"):  # the request's own
        net.master.sdo(99).upload(0x1000, 0, timeout=0.15)
    assert time.monotonic() - began >= 0.1


def test_nmt(net: Net) -> None:
    master, local = net.master, net.local
    master.nmt(LOCAL, "start")
    assert wait_until(lambda: local.nmt.state == "OPERATIONAL")
    master.nmt(0, "stop")
    assert wait_until(lambda: local.nmt.state == "STOPPED")
    master.nmt(LOCAL, "preop")
    assert wait_until(lambda: local.nmt.state == "PRE-OPERATIONAL")
    assert master.nmt_state == "PRE-OPERATIONAL"  # node 0 leaves the master alone


def test_heartbeat_bootup_emcy_events(net: Net) -> None:
    master, local = net.master, net.local
    beats: list[HeartbeatEvent] = []
    boots: list[int] = []
    emcys: list[EmcyEvent] = []
    master.on_heartbeat(beats.append)
    master.on_bootup(boots.append)
    master.on_emcy(emcys.append)
    master.monitor(LOCAL, 300)
    local.nmt.state = "RESET"  # python-canopen's slave sends its boot-up
    assert wait_until(lambda: boots == [LOCAL])
    local.nmt.state = "PRE-OPERATIONAL"
    local.nmt.start_heartbeat(50)
    assert wait_until(lambda: any(e.kind == "started" for e in beats))
    assert master.heartbeat_state(LOCAL) == "PRE-OPERATIONAL"
    master.nmt(LOCAL, "start")
    assert wait_until(lambda: beats[-1].kind == "state" and beats[-1].state == "OPERATIONAL")
    local.nmt.stop_heartbeat()
    assert wait_until(lambda: beats[-1].kind == "lost" and beats[-1].node == LOCAL)
    local.nmt.start_heartbeat(50)
    assert wait_until(lambda: beats[-1].kind == "resumed")
    local.emcy.send(0x2310, 0x03, b"\x01\x02")
    assert wait_until(lambda: len(emcys) == 1)
    assert (emcys[0].node, emcys[0].code, emcys[0].register, emcys[0].manufacturer) == (
        LOCAL, 0x2310, 0x03, b"\x01\x02\0\0\0")


def test_sync_time_and_pdo_frames(net: Net) -> None:
    master, network = net.master, net.network
    syncs: list[bytes] = []
    times: list[bytes] = []
    rpdos: list[bytes] = []
    network.subscribe(0x80, lambda can_id, data, ts: syncs.append(bytes(data)))
    network.subscribe(0x100, lambda can_id, data, ts: times.append(bytes(data)))
    network.subscribe(0x20A, lambda can_id, data, ts: rpdos.append(bytes(data)))
    master.start_sync(20_000, overflow=5)
    assert wait_until(lambda: len(syncs) >= 7)
    master.stop_sync()
    counters = [s[0] for s in syncs[:7]]
    assert counters == [1, 2, 3, 4, 5, 1, 2]
    master.send_time(dt.datetime(1984, 1, 2, 0, 0, 2, tzinfo=dt.UTC))
    assert wait_until(lambda: times == [bytes.fromhex("D00700000100")])
    master.send_pdo(0x20A, b"\x01\x02\x03")
    assert wait_until(lambda: rpdos == [b"\x01\x02\x03"])
    frames: list[Frame] = []
    master.on_frame(frames.append, cob_id=0x18A)
    network.send_message(0x18A, b"\xAA\xBB")
    assert wait_until(lambda: len(frames) == 1)
    assert frames[0].data == b"\xAA\xBB"


def test_asyncio_in_parallel(net: Net, can_bus: Callable[[], can.BusABC]) -> None:
    device = Device(INTEROP, 5, can_bus())
    with device:
        master = net.master

        async def both() -> list[bytes]:
            return await asyncio.gather(
                master.sdo(LOCAL).aupload(0x1008, 0),
                master.sdo(5).aupload(0x1008, 0, block=True),
                master.sdo(5).aupload(0x1018, 1),  # waits for the transfer before it
            )

        assert asyncio.run(both()) == [b"canola interop", b"canola interop",
                                       (0xCA0).to_bytes(4, "little")]

        async def missing() -> bytes:
            return await master.sdo(5).aupload(0x5555, 0)

        with pytest.raises(SdoAbort) as exc:
            asyncio.run(missing())
        assert exc.value.code == 0x06020000

        async def silent() -> bytes:
            return await master.sdo(98).aupload(0x1000, 0, timeout=0.1)

        with pytest.raises(SdoTimeout, match="node 98"):
            asyncio.run(silent())


def test_periodic_time(net: Net) -> None:
    times: list[float] = []
    net.network.subscribe(0x100, lambda can_id, data, ts: times.append(time.monotonic()))
    net.master.start_time(50)
    assert wait_until(lambda: len(times) >= 4)
    net.master.stop_time()
    # A frame sent after the stop: once it arrived, so did every TIME frame before it.
    marks: list[bytes] = []
    net.network.subscribe(0x7F0, lambda can_id, data, ts: marks.append(data))
    net.master.send(0x7F0, b"\x01")
    assert wait_until(lambda: marks == [b"\x01"], 30)
    count = len(times)
    time.sleep(0.3)  # six periods
    assert len(times) == count  # stopped
