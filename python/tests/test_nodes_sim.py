# SPDX-License-Identifier: Apache-2.0
"""canola.Device and canola.Master on the simulated bus: virtual time, deterministic."""

from __future__ import annotations

import asyncio
import datetime as dt
import threading
from pathlib import Path

import pytest

import canola
from canola import Device, Error, Master, SdoAbort, SdoTimeout
from canola.core import SimBus
from canola.formats.values import TimeOfDay
from canola.master import EmcyEvent, Frame, HeartbeatEvent

DATA = Path(__file__).parent / "data"
INTEROP = DATA / "interop.eds"
SAMPLE = Path(__file__).parent / "golden" / "sample.eds"


@pytest.fixture
def net() -> tuple[SimBus, Master, Device]:
    bus = SimBus()
    master = Master(bus, node_id=1)
    device = Device(INTEROP, 5, bus)
    master.start()
    device.start()
    bus.run_for(1000)
    return bus, master, device


def _frames(bus: SimBus) -> list[str]:
    return [line.split()[-1] for line in bus.trace]


def test_boot_and_nmt(net: tuple[SimBus, Master, Device]) -> None:
    bus, master, device = net
    assert "705#00" in _frames(bus)
    assert device.nmt_state == "PRE-OPERATIONAL"
    states: list[str] = []
    device.on_state(states.append)
    master.nmt(5, "start")
    assert device.nmt_state == "OPERATIONAL"
    master.nmt(0, "preop")
    assert device.nmt_state == "PRE-OPERATIONAL"
    master.nmt(5, "stop")
    assert device.nmt_state == "STOPPED"
    assert master.nmt_state == "PRE-OPERATIONAL"  # node 0 does not touch the master
    master.nmt(5, "reset-node")
    bus.run_for(1000)
    assert device.nmt_state == "PRE-OPERATIONAL"
    assert states == ["OPERATIONAL", "PRE-OPERATIONAL", "STOPPED", "INITIALISING",
                      "PRE-OPERATIONAL"]
    assert _frames(bus).count("705#00") == 2  # boot-up again after the reset
    with pytest.raises(Error, match="unknown NMT command"):
        master.nmt(5, "jump")
    with pytest.raises(Error, match=r"outside 0\.\.127"):
        master.nmt(128, "start")


def test_sdo_round_trips(net: tuple[SimBus, Master, Device]) -> None:
    _, master, device = net
    sdo = master.sdo(5)
    assert sdo.upload(0x1008, 0) == b"canola interop"
    assert sdo.read(0x1018, 1, "u32") == 0xCA0
    sdo.write(0x2003, 0, "i16", -1234)
    assert device.od[0x2003][0] == -1234
    for block in (False, True):
        data = bytes(range(256)) * 3
        sdo.download(0x200F, 0, data, block=block)
        assert device.od[0x200F, 0] == data
        assert sdo.upload(0x200F, 0, block=block) == data
    written: list[tuple[int, int, object]] = []
    device.on_write(lambda i, s, v: written.append((i, s, v)))
    sdo.write(0x2009, 0, "vs", "hello")
    device.od[0x2009][0] = "from the app"  # application writes are not reported
    assert written == [(0x2009, 0, "hello")]


def test_sdo_aborts_and_timeout(net: tuple[SimBus, Master, Device]) -> None:
    _, master, _ = net
    sdo = master.sdo(5)
    for index, sub, code in ((0x5555, 0, 0x06020000), (0x1018, 9, 0x06090011),
                             (0x2101, 0, 0x06010001)):
        with pytest.raises(SdoAbort) as exc:
            sdo.upload(index, sub)
        assert exc.value.code == code
    with pytest.raises(SdoAbort) as exc:
        sdo.download(0x1018, 1, b"\0\0\0\0")
    assert exc.value.code == 0x06010002
    with pytest.raises(SdoAbort) as exc:
        sdo.download(0x2102, 0, (5).to_bytes(2, "little"))
    assert exc.value.code == 0x06090032
    with pytest.raises(SdoTimeout) as tmo:
        master.sdo(9).upload(0x1000, 0)
    assert tmo.value.code == 0x05040000
    assert str(tmo.value) == "no response from node 9 (SDO time-out 1000 ms, after 1.00 s)"
    with pytest.raises(SdoTimeout, match=r"SDO time-out 200 ms"):
        master.sdo(9).upload(0x1000, 0, timeout=0.2)
    assert master.sdo(5).upload(0x1000, 0) == (0x191).to_bytes(4, "little")  # still usable


def test_sdo_answer_timeout(net: tuple[SimBus, Master, Device]) -> None:
    bus, master, _ = net
    began = bus.now_us
    with pytest.raises(SdoTimeout, match=r"SDO time-out 50 ms"):  # not the master's 1000
        master.sdo(9).upload(0x1000, 0, answer_timeout=0.05)
    assert 50_000 <= bus.now_us - began < 52_000  # virtual time: the core's own time-out
    trace = [f for f in _frames(bus) if f.startswith("609#")]
    assert trace[-1] == "609#8000100000000405"  # the abort went out to the node
    with pytest.raises(SdoTimeout, match=r"SDO time-out 50 ms"):  # not the whole 10 s
        master.sdo(9).upload(0x1000, 0, timeout=10, answer_timeout=0.05)
    began = bus.now_us
    with pytest.raises(SdoTimeout, match=r"SDO time-out 1000 ms"):  # the next: the master's
        master.sdo(9).download(0x2000, 0, b"\x01")
    assert 1_000_000 <= bus.now_us - began < 1_002_000
    began = bus.now_us
    with pytest.raises(SdoTimeout, match=r"SDO time-out 20 ms"):
        asyncio.run(master.sdo(9).adownload(0x2000, 0, b"\x01", answer_timeout=0.02))
    assert 20_000 <= bus.now_us - began < 22_000
    for bad in (0, 0.0004, 65.536, -1):
        with pytest.raises(Error, match="answer_timeout"):
            master.sdo(5).upload(0x1000, 0, answer_timeout=bad)
    assert master.sdo(5).upload(0x1000, 0, answer_timeout=0.01) == (0x191).to_bytes(4, "little")


def test_async_on_simbus(net: tuple[SimBus, Master, Device]) -> None:
    _, master, _ = net

    async def go() -> bytes:
        await master.sdo(5).adownload(0x2007, 0, b"\x01\x02\x03\x04")
        return await master.sdo(5).aupload(0x2007, 0)

    assert asyncio.run(go()) == b"\x01\x02\x03\x04"


def test_heartbeat_monitoring(net: tuple[SimBus, Master, Device]) -> None:
    bus, master, device = net
    events: list[HeartbeatEvent] = []
    master.on_heartbeat(events.append)
    master.monitor(5, 250)  # device beats every 100 ms (0x1017)
    bus.run_for(300_000)
    assert [e.kind for e in events] == ["started"]
    assert master.heartbeat_state(5) == "PRE-OPERATIONAL"
    master.nmt(5, "start")
    bus.run_for(200_000)
    assert events[-1].kind == "state" and events[-1].state == "OPERATIONAL"
    device.od[0x1017][0] = 0  # silence
    bus.run_for(400_000)
    assert events[-1].kind == "lost" and events[-1].node == 5
    device.od[0x1017][0] = 100
    bus.run_for(300_000)
    assert events[-1].kind == "resumed"


def test_emcy(net: tuple[SimBus, Master, Device]) -> None:
    bus, master, device = net
    got: list[EmcyEvent] = []
    master.on_emcy(got.append)
    device.emcy_raise(0x4210, b"\x01\x02")
    bus.run_for(1000)
    assert (got[0].node, got[0].code, got[0].register, got[0].manufacturer) == (
        5, 0x4210, 0x09, b"\x01\x02\0\0\0")
    assert device.od[0x1001][0] == 0x09
    assert device.emcy_active(0x4210)
    device.emcy_clear(0x4210)
    bus.run_for(1000)
    assert got[-1].code == 0 and got[-1].register == 0
    with pytest.raises(Error, match="not active"):
        device.emcy_clear(0x4210)
    with pytest.raises(Error, match="at most 5 bytes"):
        device.emcy_raise(0x1000, b"123456")


def test_pdos_sync_time(net: tuple[SimBus, Master, Device]) -> None:
    bus, master, device = net
    frames: list[Frame] = []
    master.on_frame(frames.append, cob_id=0x185)
    master.nmt(5, "start")
    device.od[0x2005][0] = 0x42  # mapped into TPDO1 (event-driven): sent at once
    bus.run_for(1000)
    assert frames[-1].data == bytes.fromhex("4433221142")
    # RPDO1 maps 0x2005 (8 bits) and 0x2006 (16 bits)
    rpdos: list[int] = []
    device.on_rpdo(rpdos.append)
    master.send_pdo(0x205, b"\x07\x34\x12")
    bus.run_for(1000)
    assert rpdos == [0] and device.od[0x2006][0] == 0x1234
    # SYNC with a counter, consumed by the device
    counters: list[int] = []
    device.on_sync(counters.append)
    device.od[0x1019][0] = 3  # a consumer expects the counter too (else EMCY 0x8240)
    master.start_sync(10_000, overflow=3)
    bus.run_for(45_000)
    assert counters == [1, 2, 3, 1]
    master.stop_sync()
    bus.run_for(50_000)
    assert len(counters) == 4
    # TIME: the device consumes it (0x1012 bit 31)
    times: list[TimeOfDay] = []
    device.on_time(times.append)
    master.send_time(dt.datetime(1984, 1, 3, 0, 0, 1, tzinfo=dt.UTC))
    bus.run_for(1000)
    assert times == [TimeOfDay(1000, 2)]
    assert "100#E80300000200" in _frames(bus)
    # periodic TIME, from a clock of the application's
    ticks = iter(range(100))
    began = bus.now_us
    master.start_time(100, clock=lambda: dt.datetime(1984, 1, 1, 0, 0, next(ticks),
                                                      tzinfo=dt.UTC))
    bus.run_for(350_000)
    master.stop_time()
    bus.run_for(300_000)
    assert times[1:] == [TimeOfDay(0, 0), TimeOfDay(1000, 0), TimeOfDay(2000, 0)]
    stamps = [line.split()[0] for line in bus.trace if " 100#" in line]
    assert stamps[1:] == [f"({(began + k * 100_000) / 1e6:.6f})" for k in (1, 2, 3)]


def test_store_dir(tmp_path: Path) -> None:
    bus = SimBus()
    master = Master(bus, node_id=1)
    device = Device(INTEROP, 5, bus, store_dir=tmp_path)
    master.start()
    device.start()
    master.sdo(5).write(0x2006, 0, "u16", 777)
    master.sdo(5).write(0x1010, 1, "u32", 0x65766173)  # "save"
    assert {p.name for p in tmp_path.iterdir()} >= {"comm.params", "app.params"}
    master.sdo(5).write(0x2006, 0, "u16", 1)
    master.nmt(5, "reset-node")
    bus.run_for(1000)
    assert device.od[0x2006][0] == 777  # the stored value is the power-on value
    master.sdo(5).write(0x1011, 1, "u32", 0x64616F6C)  # "load"
    master.nmt(5, "reset-node")
    bus.run_for(1000)
    assert device.od[0x2006][0] == 6  # the EDS default again
    with pytest.raises(Error, match="not a folder"):
        Device(INTEROP, 6, bus, store_dir=tmp_path / "missing")


def test_local_od_typed(net: tuple[SimBus, Master, Device]) -> None:
    _, _, device = net
    od = device.od
    assert od[0x2001][0] is False
    od[0x2001][0] = True
    assert od[0x2001, 0] is True
    assert od[0x2008].value == 1.5
    od[0x2011][0] = -0.125
    assert od[0x2011][0] == -0.125
    od[0x201B][0] = 2**64 - 1
    assert od[0x201B][0] == 2**64 - 1
    assert od[0x200A][0] == b"\x01\x02\x03"
    od[0x200B][0] = "żółw"
    assert od[0x200B][0] == "żółw"
    od[0x200C][0] = TimeOfDay(1234, 5)
    assert od[0x200C][0] == TimeOfDay(1234, 5)
    od[0x1018][1] = 7  # the application may set read-only entries
    assert od[0x1018][1] == 7
    with pytest.raises(canola.values.ValueFormatError, match="outside INTEGER8"):
        od[0x2002][0] = 200
    with pytest.raises(SdoAbort) as exc:
        od[0x2102][0] = 101
    assert exc.value.code == 0x06090031
    with pytest.raises(SdoAbort) as exc:
        od[0x7777][0] = 1
    assert exc.value.code == 0x06020000
    with pytest.raises(SdoAbort) as exc:
        _ = od[0x1018][9]
    assert exc.value.code == 0x06090011
    assert (0x1018, 4) in od and 0x1018 in od and 0x7777 not in od


def test_bad_construction() -> None:
    bus = SimBus()
    with pytest.raises(Error, match=r"outside 1\.\.127"):
        Device(INTEROP, 0, bus)
    with pytest.raises(Error, match="bus must be"):
        Device(INTEROP, 5, object())  # type: ignore[arg-type]
    with pytest.raises(Error, match="master itself"):
        Master(bus, node_id=3).sdo(3)
    master = Master(bus, node_id=4)
    with pytest.raises(Error, match="not started"):
        master.sdo(5).upload(0x1000, 0)
    with pytest.raises(Error, match="cannot read file"):
        Device(DATA / "missing.eds", 5, bus)
    with pytest.raises(Error, match="sdo_timeout_ms 0"):
        Master(bus, node_id=2, sdo_timeout_ms=0)
    with pytest.raises(Error, match="CAN-ID 2048"):
        master.send(0x800)
    with pytest.raises(Error, match="at most 8 bytes"):
        master.send_pdo(0x205, bytes(9))
    with pytest.raises(Error, match="counter overflow 1"):
        master.start_sync(1000, overflow=1)
    with pytest.raises(Error, match="cannot monitor node 4"):
        master.monitor(4, 100)
    master.start()
    with pytest.raises(Error, match="sub-index 256"):
        master.sdo(5).upload(0x1000, 256)
    with pytest.raises(Error, match="index 65536"):
        master.sdo(5).download(0x10000, 0, b"")


def test_deterministic() -> None:
    def run() -> list[str]:
        bus = SimBus(bitrate=500_000)
        master = Master(bus, node_id=1)
        device = Device(INTEROP, 5, bus)
        master.start()
        device.start()
        master.nmt(0, "start")
        master.start_sync(5000)
        master.sdo(5).upload(0x1008, 0, block=True)
        bus.run_for(100_000)
        return bus.trace

    assert run() == run()


def test_values_larger_than_the_sdo_buffer_into_ram_entries() -> None:
    """A DOMAIN (and a string) in RAM takes SDO downloads up to its own size, by segmented
    and by block transfer: the server's buffer (4 KiB here) frames the transfer only."""
    bus = SimBus()
    master = Master(bus, node_id=1)
    device = Device(SAMPLE, 2, bus, domain_size=65536, string_size=10_000)
    master.start()
    device.start()
    bus.run_for(10_000)
    data = bytes(range(256)) * 20  # 5,120 bytes
    master.sdo(2).download(0x2200, 0, data[:5000])
    assert device.od.read(0x2200, 0) == data[:5000]
    big = data * 12 + data[:4096]  # 65,536 bytes: the whole room
    master.sdo(2).download(0x2200, 0, big, block=True)
    assert device.od.read(0x2200, 0) == big
    assert master.sdo(2).upload(0x2200, 0, block=True, max_size=70_000) == big
    with pytest.raises(SdoAbort) as exc:
        master.sdo(2).download(0x2200, 0, big + b"!")
    assert exc.value.code == 0x06070012  # longer than the entry: its own abort code
    text = "canola " * 1400  # 9,800 characters
    master.sdo(2).write(0x2013, 0, "vs", text)
    assert master.sdo(2).read(0x2013, 0, "vs", max_size=20_000) == text


def test_visible_string_in_utf8(net: tuple[SimBus, Master, Device]) -> None:
    _, master, device = net
    master.sdo(5).write(0x2009, 0, "vs", "2 € / µm")
    assert device.od.read(0x2009, 0).rstrip(b"\0") == "2 € / µm".encode()
    assert device.od[0x2009, 0] == "2 € / µm"
    assert master.sdo(5).read(0x2009, 0, "vs") == "2 € / µm"


def test_master_announces_itself_unless_told_not_to() -> None:
    bus = SimBus()
    member = Master(bus, node_id=0x3F)
    tool = Master(bus, node_id=0x7F, announce=False)
    device = Device(INTEROP, 5, bus)
    for node in (member, tool, device):
        node.start()
    for master in (member, tool):
        master.od[0x1017, 0] = 50  # a heartbeat every 50 ms
    bus.run_for(200_000)
    tool.send(0x73F, rtr=True)  # node guarding of the tool's node: no answer either
    member.send(0x77F, rtr=True)
    bus.run_for(100_000)
    frames = _frames(bus)
    assert frames[0] == "73F#00" and frames.count("73F#7F") >= 3  # boot-up, heartbeats
    assert [f for f in frames if f.startswith("77F#")] == ["77F#R"]  # the request only
    assert tool.sdo(5).read(0x1018, 1, "u32") == 0xCA0  # it works all the same
    tool.nmt(0, "reset-communication")  # its own reset (from the member) stays quiet too
    member.nmt(0x7F, "reset-communication")
    bus.run_for(10_000)
    assert not any(f.startswith("77F#") and f != "77F#R" for f in _frames(bus))


def test_a_node_observes_the_frames_it_sends() -> None:
    """on_frame_sent: every frame of this node, in order, none of the others'; an EMCY on
    the COB-ID its 0x1014 holds, changed or not."""
    bus = SimBus()
    master = Master(bus, node_id=1)
    device = Device(INTEROP, 5, bus)
    sent: list[Frame] = []
    mine: list[Frame] = []
    device.on_frame_sent(sent.append)
    master.on_frame_sent(mine.append)
    master.start()
    device.start()
    bus.run_for(1000)
    assert master.sdo(5).upload(0x1018, 4) == b"\x78\x56\x34\x12"
    device.emcy_raise(0x5000, b"\x01")
    device.od.set(0x1014, 0, 0x80000085)  # invalid first, then a new COB-ID
    device.od.set(0x1014, 0, 0x0A5)
    device.emcy_raise(0x6000)
    bus.run_for(1000)
    assert [(f.can_id, f.data.hex()) for f in sent] == [
        (0x705, "00"), (0x585, "4318100478563412"), (0x085, "0050010100000000"),
        (0x0A5, "0060010000000000")]
    assert [f.timestamp for f in sent] == sorted(f.timestamp for f in sent)
    assert [f.can_id for f in mine] == [0x701, 0x605]
    assert [f.split()[-1][:3] for f in bus.trace if "#" in f] == \
        ["701", "705", "605", "585", "085", "0A5"]


def _time_frames(master: Master) -> list[float]:
    """The virtual instants of the TIME frames ``master`` sends (filled as it sends)."""
    instants: list[float] = []
    master.on_frame_sent(lambda f: instants.append(f.timestamp) if f.can_id == 0x100 else None)
    return instants


def test_stop_time_skips_a_run_already_queued() -> None:
    """Two masters' TIME timers fall due at the same instant; the first one's run stops
    the second's, whose run is queued by then: it must not send after stop_time."""
    bus = SimBus()
    first = Master(bus, node_id=2)  # its callbacks run first at an instant
    second = Master(bus, node_id=1)
    first.start()
    second.start()
    sent = _time_frames(second)
    at_stop: list[int] = []

    def stop_the_other() -> dt.datetime:
        second.stop_time()
        at_stop.append(len(sent))
        return dt.datetime(2024, 1, 1, tzinfo=dt.UTC)

    second.start_time(50)
    first.start_time(50, clock=stop_the_other)
    bus.run_for(1_000_000)
    assert at_stop and at_stop[0] == 0
    assert sent == []


def test_stop_time_waits_for_a_run_in_progress() -> None:
    """A TIME run in progress in the bus's thread when another thread stops TIME: stop_time
    returns after that run's frame, and nothing follows it."""
    bus = SimBus()
    master = Master(bus, node_id=1)
    master.start()
    sent = _time_frames(master)
    entered, release = threading.Event(), threading.Event()

    def slow_clock() -> dt.datetime:
        entered.set()
        release.wait(30)
        return dt.datetime(2024, 1, 1, tzinfo=dt.UTC)

    master.start_time(50, clock=slow_clock)
    runner = threading.Thread(target=bus.run_for, args=(1_000_000,))
    runner.start()
    assert entered.wait(30)
    at_return: list[int] = []
    stopper = threading.Thread(target=lambda: (master.stop_time(), at_return.append(len(sent))))
    stopper.start()
    stopper.join(0.5)  # a bound, not an expectation: stop_time waits for the run (fixed)
    release.set()
    stopper.join(30)
    runner.join(30)
    assert not stopper.is_alive() and not runner.is_alive()
    assert at_return == [1]  # the run's frame went out before stop_time returned
    bus.run_for(1_000_000)
    assert len(sent) == 1
