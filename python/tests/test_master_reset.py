# SPDX-License-Identifier: Apache-2.0
"""canola.Master after its own node was reset (NMT reset node / reset communication, to
its node-ID or to all, from another bus participant or the gateway's own commands): it
serves every node again, those it talked to before included; the manager on it boots the
network again. Simulated bus (virtual time), python-can's virtual bus, the gateway."""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable
from pathlib import Path

import can
import pytest
from conftest import SDO_TIMEOUT_MS, wait_until
from gateway_helpers import Client, run
from managed import VENDOR, model
from test_gateway_master import serve

from canola import Device, Master
from canola.boot_plan import Identity, Network, SlaveSpec
from canola.core import SimBus
from canola.master import HeartbeatEvent

SAMPLE = Path(__file__).parent / "golden" / "sample.eds"
MASTER = 1

#: NMT reset frames another participant sends: reset node / reset communication, to the
#: master's node-ID or to all.
RESETS = {"reset-comm-all": b"\x82\x00", "reset-node-all": b"\x81\x00",
          "reset-comm-master": bytes([0x82, MASTER]), "reset-node-master": bytes([0x81, MASTER])}


def _network(bus: SimBus | Callable[[], can.BusABC]) -> tuple[Master, Master, list[Device]]:
    """The master (node 1), another participant (node 9) and devices 2..4."""
    new = (lambda: bus) if isinstance(bus, SimBus) else bus
    master = Master(new(), node_id=MASTER,
                    sdo_timeout_ms=500 if isinstance(bus, SimBus) else SDO_TIMEOUT_MS)
    other = Master(new(), node_id=9)
    devices = [Device(model(serial=n), n, new()) for n in (2, 3, 4)]
    for node in (master, other, *devices):
        node.start()
    return master, other, devices


@pytest.mark.parametrize("reset", list(RESETS))
def test_master_serves_every_node_after_a_reset(reset: str) -> None:
    bus = SimBus(500_000)
    master, other, _ = _network(bus)
    bus.run_for(10_000)
    assert master.sdo(2).read(0x1018, 4, "u32") == 2
    assert master.sdo(3).read(0x1018, 4, "u32") == 3
    before = len(bus.trace)
    other.send(0x000, RESETS[reset])
    bus.run_for(10_000)
    assert f"{0x700 + MASTER:03X}#00" in [line.split()[-1] for line in bus.trace[before:]]
    assert master.nmt_state == "PRE-OPERATIONAL"
    assert master.sdo(2).read(0x1018, 4, "u32") == 2  # used before the reset
    assert master.sdo(3).read(0x1018, 4, "u32") == 3
    assert master.sdo(4).read(0x1018, 4, "u32") == 4  # never used before
    other.send(0x000, RESETS[reset])  # and again
    bus.run_for(10_000)
    assert master.sdo(2).read(0x1018, 4, "u32") == 2
    assert master.sdo(4).read(0x1018, 4, "u32") == 4


def test_channel_table_follows_the_core() -> None:
    """The table is checked against 0x1280..: a channel another client rewrote over SDO is
    not used for the node it no longer talks to."""
    bus = SimBus(500_000)
    master, other, _ = _network(bus)
    bus.run_for(10_000)
    assert master.sdo(2).read(0x1018, 4, "u32") == 2
    channel = master._sdo.table[2]
    # another tool points the master's channel at node 3 through its SDO server
    for sub, value in ((1, 0x603), (2, 0x583), (3, 3)):
        other.sdo(MASTER).write(0x1280 + channel, sub, "u32" if sub < 3 else "u8", value)
    assert master.sdo(3).read(0x1018, 4, "u32") == 3
    assert master._sdo.table[3] == channel  # adopted: it talks to node 3 now
    assert master.sdo(2).read(0x1018, 4, "u32") == 2
    assert master._sdo.table[2] != channel


def test_manager_boots_the_network_again_after_a_reset_all() -> None:
    bus = SimBus(500_000)
    master, other, devices = _network(bus)
    bus.run_for(10_000)
    net = Network(tuple(SlaveSpec(n, identity=Identity(vendor=VENDOR), heartbeat_ms=300)
                        for n in (2, 3)), start="all")
    for device in devices[:2]:
        device.od[0x1017, 0] = 100
    mgr = master.boot(net)
    assert mgr.started
    events = len(mgr.events)
    other.send(0x000, RESETS["reset-comm-all"])  # the slaves forget 0x1017, the master its watches
    bus.run_for(10_000)
    for device in devices[:2]:
        device.od[0x1017, 0] = 100
    assert mgr.wait(10.0)
    later = mgr.events[events:]
    assert [e.kind for e in later if e.kind == "failed"] == []
    assert sorted(e.node for e in later if e.kind == "booted") == [2, 3]
    assert devices[0].nmt_state == devices[1].nmt_state == "OPERATIONAL"
    bus.run_for(500_000)
    assert master.heartbeat_state(2) == "OPERATIONAL"  # watched again
    assert master.sdo(2).read(0x1018, 4, "u32") == 2


def test_python_can_reset_all_from_another_participant(
        can_bus: Callable[[], can.BusABC]) -> None:
    master, other, devices = _network(can_bus)
    raw = can_bus()
    try:
        assert master.sdo(2).read(0x1018, 4, "u32") == 2
        raw.send(can.Message(arbitration_id=0x000, data=b"\x82\x00", is_extended_id=False))
        seen = set()
        end = time.monotonic() + 10.0
        while 0x700 + MASTER not in seen and time.monotonic() < end:
            msg = raw.recv(0.1)
            if msg is not None and bytes(msg.data) == b"\x00":
                seen.add(msg.arbitration_id)
        assert 0x700 + MASTER in seen  # the master was reset (its boot-up)
        assert master.sdo(2).read(0x1018, 4, "u32") == 2
        assert master.sdo(3).read(0x1018, 4, "u32") == 3
    finally:
        for node in (master, other, *devices):
            node.stop()


@pytest.mark.parametrize("command", ["reset comm", "reset node"])
def test_gateway_own_reset_leaves_it_serving(command: str) -> None:
    async def main() -> None:
        bus = SimBus()
        master = Master(bus, node_id=127)
        devices = [Device(SAMPLE, n, bus) for n in (2, 3)]
        master.start()
        for device in devices:
            device.start()
        bus.run_for(10_000)
        async with serve(master) as (address, _):
            c = await Client.connect(address)
            assert await c.ask("[1] 2 r 0x1018 1 u32") == "[1] 3232"
            assert await c.ask(f"[2] 127 {command}") == "[2] OK"
            assert await c.ask("[3] 2 r 0x1018 1 u32") == "[3] 3232"
            assert await c.ask("[4] 3 r 0x1018 1 u32") == "[4] 3232"
            await c.close()

    run(main())


def _stamps(trace: list[str], cob: str) -> list[tuple[int, str]]:
    """(virtual time in us, data) of the frames on ``cob`` (e.g. "080") in ``trace``."""
    out = []
    for line in trace:
        stamp, _, frame = line.split()
        can_id, data = frame.split("#")
        if can_id == cob:
            out.append((round(float(stamp.strip("()")) * 1e6), data))
    return out


@pytest.mark.parametrize("reset", list(RESETS))
def test_monitor_sync_and_time_survive_the_masters_reset(reset: str) -> None:
    """What the application set up (heartbeat watches, SYNC period and counter, TIME
    period) is in force again after the master's own reset, at the configured periods."""
    bus = SimBus()  # frames arrive at the instant they are sent: exact stamps
    master, other, devices = _network(bus)
    events: list[HeartbeatEvent] = []
    master.on_heartbeat(events.append)
    master.monitor(2, 300)
    master.start_sync(10_000, overflow=4)
    master.start_time(100)
    devices[0].od[0x1017, 0] = 100
    bus.run_for(1_000_000)
    assert master.heartbeat_state(2) == "PRE-OPERATIONAL"
    reset_at = bus.now_us
    mark = len(bus.trace)
    other.send(0x000, RESETS[reset])
    assert master.od[0x1012, 0] == 0x40000100  # a TIME producer again at once
    devices[0].od[0x1017, 0] = 100  # a reset to all took the device's heartbeat too
    bus.run_for(1_000_000)
    after = bus.trace[mark:]
    assert (reset_at, "00") in _stamps(after, f"{0x700 + MASTER:03X}")  # it was reset
    syncs = _stamps(after, "080")
    assert [t - reset_at for t, _ in syncs] == [k * 10_000 for k in range(1, 101)]
    assert [d for _, d in syncs] == ["0" + str(k % 4 + 1) for k in range(100)]
    times = [t for t, _ in _stamps(after, "100")]
    assert len(times) == 10 and {b - a for a, b in itertools.pairwise(times)} == {100_000}
    assert master.heartbeat_state(2) == "PRE-OPERATIONAL"  # watched again
    devices[0].od[0x1017, 0] = 0  # silent: the master reports it
    lost = len(events)
    bus.run_for(1_000_000)
    assert [(e.node, e.kind) for e in events[lost:]] == [(2, "lost")]


def test_set_up_before_start_holds_after_it() -> None:
    """monitor()/start_sync() before start(): the start's reset does not undo them."""
    bus = SimBus()
    master = Master(bus, node_id=MASTER)
    device = Device(model(serial=2), 2, bus)
    master.monitor(2, 300)
    master.start_sync(20_000)
    device.start()
    device.od[0x1017, 0] = 100
    master.start()
    began = bus.now_us
    bus.run_for(1_000_000)
    assert [t - began for t, _ in _stamps(bus.trace, "080")] == [k * 20_000
                                                                 for k in range(1, 51)]
    assert master.heartbeat_state(2) == "PRE-OPERATIONAL"
    master.stop_sync()
    master.monitor(2, 0)
    mark = len(bus.trace)
    other = Master(bus, node_id=9)
    other.start()
    other.send(0x000, RESETS["reset-comm-master"])
    bus.run_for(1_000_000)
    assert _stamps(bus.trace[mark:], "080") == []  # stopped stays stopped
    assert master.heartbeat_state(2) is None


def test_python_can_restart_keeps_sync_and_monitor(
        can_bus: Callable[[], can.BusABC]) -> None:
    """stop() then start() of the master object: SYNC and heartbeat watches go on."""
    master = Master(can_bus(), node_id=MASTER, sdo_timeout_ms=SDO_TIMEOUT_MS)
    device = Device(model(serial=2), 2, can_bus())
    raw = can_bus()
    events: list[HeartbeatEvent] = []
    master.on_heartbeat(events.append)
    try:
        master.start()
        device.start()
        device.od[0x1017, 0] = 50
        master.monitor(2, 500)
        master.start_sync(20_000)
        master.stop()
        master.start()
        syncs = 0
        end = time.monotonic() + 30.0
        while syncs < 10 and time.monotonic() < end:
            msg = raw.recv(0.1)
            if msg is not None and msg.arbitration_id == 0x080:
                syncs += 1
        assert syncs == 10
        assert wait_until(lambda: master.heartbeat_state(2) == "PRE-OPERATIONAL")
        device.od[0x1017, 0] = 0
        assert wait_until(lambda: (2, "lost") in [(e.node, e.kind) for e in events])
    finally:
        for node in (master, device):
            node.stop()
