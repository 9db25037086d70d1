# SPDX-License-Identifier: Apache-2.0
"""The gateway's lss_* commands (CiA 309-3) through canola.Master's LSS master, against
canola.Devices without node-ID (0xFF) on a simulated bus (virtual time)."""

from __future__ import annotations

from gateway_helpers import Client, run
from managed import PRODUCT, REVISION, VENDOR, model
from test_gateway_master import serve

from canola import Device, Master
from canola.core import SimBus
from canola.lss import UNCONFIGURED

GW = 127
SERIALS = (0x300, 0x100)


def _network() -> tuple[SimBus, Master, list[Device]]:
    bus = SimBus(500_000)
    master = Master(bus, node_id=GW)
    master.start()
    master.lss.timeout_ms = 20
    devices = [Device(model(serial=s), UNCONFIGURED, bus) for s in SERIALS]
    for device in devices:
        device.start()
    bus.run_for(10_000)
    return bus, master, devices


def _addr(serial: int) -> str:
    return f"0x{VENDOR:08X} 0x{PRODUCT:08X} 0x{REVISION:08X} 0x{serial:08X}"


def test_fastscan_set_node_store_and_boot() -> None:
    async def main() -> None:
        bus, master, devices = _network()
        by_serial = {d.od[0x1018, 4]: d for d in devices}
        async with serve(master) as (address, _):
            c = await Client.connect(address)
            assert await c.ask("[1] lss_get_node") == "[1] ERROR:102"  # none selected
            assert await c.ask("[2] _lss_fastscan 20") == f"[2] {_addr(0x100)}"
            assert await c.ask("[3] lss_get_node") == "[3] 0xFF"
            assert await c.ask("[4] lss_inquire_addr 3") == "[4] 0x00000100"
            assert await c.ask("[5] lss_inquire_addr") == f"[5] {_addr(0x100)}"
            assert await c.ask("[6] lss_set_node 10") == "[6] OK"
            # a canola.Device has no storage for LSS: it refuses (the ID still applies)
            assert await c.ask("[7] lss_store") == "[7] ERROR:504"
            assert await c.ask("[8] lss_get_node") == "[8] 0xFF"  # the active one
            assert by_serial[0x100].node_id == UNCONFIGURED  # not before waiting
            assert await c.ask("[9] lss_switch_glob 0") == "[9] OK"
            bus.run_for(10_000)
            assert by_serial[0x100].node_id == 10
            assert by_serial[0x100].nmt_state == "PRE-OPERATIONAL"
            assert "70A#00" in {line.split()[-1] for line in bus.trace}
            assert await c.ask("[10] 10 r 0x1018 4 u32") == "[10] 256"
            # selective switch of the other one, by its address
            assert await c.ask(f"[11] lss_switch_sel {_addr(0x300)}") == "[11] OK"
            assert await c.ask("[12] lss_inquire_addr 3") == "[12] 0x00000300"
            assert await c.ask("[13] lss_set_node 11") == "[13] OK"
            assert await c.ask("[14] lss_switch_glob 0") == "[14] OK"
            bus.run_for(10_000)
            assert by_serial[0x300].node_id == 11
            assert await c.ask("[15] _lss_fastscan 20") == "[15] ERROR:103"  # none left
            assert await c.ask(f"[16] lss_switch_sel {_addr(0x999)}") == "[16] ERROR:103"
            assert await c.ask("[17] lss_switch_glob 2") == "[17] ERROR:101"
            assert await c.ask("[18] lss_set_node 128") == "[18] ERROR:101"
            assert await c.ask("[19] lss_conf_bitrate 0 2") == "[19] ERROR:100"
            assert await c.ask("[20] lss_activate_bitrate 100") == "[20] ERROR:100"
            assert await c.ask("[21] 2 lss_store") == "[21] ERROR:106"  # network 2
            await c.close()

    run(main())


def test_allnodes() -> None:
    async def main() -> None:
        bus, master, devices = _network()
        async with serve(master) as (address, _):
            c = await Client.connect(address)
            # one reply, its lines joined by LF (127 is the gateway's own node-ID: no
            # node-ID left for the second device)
            assert await c.ask("[1] lss_allnodes 20 126 0") == (
                f"# Node-ID 126 assigned to: {_addr(0x100)}\n# Not all nodes scanned!\n[1] OK")
            bus.run_for(10_000)
            assert sorted(d.node_id for d in devices) == [126, UNCONFIGURED]
            # store 1: the device refuses (no LSS storage): 504, its node-ID applies
            assert await c.ask("[2] lss_allnodes 20 5 1 0 0 0 0 0 0 0 0") == "[2] ERROR:504"
            bus.run_for(10_000)
            assert sorted(d.node_id for d in devices) == [5, 126]
            assert await c.ask("[5] lss_allnodes 20") == \
                "# Found 0 nodes, search finished.\n[5] OK"
            assert await c.ask("[3] lss_allnodes 20 5 0 1 0 0 0 0 0 0 0") == "[3] ERROR:100"
            assert await c.ask("[4] lss_allnodes 20 5") == "[4] ERROR:101"
            await c.close()

    run(main())



def test_error_codes_as_canopennode_gives_them() -> None:
    """Arguments out of range: 101; the LSS master not in the state for the command (it
    remembers what it switched to configuration): 102; a scan time-out 0 is the default."""
    async def main() -> None:
        _, master, devices = _network()
        async with serve(master) as (address, _):
            c = await Client.connect(address)
            for seq, (line, code) in enumerate([
                    ("lss_set_node 10", 102), ("lss_set_node 0", 102),
                    ("lss_set_node 200", 101), ("lss_store", 102), ("lss_inquire_addr", 102),
                    ("lss_inquire_addr 4", 101), ("lss_switch_glob 1", 0),
                    ("lss_set_node 5", 102),  # all in configuration: only 255 is allowed
                    ("lss_store", 102), ("_lss_fastscan", 102), ("lss_switch_glob 0", 0),
                    ("lss_conf_bitrate 1 2", 101), ("lss_conf_bitrate 0 5", 101),
                    ("lss_conf_bitrate 0 2", 100), ("lss_activate_bitrate 70000", 101),
                    ("lss_allnodes 20 5 0 3 0 0 0 0 0 0 0", 101), ("_lss_fastscan 70000", 101),
                    ("lss_switch_sel 1 2 3", 101), ("lss_allnodes 0 1 2 3 4 5 6 7 8 9 10 11", 101),
            ], start=1):
                want = f"[{seq}] OK" if code == 0 else f"[{seq}] ERROR:{code}"
                assert await c.ask(f"[{seq}] {line}") == want, line
            assert await c.ask("[30] _lss_fastscan 0") == f"[30] {_addr(0x100)}"  # 0: 100 ms
            assert await c.ask("[31] _lss_fastscan") == "[31] ERROR:102"  # one is selected
            assert await c.ask(f"[32] lss_switch_sel {_addr(0x300)}") == "[32] ERROR:102"
            assert await c.ask("[33] lss_allnodes") == "[33] ERROR:102"
            assert await c.ask("[34] lss_get_node") == "[34] 0xFF"
            assert await c.ask("[35] lss_switch_glob 0") == "[35] OK"
            assert await c.ask("[36] lss_get_node") == "[36] ERROR:102"
            assert {d.node_id for d in devices} == {UNCONFIGURED}
            await c.close()

    run(main())


def test_refusals_map_to_canopennode_codes() -> None:
    from canola.gateway.masterbackend import _lss_error  # noqa: PLC0415 -- the mapping only

    refused = "refused by the slave"
    assert _lss_error("set_node", refused, 1) == 502
    assert _lss_error("store", refused, 2) == 504
    assert _lss_error("store", refused, 0xFF) == 501  # manufacturer-specific
    assert _lss_error("set_node", refused, 0xFF) == 501
    assert _lss_error("inquire", "time-out", 0) == 103
    assert _lss_error("fastscan", "fastscan lost the slave", 0) == 102
    assert _lss_error("select", "cancelled", 0) == 102
