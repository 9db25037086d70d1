# SPDX-License-Identifier: Apache-2.0
"""The gateway end to end: a TCP client, the gateway (:class:`MasterBackend` on a
:class:`canola.Master`, as ``canola gateway --simulate`` runs it) and :class:`canola.Device`
peers, all on the simulated bus (virtual time)."""

from __future__ import annotations

import asyncio
import base64
import contextlib
import os
import struct
from collections.abc import AsyncIterator
from pathlib import Path

import pytest
from gateway_helpers import Client, run, serving

from canola import Device, Master
from canola.core import SimBus
from canola.formats import eds
from canola.gateway import Executor, GatewayServer, parse_listen
from canola.gateway.backend import BootUp, Emcy, Event, Heartbeat
from canola.gateway.masterbackend import MasterBackend

SAMPLE = Path(__file__).parent / "golden" / "sample.eds"
MIB = 1024 * 1024


@contextlib.asynccontextmanager
async def gateway(devices: tuple[int, ...] = (2, 3)) -> AsyncIterator[
        tuple[str, MasterBackend, dict[int, Device]]]:
    """The gateway (node 1, its dictionary from sample.eds) and ``devices`` on a SimBus."""
    bus = SimBus()
    master = Master(bus, node_id=1, eds_file=SAMPLE)
    nodes = {n: Device(SAMPLE, n, bus, string_size=64, domain_size=MIB + 16) for n in devices}
    master.start()
    for node in nodes.values():
        node.start()
    bus.run_for(10_000)
    backend = MasterBackend(master)
    async with serving(backend) as address:
        yield address, backend, nodes


def _trace(backend: MasterBackend) -> list[str]:
    bus = backend.master.bus
    assert isinstance(bus, SimBus)
    return bus.trace


def test_every_type_over_sdo() -> None:
    async def main() -> None:
        async with gateway() as (address, _, nodes):
            c = await Client.connect(address)
            assert await c.ask("[1] set node 2") == "[1] OK"
            cases = [
                (0x2000, "b", "1"), (0x2001, "i8", "-5"), (0x2002, "i16", "-300"),
                (0x2003, "i24", "-70000"), (0x2004, "i32", "-2000000000"),
                (0x2005, "i40", "-549755813888"), (0x2006, "i48", "140737488355327"),
                (0x2007, "i56", "-1"), (0x2008, "i64", "-9223372036854775808"),
                (0x200A, "u16", "65535"), (0x200B, "u24", "16777215"),
                (0x200C, "u32", "4294967295"), (0x200D, "u40", "1099511627775"),
                (0x200E, "u48", "1"), (0x200F, "u56", "72057594037927935"),
                (0x2010, "u64", "18446744073709551615"), (0x2011, "r32", "21.5"),
                (0x2012, "r64", "0.125"), (0x2013, "vs", '"hello ""gateway"""'),
                (0x2015, "vs", '""'),
            ]
            for seq, (index, type_name, text) in enumerate(cases, start=10):
                assert await c.ask(f"[{seq}] w 0x{index:04X} 0 {type_name} {text}") == \
                    f"[{seq}] OK", type_name
                assert await c.ask(f"[{seq}] r 0x{index:04X} 0 {type_name}") == \
                    f"[{seq}] {text}", type_name
            assert nodes[2].od.read(0x2011, 0) == struct.pack("<f", 21.5)
            assert await c.ask("[40] r 0x200C 0 x32") == "[40] 0xFFFFFFFF"
            assert await c.ask("[41] r 0x200C 0") == "[41] FF FF FF FF"
            assert await c.ask("[42] w 0x2200 0 d AAECAw==") == "[42] OK"
            assert await c.ask("[43] r 0x2200 0 d") == "[43] AAECAw=="
            assert await c.ask("[44] r 0x2200 0 os") == "[44] AAECAw=="
            assert await c.ask("[45] 3 r 0x1008 0 vs") == '[45] "canola sample"'
            assert await c.ask("[46] 3 r 0x2014 0 hex") == \
                "[46] " + " ".join(f"{b:02X}" for b in nodes[3].od.read(0x2014, 0))
            await c.close()

    run(main())


def test_abort_and_gateway_errors() -> None:
    async def main() -> None:
        async with gateway() as (address, backend, _nodes):
            c = await Client.connect(address)
            assert await c.ask("[1] 2 r 0x5FFF 0") == "[1] ERROR:0x06020000"
            assert await c.ask("[2] 2 r 0x1018 9") == "[2] ERROR:0x06090011"
            assert await c.ask("[3] 2 w 0x1018 1 u32 5") == "[3] ERROR:0x06010002"
            assert await c.ask("[4] 2 r 0x2009 0 u8") == "[4] ERROR:0x06010001"
            assert await c.ask("[5] 2 w 0x200C 0 u16 5") == "[5] ERROR:0x06070013"
            assert await c.ask("[6] 2 w 0x2300 1 i32 5000") == "[6] ERROR:0x06090031"
            assert await c.ask("[7] 2 r 0x200C 0 u16") == "[7] ERROR:0x06070010"
            assert await c.ask("[8] set sdo_timeout 50") == "[8] OK"
            assert await c.ask("[9] 42 r 0x1000 0") == "[9] ERROR:0x05040000"  # nobody there
            assert await c.ask("[10] r 0x1000 0") == "[10] ERROR:105"
            assert await c.ask("[11] 2 2 r 0x1000 0") == "[11] ERROR:106"
            assert await c.ask("[12] 0 r 0x1000 0") == "[12] ERROR:107"
            assert await c.ask("[13] 2 bogus") == "[13] ERROR:100"
            assert await c.ask("[14] 2 r 0x1000") == "[14] ERROR:101"
            assert await c.ask("[15] lss_get_node") == "[15] ERROR:102"  # no LSS switch yet
            assert await c.ask("[16] 1 start") == "[16] OK"  # the gateway itself: on the bus too
            assert backend.master.nmt_state == "OPERATIONAL"
            assert await c.ask("[17] 2 r 0x1000 0 u32") == "[17] 401"  # still usable
            await c.close()

    run(main())


def test_local_node_has_no_frames() -> None:
    async def main() -> None:
        async with gateway() as (address, backend, _):
            c = await Client.connect(address)
            before = len(_trace(backend))
            assert await c.ask("[1] 1 r 0x1018 1 u32") == "[1] 3232"
            assert await c.ask("[2] 1 w 0x200C 0 u32 7") == "[2] OK"
            assert backend.master.od.read(0x200C, 0) == (7).to_bytes(4, "little")
            sdo = [line for line in _trace(backend)[before:]
                   if line.split()[-1][:3] in ("581", "601")]
            assert sdo == []
            assert await c.ask("[3] info version") == "[3] 3232 4660 1.2 0 2 3.0 0.1"
            await c.close()

    run(main())


@pytest.mark.slow
def test_nmt_boot_up_and_heartbeat_events() -> None:
    async def main() -> None:
        async with gateway() as (address, _, nodes):
            c = await Client.connect(address)
            assert await c.ask("[1] set events 1") == "[1] OK"
            assert await c.ask("[2] 2 start") == "[2] OK"
            assert nodes[2].nmt_state == "OPERATIONAL"
            assert await c.ask("[3] 2 stop") == "[3] OK"
            assert nodes[2].nmt_state == "STOPPED"
            assert await c.ask("[4] 0 preop") == "[4] OK"
            assert nodes[2].nmt_state == nodes[3].nmt_state == "PRE-OPERATIONAL"
            await c.send("[5] 3 reset node")  # the event may come before the reply
            assert {await c.line(), await c.line()} == {"[5] OK", "1 3 BOOT_UP"}
            await c.send("[6] 3 reset comm")
            assert {await c.line(), await c.line()} == {"[6] OK", "1 3 BOOT_UP"}
            assert await c.ask("[7] 2 w 0x1017 0 u16 10") == "[7] OK"
            assert await c.ask("[8] 2 enable heartbeat 1000") == "[8] OK"
            await asyncio.sleep(0.4)  # heartbeats every 10 ms: no event
            reply, events = await c.reply("[9] 2 w 0x1017 0 u16 0")
            assert (reply, events) == ("[9] OK", [])
            assert await c.line(timeout=10) == "1 2 ERROR 203"
            reply, events = await c.reply("[10] 2 w 0x1017 0 u16 10")
            assert reply == "[10] OK"
            assert (events or [await c.line(timeout=10)]) == ["1 2 ERROR 202"]
            assert await c.ask("[11] 2 disable heartbeat") == "[11] OK"
            await c.close()

    run(main())


def test_frames_to_events() -> None:
    """Boot-up, heartbeat and EMCY frames of a node become the gateway's events; other
    frames (a TPDO, SYNC) do not. The frames come from another node on the bus."""
    bus = SimBus()
    master = Master(bus, node_id=1)
    other = Master(bus, node_id=6, announce=False)
    master.start()
    other.start()
    bus.run_for(10_000)
    backend = MasterBackend(master)
    events: list[Event] = []
    backend.subscribe(events.append)
    for can_id, data in [(0x705, b"\x00"), (0x705, b"\x05"),
                         (0x085, bytes.fromhex("3081110102030405")), (0x185, b"\x00"),
                         (0x080, b"")]:
        other.send(can_id, data)
        bus.run_for(1000)
    assert events == [BootUp(5), Heartbeat(5, 5),
                      Emcy(5, 0x8130, 0x11, b"\x01\x02\x03\x04\x05")]
    assert [line.split()[-1] for line in bus.trace[-5:]] == [
        "705#00", "705#05", "085#3081110102030405", "185#00", "080#"]


def test_domain_block_mode() -> None:
    """Block transfers through the gateway on the bus, both ways (the 1 MiB domain of a
    device through the gateway: test_gateway_domain.py)."""

    async def main() -> None:
        async with gateway(devices=(2,)) as (address, backend, nodes):
            c = await Client.connect(address)
            data = os.urandom(880)
            text = base64.b64encode(data).decode()
            assert await c.ask("[1] set sdo_block 1") == "[1] OK"
            before = len(_trace(backend))
            assert await c.ask(f"[2] 2 w 0x2200 0 d {text}") == "[2] OK"
            assert nodes[2].od.read(0x2200, 0) == data
            assert await c.ask("[3] 2 r 0x2200 0 d") == f"[3] {text}"
            requests = [line.split()[-1] for line in _trace(backend)[before:]
                        if line.split()[-1].startswith("602#")]
            assert requests[0].startswith("602#C")  # block download initiate
            assert any(r.startswith("602#A") for r in requests)  # block upload initiate
            await c.close()

    run(main())


def test_one_mib_domain_of_the_gateway_itself() -> None:
    """1 MiB through the text protocol into the gateway's own dictionary (no frames: its
    own node-ID is served locally). canola.Master gives its own DOMAIN entries no storage,
    so the 1 MiB value is an OCTET_STRING of that length (0x2200 of sample.eds, retyped)."""

    async def main() -> None:
        model = eds.parse(SAMPLE)
        entry = model.objects[0x2200].subs[0]
        entry.data_type, entry.default_value = 0x000A, "00" * MIB  # OCTET_STRING, 1 MiB
        bus = SimBus()
        own = Master(bus, node_id=1, eds_file=model)
        own.start()
        server = GatewayServer(Executor(MasterBackend(own)))
        srv = await server.start(parse_listen("tcp:127.0.0.1:0"))
        c = await Client.connect(GatewayServer.address(srv))
        data = os.urandom(MIB)
        text = base64.b64encode(data).decode()
        before = len(bus.trace)
        assert await c.ask("[1] set sdo_block 1") == "[1] OK"
        assert await c.ask(f"[2] 1 w 0x2200 0 d {text}", timeout=60) == "[2] OK"
        assert own.od.read(0x2200, 0) == data
        assert await c.ask("[3] 1 r 0x2200 0 d", timeout=60) == f"[3] {text}"
        assert await c.ask("[4] 1 w 0x2200 0 d " + base64.b64encode(data + b"x").decode(),
                           timeout=60) == "[4] ERROR:0x06070012"  # one byte too many
        assert len(bus.trace) == before
        await c.close()
        await server.close()

    run(main(), timeout=120)
