# SPDX-License-Identifier: Apache-2.0
"""The gateway on canola.Master with canola.Device peers: a simulated bus (virtual time)
and a python-can bus (real time, the master's and devices' bus threads)."""

from __future__ import annotations

import asyncio
import base64
import contextlib
import os
import queue
from collections.abc import AsyncIterator, Callable
from pathlib import Path

import can
import pytest
from gateway_helpers import Client, run, serving

from canola import Device, Master
from canola.core import SimBus
from canola.gateway.masterbackend import MasterBackend

SAMPLE = Path(__file__).parent / "golden" / "sample.eds"
GW = 127


@contextlib.asynccontextmanager
async def serve(master: Master) -> AsyncIterator[tuple[str, MasterBackend]]:
    backend = MasterBackend(master)
    async with serving(backend) as address:
        yield address, backend


def _sim() -> tuple[SimBus, Master, dict[int, Device]]:
    bus = SimBus()
    master = Master(bus, node_id=GW)
    devices = {n: Device(SAMPLE, n, bus, domain_size=880) for n in (2, 3)}
    master.start()
    for d in devices.values():
        d.start()
    bus.run_for(10_000)
    return bus, master, devices


def test_sim_sdo_nmt_and_local_node() -> None:
    async def main() -> None:
        bus, master, devices = _sim()
        async with serve(master) as (address, _):
            c = await Client.connect(address)
            assert await c.ask("[1] 2 r 0x1018 1 u32") == "[1] 3232"
            assert await c.ask("[2] 3 w 0x2013 0 vs \"via canola.Master\"") == "[2] OK"
            assert await c.ask("[3] 3 r 0x2013 0 vs") == '[3] "via canola.Master"'
            assert await c.ask("[4] 2 w 0x2004 0 i32 -7") == "[4] OK"
            assert devices[2].od.get(0x2004, 0) == -7
            assert await c.ask("[5] 2 r 0x5000 0") == "[5] ERROR:0x06020000"
            assert await c.ask("[6] 2 w 0x1018 1 u32 1") == "[6] ERROR:0x06010002"
            assert await c.ask("[7] 2 start") == "[7] OK"
            assert devices[2].nmt_state == "OPERATIONAL"
            assert await c.ask("[8] 0 stop") == "[8] OK"
            assert devices[2].nmt_state == devices[3].nmt_state == "STOPPED"
            assert master.nmt_state == "STOPPED"  # node-ID 0 is every node, the gateway's too
            assert await c.ask("[9] 0 preop") == "[9] OK"
            assert master.nmt_state == "PRE-OPERATIONAL"
            before = len(bus.trace)
            assert await c.ask(f"[10] {GW} stop") == "[10] OK"
            assert master.nmt_state == "STOPPED"
            assert await c.ask(f"[11] {GW} preop") == "[11] OK"
            assert master.nmt_state == "PRE-OPERATIONAL"
            assert await c.ask(f"[12] {GW} w 0x1017 0 u16 0") == "[12] OK"
            assert await c.ask(f"[13] {GW} r 0x1017 0 u16") == "[13] 0"
            assert await c.ask(f"[14] {GW} w 0x1018 1 u32 1") == "[14] ERROR:0x06010002"
            # NMT to its own node-ID goes on the bus too; its SDO never does
            assert [frame for line in bus.trace[before:]
                    if (frame := line.split()[-1]).startswith(("000#", f"{0x600 + GW:03X}#"))
                    ] == [f"000#02{GW:02X}", f"000#80{GW:02X}"]
            assert await c.ask("[15] set sdo_block 1") == "[15] OK"
            data = os.urandom(880)
            text = base64.b64encode(data).decode()
            assert await c.ask(f"[16] 2 w 0x2200 0 d {text}") == "[16] OK"
            assert await c.ask("[17] 2 r 0x2200 0 d") == f"[17] {text}"
            assert devices[2].od.read(0x2200, 0) == data
            await c.close()

    run(main())


def test_nmt_to_the_gateways_own_node_id_goes_on_the_bus() -> None:
    """As CANopenNode's gateway does (scripts count the frames): ``<own id> reset comm`` is
    000#82<id> on the bus, then the gateway's own reset (its boot-up); the same for reset
    node and the state commands, which the gateway follows too."""
    async def main() -> None:
        bus, master, devices = _sim()
        async with serve(master) as (address, _):
            c = await Client.connect(address)
            for seq, (command, cs) in enumerate([("reset comm", 0x82), ("reset node", 0x81),
                                                 ("start", 0x01)], start=1):
                before = len(bus.trace)
                assert await c.ask(f"[{seq}] {GW} {command}") == f"[{seq}] OK"
                bus.run_for(10_000)
                frames = [line.split()[-1] for line in bus.trace[before:]]
                assert frames[0] == f"000#{cs:02X}{GW:02X}", frames
                if command.startswith("reset"):
                    assert f"{0x700 + GW:03X}#00" in frames[1:], frames  # its boot-up
            assert master.nmt_state == "OPERATIONAL"
            # the devices heard the frames addressed to the gateway only
            assert {d.nmt_state for d in devices.values()} == {"PRE-OPERATIONAL"}
            await c.close()

    run(main())


def test_sim_sdo_timeout_per_client() -> None:
    """A client's ``set sdo_timeout`` is the master's time-out per answer for its requests;
    another client keeps the master's own (1000 ms)."""
    async def main() -> None:
        bus, master, _ = _sim()
        async with serve(master) as (address, _):
            quick = await Client.connect(address)
            plain = await Client.connect(address)
            assert await quick.ask("[1] set sdo_timeout 50") == "[1] OK"
            began = bus.now_us
            assert await quick.ask("[2] 42 r 0x1000 0") == "[2] ERROR:0x05040000"
            # Virtual time, but the gateway's loop keeps the simulated bus in step with the
            # wall clock meanwhile: a starved machine adds time. The bounds tell the two
            # time-outs apart (50 ms is well under the master's 1000 ms) with room for that.
            assert 50_000 <= bus.now_us - began < 1_000_000
            began = bus.now_us
            assert await plain.ask("[1] 42 r 0x1000 0") == "[1] ERROR:0x05040000"
            assert 1_000_000 <= bus.now_us - began < 2_000_000
            assert await quick.ask("[3] 2 r 0x1018 1 u32") == "[3] 3232"
            await quick.close()
            await plain.close()

    run(main())


@pytest.mark.slow
def test_sim_events() -> None:
    async def main() -> None:
        _, master, devices = _sim()
        async with serve(master) as (address, _):
            c = await Client.connect(address)
            assert await c.ask("[1] set events 1") == "[1] OK"
            await c.send("[2] 3 reset node")
            assert {await c.line(), await c.line()} == {"[2] OK", "1 3 BOOT_UP"}
            devices[2].emcy_raise(0x5000, b"\x01\x02")
            assert (await c.line()).startswith("1 2 EMCY 5000 ")
            assert await c.ask("[3] 2 w 0x1017 0 u16 20") == "[3] OK"
            assert await c.ask("[4] 2 enable heartbeat 1000") == "[4] OK"
            await asyncio.sleep(0.5)
            reply, events = await c.reply("[5] 2 w 0x1017 0 u16 0")
            assert (reply, events) == ("[5] OK", [])
            assert await c.line(timeout=10) == "1 2 ERROR 203"
            await c.close()

    run(main())


@pytest.mark.realtime
@pytest.mark.slow
def test_python_can_other_clients_not_stalled_and_abort_on_disconnect(
        can_bus: Callable[[], can.BusABC]) -> None:
    watch = can_bus()
    frames: queue.Queue[can.Message] = queue.Queue()
    notifier = can.Notifier(watch, [frames.put])
    master = Master(can_bus(), node_id=GW, sdo_timeout_ms=5000)
    device = Device(SAMPLE, 2, can_bus(), domain_size=880)
    master.start()
    device.start()

    async def main() -> None:
        async with serve(master) as (address, _):
            a = await Client.connect(address)
            b = await Client.connect(address)
            # a waits for node 42, which is not there (5 s per answer) ...
            await a.send("[1] 42 r 0x1000 0 u32")
            # ... while b is served at once, several times over
            for seq in range(5):
                assert await b.ask(f"[{seq}] 2 r 0x1018 1 u32", timeout=4.5) == f"[{seq}] 3232"
            assert await b.ask("[9] set sdo_block 1") == "[9] OK"
            data = os.urandom(800)
            text = base64.b64encode(data).decode()
            assert await b.ask(f"[10] 2 w 0x2200 0 d {text}", timeout=4.5) == "[10] OK"
            assert await b.ask("[11] 2 r 0x2200 0 d", timeout=4.5) == f"[11] {text}"
            assert await a.line(timeout=10) == "[1] ERROR:0x05040000"
            # a client that leaves in the middle of a transfer: abort frame on the bus
            while not frames.empty():
                frames.get_nowait()
            await a.send("[2] 43 r 0x1000 0 u32")
            await asyncio.sleep(0.3)
            await a.close()
            loop = asyncio.get_running_loop()
            deadline = loop.time() + 5
            abort = None
            while abort is None and loop.time() < deadline:
                try:
                    msg = frames.get_nowait()
                except queue.Empty:
                    await asyncio.sleep(0.01)
                    continue
                if msg.arbitration_id == 0x600 + 43 and msg.data[0] == 0x80:
                    abort = msg
            assert abort is not None, "no SDO abort frame after the client left"
            assert bytes(abort.data[4:8]) == (0x05040000).to_bytes(4, "little")
            assert await b.ask("[12] 2 r 0x1000 0 u32", timeout=5) == "[12] 401"
            await b.close()

    try:
        run(main())
    finally:
        notifier.stop()
        device.stop()
        master.stop()


INTEROP = Path(__file__).parent / "data" / "interop.eds"


def test_sim_pdos_of_the_gateway() -> None:
    """The gateway's own PDOs (its dictionary from interop.eds): configure, read, write,
    and the RPDO event."""

    async def main() -> None:
        bus = SimBus()
        master = Master(bus, node_id=GW, eds_file=INTEROP)
        device = Device(INTEROP, 2, bus)
        master.start()
        device.start()
        bus.run_for(10_000)
        async with serve(master) as (address, _):
            c = await Client.connect(address)
            assert await c.ask("[1] set events 1") == "[1] OK"
            # RPDO1 of the gateway takes the device's TPDO1 (0x2100 u32, 0x2005 u8)
            assert await c.ask("[2] set rpdo 1 0x182 event 2 0x2007 0 u32 0x2005 0 u8") == \
                "[2] OK"
            assert await c.ask(f"[3] {GW} start") == "[3] OK"
            assert await c.ask("[4] 2 start") == "[4] OK"
            device.od.set(0x2100, 0, 0xCAFE)
            device.od.set(0x2005, 0, 0x2A)  # event-driven TPDO: sent on the change
            seen = [await c.line()]  # one event per change of a mapped object
            while seen[-1] != "1 pdo 1 2 0xCAFE 0x2A":
                seen.append(await c.line())
            assert [line for line in seen if "pdo" in line] == ["1 pdo 1 2 0xCAFE 0x5",
                                                                 "1 pdo 1 2 0xCAFE 0x2A"]
            assert await c.ask("[5] r p 1") == "[5] 1 pdo 2 0xCAFE 0x2A"
            # TPDO1 of the gateway: two values, sent on request
            assert await c.ask(f"[6] set tpdo 1 0x{0x180 + GW:X} event 2 0x2006 0 u16 "
                               "0x2005 0 u8") == "[6] OK"
            before = len(bus.trace)
            assert await c.ask("[7] w p 1 2 0x1234 0x56") == "[7] OK"
            bus.run_for(1000)
            sent = [line.split()[-1] for line in bus.trace[before:]]
            assert f"{0x180 + GW:03X}#341256" in sent
            assert await c.ask("[8] w p 1 2 0x10000 0") == "[8] ERROR:401"
            await c.close()

    run(main())
