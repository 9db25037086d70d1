# SPDX-License-Identifier: Apache-2.0
"""master.lss (CiA 305) with canola.Devices that have no node-ID (0xFF): fastscan, node-IDs
given, the devices boot; on the simulated bus (virtual time) and on python-can."""

from __future__ import annotations

from collections.abc import Callable

import can
import pytest
from conftest import SDO_TIMEOUT_MS, wait_until
from lss_models import ChattyLssSlave
from managed import PRODUCT, REVISION, VENDOR, model

from canola import Device, Error, Master
from canola.boot_plan import Identity, Network, SlaveSpec
from canola.core import SimBus
from canola.lss import UNCONFIGURED, FastscanTimeLimitError, LssAddress, LssError

SERIALS = (0x300, 0x100, 0x200)


def _unconfigured(bus: SimBus | can.BusABC) -> list[Device]:
    devices = [Device(model(serial=s), UNCONFIGURED, bus) for s in SERIALS]
    for device in devices:
        device.start()
    return devices


def test_fastscan_assign_and_boot() -> None:
    bus = SimBus(500_000)
    master = Master(bus, node_id=1)
    master.start()
    devices = _unconfigured(bus)
    bus.run_for(10_000)
    assert all(d.nmt_state == "INITIALISING" and d.node_id == UNCONFIGURED for d in devices)
    assert [f for f in (line.split()[-1] for line in bus.trace) if f.startswith("7")] == [
        "701#00"]  # the master's boot-up only
    master.lss.timeout_ms = 20
    assert master.lss.count_unconfigured() == 3

    found = master.lss.fastscan()
    assert found == [LssAddress(VENDOR, PRODUCT, REVISION, s) for s in sorted(SERIALS)]
    assert str(found[0]) == "00000CA0:00000302:00010000:00000100"

    for address, node_id in zip(found, (10, 11, 12), strict=True):
        master.lss.set_node_id(address, node_id)
    bus.run_for(10_000)
    by_serial = {d.od[0x1018, 4]: d for d in devices}
    assert [by_serial[s].node_id for s in (0x100, 0x200, 0x300)] == [10, 11, 12]
    assert all(d.nmt_state == "PRE-OPERATIONAL" for d in devices)
    frames = [line.split()[-1] for line in bus.trace]
    assert {"70A#00", "70B#00", "70C#00"} <= set(frames)
    assert master.lss.count_unconfigured() == 0
    assert master.lss.fastscan() == []

    # inquire through the selected device, and the configured devices answer SDO
    assert master.lss.inquire(found[1]) == {"vendor": VENDOR, "product": PRODUCT,
                                            "revision": REVISION, "serial": 0x200,
                                            "node_id": 11}
    assert master.sdo(11).read(0x1018, 4, "u32") == 0x200

    # the manager boots them now that they have node-IDs
    mgr = master.boot(Network(tuple(SlaveSpec(n, identity=Identity(serial=s)) for n, s in
                                    ((10, 0x100), (11, 0x200), (12, 0x300)))))
    assert mgr.started, [str(s) for s in mgr.slaves()]


def test_assign_ids_as_they_are_found() -> None:
    bus = SimBus(500_000)
    master = Master(bus, node_id=1)
    master.start()
    devices = _unconfigured(bus)
    master.lss.timeout_ms = 10
    given = master.lss.assign([20, 21, 22, 23])
    assert sorted(given.values()) == [20, 21, 22]
    assert given[LssAddress(VENDOR, PRODUCT, REVISION, 0x100)] == 20
    bus.run_for(10_000)
    assert sorted(d.node_id for d in devices) == [20, 21, 22]


def test_lss_errors() -> None:
    bus = SimBus(500_000)
    master = Master(bus, node_id=1)
    lss = master.lss
    with pytest.raises(Error, match="not started"):
        lss.fastscan()
    master.start()
    lss.timeout_ms = 10
    nobody = LssAddress(1, 2, 3, 4)
    with pytest.raises(Error, match="no device with address 00000001:00000002"):
        lss.set_node_id(nobody, 5)
    with pytest.raises(LssError, match="LSS inquire vendor: no answer") as info:
        lss.inquire_value("vendor")
    assert info.value.status == "time-out"
    for bad in (0, 128, True):
        with pytest.raises(Error, match=r"outside 1\.\.127"):
            lss.set_node_id(nobody, bad)
    with pytest.raises(Error, match=r"outside 1\.\.65535"):
        lss.timeout_ms = 0
    with pytest.raises(Error, match="cannot inquire"):
        lss.inquire_value("colour")
    with pytest.raises(Error, match="waiting or configuration"):
        lss.switch_global("asleep")
    with pytest.raises(Error, match="LssAddress is needed"):
        lss.select("1:2:3:4")  # type: ignore[arg-type]
    for text in ("1:2:3", "1:2:3:x", "123456789:1:1:1", ""):
        with pytest.raises(Error, match="bad LSS address"):
            LssAddress.parse(text)
    assert LssAddress.parse("0xCA0:302:10000:0x2a") == LssAddress(VENDOR, PRODUCT, REVISION, 42)
    with pytest.raises(Error, match=r"outside 1\.\.127 \(or 0xFF"):
        Device(model(), 0, bus)


def test_refused_node_id() -> None:
    bus = SimBus(500_000)
    master = Master(bus, node_id=1)
    master.start()
    device = Device(model(serial=9), 5, bus)  # configured: LSS may still renumber it
    device.start()
    master.lss.timeout_ms = 10
    address = LssAddress(VENDOR, PRODUCT, REVISION, 9)
    master.lss.select(address)
    with pytest.raises(LssError, match="store configuration: refused with error 1") as info:
        master.lss.store()  # the device has no storage for it
    assert info.value.status == "refused by the slave" and info.value.error == 1
    master.lss.switch_global("waiting")
    master.lss.set_node_id(address, 6)  # taken at the next reset communication
    assert device.node_id == 5
    master.nmt(5, "reset-communication")
    bus.run_for(10_000)
    assert device.node_id == 6


@pytest.mark.realtime
def test_lss_on_python_can(can_bus: Callable[[], can.BusABC]) -> None:
    """LSS over python-can's threads: identify, select, configure, inquire, the device boots.
    Requests that end on an answer wait for it (the time-out only bounds them); a fastscan
    reads a missing answer as a bit, so it runs in virtual time only (above, and the CLI's
    in test_cli_302)."""
    master = Master(can_bus(), node_id=1, sdo_timeout_ms=SDO_TIMEOUT_MS)
    device = Device(model(serial=0x100), UNCONFIGURED, can_bus())
    with master, device:
        master.lss.timeout_ms = 2000  # answers of starved threads come late, not never
        assert master.lss.count_unconfigured() == 1
        address = LssAddress(VENDOR, PRODUCT, REVISION, 0x100)
        master.lss.set_node_id(address, 30)
        assert wait_until(lambda: device.nmt_state == "PRE-OPERATIONAL")
        assert device.node_id == 30
        assert master.lss.inquire(address)["node_id"] == 30
        assert master.sdo(30).read(0x1018, 4, "u32") == 0x100


# ---- slaves that answer every fastscan request in configuration (CANopenNode's)

CHATTY = ((0x2E0, 0x17, 3, 0x100), (0x2E0, 0x17, 3, 0x200))


def test_fastscan_against_slaves_that_answer_in_configuration() -> None:
    bus = SimBus(500_000)
    master = Master(bus, node_id=1)
    master.start()
    slaves = [ChattyLssSlave(bus, a, port_id=100 + i) for i, a in enumerate(CHATTY)]
    master.lss.timeout_ms = 10
    # the one found is switched back to waiting (left in configuration it would confirm
    # every bit: the all-zero address, again and again); the next scan is above it
    assert master.lss.fastscan(max_devices=3) == [LssAddress(*a) for a in CHATTY]
    bus.run_for(10_000)
    assert not any(s.configuration for s in slaves)
    # each one given a node-ID makes way for the next
    given = master.lss.assign([30, 31, 32])
    assert given == {LssAddress(*CHATTY[0]): 30, LssAddress(*CHATTY[1]): 31}
    assert [s.node_id for s in slaves] == [30, 31]
    assert master.lss.fastscan() == []


#: Slaves that answer in configuration, lowest address first: serial numbers one bit
#: apart and far apart, then a higher revision with a lower serial, a higher product, a
#: higher vendor (each a scan above the one before that differs in another part).
MANY_CHATTY = ((0x2E0, 0x17, 3, 0x100), (0x2E0, 0x17, 3, 0x101), (0x2E0, 0x17, 3, 0x80000000),
               (0x2E0, 0x17, 4, 0x50), (0x2E0, 0x18, 0, 7), (0x2E1, 1, 1, 1))


def test_fastscan_lists_every_slave_that_answers_in_configuration() -> None:
    """Several CANopenNode-style slaves without node-ID, and CiA 305 ones among them (a
    canola.Device below, between and above them): one scan lists them all, once each."""
    bus = SimBus(500_000)
    master = Master(bus, node_id=1)
    master.start()
    chatty = [ChattyLssSlave(bus, a, port_id=100 + i) for i, a in enumerate(MANY_CHATTY)]
    plain = [(0x100, PRODUCT, REVISION, 9), (0x2E0, 0x17, REVISION, 9),
             (VENDOR, PRODUCT, REVISION, 9)]
    for vendor, product, _, serial in plain:
        Device(model(vendor=vendor, product=product, serial=serial), UNCONFIGURED,
               bus).start()
    master.lss.timeout_ms = 10
    mark = len(bus.trace)
    found = master.lss.fastscan()
    assert found == sorted(LssAddress(*a) for a in (*MANY_CHATTY, *plain))
    bus.run_for(10_000)
    assert not any(s.configuration for s in chatty)  # all back in waiting
    # above 0x100, the neighbour 0x101: reset, the three parts, bit 0, its verify, the
    # probe (7 requests where a whole scan takes 134)
    frames = [line.split()[-1] for line in bus.trace[mark:]]
    switch = [i for i, f in enumerate(frames) if f == "7E5#0400000000000000"]
    between = [f for f in frames[switch[0]:switch[1]] if f.startswith("7E5#51")]
    assert len(between) == 7
    # and all of them get node-IDs
    given = master.lss.assign(range(20, 20 + len(found)))
    assert sorted(given) == found
    assert master.lss.fastscan() == []


def test_fastscan_time_limit() -> None:
    bus = SimBus(500_000)
    master = Master(bus, node_id=1)
    master.start()
    _unconfigured(bus)
    master.lss.timeout_ms = 10
    began = bus.now_us
    with pytest.raises(FastscanTimeLimitError) as exc:
        # 134 steps of 10 ms for the first device, 24 for the one above it: one fits
        master.lss.fastscan(time_limit=1.5)
    assert exc.value.found == [LssAddress(VENDOR, PRODUCT, REVISION, 0x100)]
    assert "not done within 1.5 s (found so far: 00000CA0:00000302:00010000:00000100)" in str(
        exc.value)
    assert bus.now_us - began <= 1_600_000
    with pytest.raises(Error, match="time_limit must be positive"):
        master.lss.fastscan(time_limit=0)
    with pytest.raises(Error, match="max_devices 0 is outside"):
        master.lss.fastscan(max_devices=0)
