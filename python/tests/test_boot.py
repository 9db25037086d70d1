# SPDX-License-Identifier: Apache-2.0
"""canola.Master.boot: the CANopen manager (CiA 302-2) booting a network of canola.Devices
described in YAML and DCF files, on the simulated bus in virtual time."""

from __future__ import annotations

from pathlib import Path

import pytest
from managed import DEVICE_TYPE, PRODUCT, VENDOR, model, write_dcf

from canola import Device, Error, Master, SdoAbort
from canola.boot_plan import Identity, Network, NetworkError, SlaveSpec
from canola.core import SimBus
from canola.manager import BootEvent, NetworkManager
from canola.master import Frame

PLANT = """
nodes:
  - id: 2                     # good, configured by its DCF, heartbeat watched
    dcf: node2.dcf
    heartbeat_ms: 300
  - id: 3                     # answers with another vendor-ID
    optional: true
    identity: {vendor: 0xCA0}
  - id: 4                     # not there at boot time
    optional: true
  - id: 5                     # its DCF holds a value the device refuses
    optional: true
    dcf: node5.dcf
  - id: 6                     # good, no configuration
    identity: {product: 0x302, serial: 6}
"""


@pytest.fixture
def plant(tmp_path: Path) -> Path:
    write_dcf(tmp_path / "node2.dcf", 2, {(0x1017, 0): "100", (0x2001, 0): "0x12345678",
                                          (0x2000, 0): "750"}, serial=2)
    write_dcf(tmp_path / "node5.dcf", 5, {(0x1017, 0): "40", (0x2000, 0): "5000",
                                          (0x2001, 0): "7"}, serial=5)
    path = tmp_path / "plant.yaml"
    path.write_text(PLANT)
    return path


def _network(bus: SimBus, *nodes: int, vendor3: int = 0xBAD) -> dict[int, Device]:
    devices = {n: Device(model(vendor=vendor3 if n == 3 else VENDOR, serial=n), n, bus)
               for n in nodes}
    for device in devices.values():
        device.start()
    bus.run_for(10_000)  # their boot-ups are on the bus before any boot starts
    return devices


def test_plant_boot(plant: Path) -> None:
    bus = SimBus(500_000)
    master = Master(bus, node_id=1)
    master.start()
    devices = _network(bus, 2, 3, 5, 6)
    assert master.sdo(2).read(0x1018, 4, "u32") == 2  # the master talked to it before
    seen: list[BootEvent] = []
    mgr = master.boot(plant, on_event=seen.append)
    assert mgr.started
    bus.run_for(10_000)  # the NMT commands sent when the network started arrive
    assert seen == mgr.events
    by_node = {s.node: s for s in mgr.slaves()}

    # the rest reach operational, configured by their DCF
    assert by_node[2].state == by_node[6].state == "running"
    assert devices[2].nmt_state == devices[6].nmt_state == "OPERATIONAL"
    assert master.nmt_state == "OPERATIONAL"
    assert devices[2].od[0x2001, 0] == 0x12345678 and devices[2].od[0x2000, 0] == 750
    assert devices[2].od[0x1017, 0] == 100
    bus.run_for(200_000)
    assert master.heartbeat_state(2) == "OPERATIONAL"

    # the wrong vendor is refused and reported with what it answered
    three = by_node[3]
    assert (three.state, three.reason, three.index, three.sub, three.value) == (
        "failed", "D", 0x1018, 1, 0xBAD)
    assert three.text == "D: vendor-ID does not match"
    assert str(three) == ("node 3 (optional): failed: D: vendor-ID does not match "
                          "(0x1018:01 is 0x00000BAD)")
    assert devices[3].nmt_state == "PRE-OPERATIONAL"

    # the missing one: no answer to the device type read (SDO time-out)
    four = by_node[4]
    assert (four.state, four.reason, four.abort, four.index) == ("failed", "B", 0x05040000,
                                                                 0x1000)

    # the refused configuration entry, with its abort code (value above HighLimit)
    five = by_node[5]
    assert (five.state, five.reason, five.abort, five.index, five.sub) == (
        "failed", "J", 0x06090031, 0x2000, 0)
    assert "J: " in five.text and "SDO abort 0x06090031" in str(five)
    assert devices[5].od[0x1017, 0] == 40  # the entry before it was written
    assert devices[5].od[0x2001, 0] == 0  # the one after it was not
    assert devices[5].nmt_state == "PRE-OPERATIONAL"

    # the master's SDO client reaches the slaves after the boot, the last one booted too
    assert master.sdo(6).read(0x1018, 4, "u32") == 6
    assert master.sdo(2).read(0x2001, 0, "u32") == 0x12345678

    kinds = [(e.node, e.kind) for e in mgr.events]
    assert (3, "failed") in kinds and (0, "network-started") in kinds
    assert (2, "booted") in kinds and (2, "started") in kinds
    assert [e.node for e in mgr.events if e.kind == "started"] == [2, 6]

    # the missing optional one appears later: booted on its boot-up, joins the network
    late = _network(bus, 4)[4]
    bus.run_for(2_000_000)
    assert mgr.status(4).state == "running"
    assert late.nmt_state == "OPERATIONAL"
    assert [e.kind for e in mgr.events if e.node == 4] == ["failed", "booted", "started"]
    assert [e.kind for e in seen if e.node == 4][-1] == "started"


def test_mandatory_failure_halts_the_network(tmp_path: Path) -> None:
    bus = SimBus(500_000)
    master = Master(bus, node_id=1)
    master.start()
    devices = _network(bus, 2, 3)
    net = Network((SlaveSpec(2), SlaveSpec(3, identity=Identity(vendor=VENDOR))))
    mgr = master.boot(net)
    assert not mgr.started
    halted = [e for e in mgr.events if e.kind == "network-halted"]
    assert len(halted) == 1 and halted[0].node == 3 and halted[0].reason == "D"
    assert str(halted[0]) == ("network halted: mandatory node 3 failed "
                              "(D: vendor-ID does not match)")
    assert mgr.status(2).state == "configured"  # booted, but nothing is started
    assert devices[2].nmt_state == "PRE-OPERATIONAL"
    assert master.nmt_state == "PRE-OPERATIONAL"


def test_start_all_and_heartbeat_loss(tmp_path: Path) -> None:
    bus = SimBus(500_000)
    master = Master(bus, node_id=1)
    master.start()
    devices = _network(bus, 2, 3, vendor3=VENDOR)
    for device in devices.values():
        device.od[0x1017, 0] = 50
    net = Network((SlaveSpec(2, heartbeat_ms=200), SlaveSpec(3, heartbeat_ms=200)),
                  start="all", master_start=False)
    mgr = master.boot(net)
    assert mgr.started
    bus.run_for(10_000)
    assert all(d.nmt_state == "OPERATIONAL" for d in devices.values())
    assert master.nmt_state == "PRE-OPERATIONAL"  # master_start: false
    assert any(line.split()[-1] == "000#0100" for line in bus.trace)  # one start to all
    devices[3].od[0x1017, 0] = 0  # stops its heartbeat
    bus.run_for(1_000_000)
    lost = [e for e in mgr.events if e.kind == "lost"]
    assert [(e.node, e.reason) for e in lost] == [(3, "E")]
    assert mgr.status(3).state == "missing"
    assert mgr.status(3).text == "E: heartbeat lost"


def test_dcf_files_and_identity(tmp_path: Path) -> None:
    bus = SimBus(500_000)
    master = Master(bus, node_id=1)
    master.start()
    devices = _network(bus, 7, 8)
    a = write_dcf(tmp_path / "a.dcf", 7, {(0x2001, 0): "77"}, serial=7)
    b = write_dcf(tmp_path / "b.dcf", 8, {}, serial=99)  # the device's serial is 8
    mgr = master.boot([a, b])
    assert not mgr.started
    assert devices[7].od[0x2001, 0] == 77
    assert mgr.status(7).state == "configured"
    eight = mgr.status(8)
    assert (eight.reason, eight.value) == ("O", 8)


def test_boot_without_waiting_and_errors(tmp_path: Path) -> None:
    bus = SimBus(500_000)
    master = Master(bus, node_id=1)
    with pytest.raises(Error, match="not started"):
        master.boot(Network((SlaveSpec(2),)))
    master.start()
    _network(bus, 2)
    with pytest.raises(Error, match="node 1 is the master itself"):
        master.boot(Network((SlaveSpec(1),)))
    with pytest.raises(NetworkError, match="cannot read"):
        master.boot(tmp_path / "none.yaml")
    with pytest.raises(Error, match="Network is needed"):
        NetworkManager(master, "x")  # type: ignore[arg-type]
    mgr = master.boot(Network((SlaveSpec(2, identity=Identity(product=PRODUCT)),)),
                      wait=False)
    assert not mgr.settled()
    with pytest.raises(Error, match="in progress"):
        master.boot(Network((SlaveSpec(2),)))
    assert mgr.wait()
    with pytest.raises(Error, match="not in the network"):
        mgr.status(9)
    again = master.boot(Network((SlaveSpec(2),)))  # a settled boot may be replaced
    assert again.started and again is not mgr


def test_reset_slaves_first() -> None:
    bus = SimBus(500_000)
    master = Master(bus, node_id=1)
    master.start()
    devices = _network(bus, 2, 3, vendor3=VENDOR)
    devices[3].od[0x2001, 0] = 99  # reset communication keeps application values
    net = Network((SlaveSpec(2), SlaveSpec(3, keep_alive=True)), reset_slaves=True)
    mgr = master.boot(net)
    assert mgr.started
    frames = [line.split()[-1] for line in bus.trace]
    assert "000#8202" in frames and "000#8203" not in frames  # keep-alive spared
    assert devices[3].od[0x2001, 0] == 99


def test_dcf_that_remaps_pdos_boots_a_device_that_enforces_the_procedure(
        tmp_path: Path) -> None:
    """A DCF made from an EDS re-maps TPDO1 and RPDO1; the device refuses a mapping
    written while its PDO is valid, as CiA 301 has it: the concise DCF follows the
    re-mapping procedure, and the PDOs work afterwards."""
    from test_boot_plan import INTEROP, _remapping_dcf  # noqa: PLC0415

    bus = SimBus(500_000)
    master = Master(bus, node_id=1)
    master.start()
    device = Device(INTEROP, 5, bus)
    device.start()
    bus.run_for(10_000)
    with pytest.raises(SdoAbort):  # the device enforces the procedure
        master.sdo(5).write(0x1A00, 0, "u8", 0)
    mgr = master.boot([_remapping_dcf(tmp_path)])
    assert mgr.started, [str(s) for s in mgr.slaves()]
    assert device.od[0x1A00, 1] == 0x20070020 and device.od[0x1A00, 0] == 1
    assert device.od[0x1600, 1] == 0x20010008 and device.od[0x1800, 1] == 0x185
    seen: list[bytes] = []
    master.on_frame(lambda f: seen.append(f.data), cob_id=0x185)
    device.od[0x2007, 0] = 0x01020304
    master.start_sync(10_000)
    bus.run_for(50_000)
    assert seen and seen[-1] == (0x01020304).to_bytes(4, "little")


@pytest.mark.parametrize("start", ["each", "all"])
@pytest.mark.parametrize("mandatory", [False, True])
def test_late_slave_that_answers_late_too(mandatory: bool, start: str) -> None:
    """A slave missing at boot (B) boots later; being slow, it also answers the request it
    got before its boot-up while its identity is read. Booted all the same: an optional
    one joins the running network, a mandatory one lets the network start."""
    bus = SimBus(500_000)
    master = Master(bus, node_id=1)
    master.start()
    slow = Master(bus, node_id=100, announce=False)  # plays the slave's late answer
    slow.start()
    late_answers: list[int] = []

    def answer_late(frame: Frame) -> None:
        if frame.data[:4] == bytes.fromhex("43181001") and not late_answers:
            late_answers.append(1)
            slow.send(0x584, bytes.fromhex("43001000") + DEVICE_TYPE.to_bytes(4, "little"))

    slow.on_frame(answer_late, cob_id=0x584)
    net = Network((SlaveSpec(4, mandatory=mandatory,
                             identity=Identity(vendor=VENDOR, product=PRODUCT)),), start=start)
    mgr = master.boot(net)
    assert mgr.status(4).reason == "B" and mgr.started is not mandatory
    device = Device(model(serial=4), 4, bus)
    device.start()
    for _ in range(200):  # fine steps: the late answer follows the vendor-ID's at once
        bus.run_for(100)
    bus.run_for(2_000_000)
    assert late_answers == [1]
    kinds = [e.kind for e in mgr.events if e.node == 4 and e.kind != "network-halted"]
    assert kinds == ["failed", "booted", "started"]
    assert mgr.started and device.nmt_state == "OPERATIONAL"
