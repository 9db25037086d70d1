# SPDX-License-Identifier: Apache-2.0
"""What the gateway's clients get while its own node is not in a state for SDO (CiA 301:
SDO in PRE-OPERATIONAL and OPERATIONAL only, client and server alike): ERROR:204 naming
the state, at once, and service again as soon as the node is started; NMT storms that do
not stop it never cut a transfer. Simulated bus, virtual time moved by the test; a
hostile node (a second master that does not announce itself) sends the NMT frames."""

from __future__ import annotations

import base64
import contextlib
import os
import time
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass
from pathlib import Path

import can
import pytest
from gateway_helpers import Client, client_of, run

from canola import Device, Master
from canola.core import SimBus
from canola.gateway.masterbackend import MasterBackend
from canola.master import Frame

SAMPLE = Path(__file__).parent / "golden" / "sample.eds"
GW = 127
STOPPED_REPLY = (f"ERROR:204 #the gateway's node {GW} is STOPPED: no SDO until it is started "
                 "(CiA 301)")


@dataclass
class Net:
    bus: SimBus
    backend: MasterBackend
    device: Device
    hostile: Master
    client: Client

    async def ask(self, line: str) -> str:
        reply = await self.client.ask(line)
        self.bus.run_for(2000)
        return reply

    def sdo_frames(self, since: int) -> list[str]:
        return [line.split()[-1] for line in self.bus.trace[since:]
                if line.split()[-1].startswith(("602#", "582#"))]


@contextlib.asynccontextmanager
async def network() -> AsyncIterator[Net]:
    """The gateway, device 2 and the hostile node 9 on a 250 kbit/s bus (frames take their
    time: the hostile node's reactions fall between the frames of a transfer)."""
    bus = SimBus(bitrate=250_000)
    master = Master(bus, node_id=GW)
    device = Device(SAMPLE, 2, bus, domain_size=880)
    hostile = Master(bus, node_id=9, announce=False)
    for node in (master, device, hostile):
        node.start()
    bus.run_for(10_000)
    backend = MasterBackend(master)
    async with client_of(backend) as client:
        yield Net(bus, backend, device, hostile, client)


def test_stopped_gateway_answers_wrong_state_and_recovers_when_started() -> None:
    """Stopped by its client, or by any node on the bus (to its node-ID or to all): SDO
    requests to other nodes get ERROR:204 naming the state and no frame goes out; its own
    dictionary, NMT and the rest still work; a start (from anyone) brings SDO back at
    once. (Before, the requests ended in a bare ERROR:102.)"""
    async def main() -> None:
        async with network() as net:
            assert await net.ask("[1] 2 r 0x1018 1 u32") == "[1] 3232"
            for stop, start in [(f"[2] {GW} stop", f"[5] {GW} start"),
                                (b"\x02\x00", b"\x01\x00"),
                                (bytes([0x02, GW]), bytes([0x80, GW]))]:
                if isinstance(stop, str):
                    assert await net.ask(stop) == "[2] OK"
                else:
                    net.hostile.send(0x000, stop)
                    net.bus.run_for(1000)
                assert net.backend.nmt_state == "STOPPED"
                before = len(net.bus.trace)
                assert await net.ask("[3] 2 r 0x1018 1 u32") == f"[3] {STOPPED_REPLY}"
                assert await net.ask("[4] 2 w 0x2004 0 i32 5") == f"[4] {STOPPED_REPLY}"
                assert net.sdo_frames(before) == []
                assert await net.ask(f"[4] {GW} r 0x1018 1 u32") == "[4] 0"  # its own: no frame
                if isinstance(start, str):
                    assert await net.ask(start) == "[5] OK"
                else:
                    net.hostile.send(0x000, start)
                    net.bus.run_for(1000)
                assert await net.ask("[6] 2 r 0x1018 1 u32") == "[6] 3232"
                assert net.sdo_frames(before)  # out again

    run(main())


def _on_sdo_requests(net: Net, react: Callable[[int], None]) -> None:
    """``react(n)`` for the n-th SDO request frame of the gateway to node 2 (n from 1)."""
    count = [0]

    def seen(frame: Frame) -> None:
        count[0] += 1
        react(count[0])

    net.hostile.on_frame(seen, 0x602)


def test_a_transfer_cut_by_the_gateways_stop_is_a_state_error() -> None:
    """A segmented upload under way when another node stops the gateway: the transfer
    ends (the gateway's client may send no more frames), answered ERROR:204 saying the
    node was stopped during it, not abort 0x08000022 (which blames the device); after a
    start the same read succeeds."""
    async def main() -> None:
        async with network() as net:
            data = os.urandom(880)
            net.device.od.write(0x2200, 0, data)
            _on_sdo_requests(net, lambda n: n == 40 and net.hostile.send(0x000, bytes([2, GW])))
            reply = await net.ask("[1] 2 r 0x2200 0 d")
            assert reply == (f"[1] ERROR:204 #the gateway's node {GW} was stopped or reset "
                             "during the transfer, now STOPPED: no SDO until it is started "
                             "(CiA 301)")
            net.hostile.send(0x000, bytes([1, GW]))
            net.bus.run_for(1000)
            assert await net.ask("[2] 2 r 0x2200 0 d") == (
                f"[2] {base64.b64encode(data).decode()}")

    run(main())


def test_an_nmt_storm_that_does_not_stop_the_gateway_cuts_no_transfer() -> None:
    """Every SDO request of the gateway answered by a burst of NMT frames: pre-operational
    and start to it and to all, stop and resets to other node-IDs, malformed commands.
    None of them stops the gateway: 40 segmented reads and writes all succeed."""
    burst = [b"\x80\x00", bytes([0x01, GW]), b"\x80" + bytes([GW]), b"\x01\x00",
             b"\x02\x05", b"\x82\x05", b"\x81\x06", b"\x02", b"\x02\x00\x00", b"\x05\x00",
             b"\x02\x80"]

    async def main() -> None:
        async with network() as net:
            data = os.urandom(880)
            net.device.od.write(0x2200, 0, data)
            text = base64.b64encode(data).decode()

            def storm(_: int) -> None:
                for frame in burst:
                    net.hostile.send(0x000, frame)

            _on_sdo_requests(net, storm)
            for i in range(20):
                assert await net.ask(f"[{i}] 2 r 0x2200 0 d") == f"[{i}] {text}"
                assert await net.ask(f'[{i}] 2 w 0x2013 0 vs "storm {i}"') == f"[{i}] OK"
            assert net.device.od.read(0x2013, 0) == b"storm 19"
            assert net.backend.nmt_state in ("PRE-OPERATIONAL", "OPERATIONAL")

    run(main())


def test_an_nmt_storm_with_stops_gets_values_or_the_state_error_only() -> None:
    """The same storm with stop and start to all in it: each request ends with its value
    or ERROR:204 (before: abort 0x08000022 or ERROR:102), and once the storm is over and
    the gateway started, every request succeeds again."""
    burst = [b"\x02\x00", b"\x80\x00", bytes([0x02, GW]), b"\x01\x00"]

    async def main() -> None:
        async with network() as net:
            data = os.urandom(880)
            net.device.od.write(0x2200, 0, data)
            text = base64.b64encode(data).decode()
            storming = [True]

            def storm(n: int) -> None:
                if storming[0]:
                    net.hostile.send(0x000, burst[n % len(burst)])

            _on_sdo_requests(net, storm)
            outcomes = set()
            for i in range(30):
                reply = await net.ask(f"[{i}] 2 r 0x2200 0 d")
                assert reply == f"[{i}] {text}" or reply.startswith(f"[{i}] ERROR:204 #"), reply
                outcomes.add(reply.split()[1][:9])
            assert "ERROR:204" in outcomes
            storming[0] = False
            net.hostile.send(0x000, b"\x01\x00")
            net.bus.run_for(1000)
            for i in range(3):
                assert await net.ask(f"[{i}] 2 r 0x2200 0 d") == f"[{i}] {text}"

    run(main())


@pytest.mark.realtime
def test_on_python_can_too(tmp_path: Path) -> None:
    """The same on python-can (the master's bus thread runs the state callbacks): OPERATIONAL
    by itself, stopped by a frame from another node, OPERATIONAL again after a reset
    communication to all (bounded waits, seconds of margin)."""
    channel = f"own-{tmp_path.name}"
    bus = can.Bus(interface="virtual", channel=channel)
    master = Master(bus, node_id=1)
    other = can.Bus(interface="virtual", channel=channel)
    master.start()
    try:
        backend = MasterBackend(master)

        def reaches(state: str) -> bool:
            end = time.monotonic() + 10
            while backend.nmt_state != state and time.monotonic() < end:
                time.sleep(0.01)
            return backend.nmt_state == state

        assert reaches("OPERATIONAL")
        other.send(can.Message(arbitration_id=0, data=b"\x02\x01", is_extended_id=False))
        assert reaches("STOPPED")
        other.send(can.Message(arbitration_id=0, data=b"\x82\x00", is_extended_id=False))
        assert reaches("OPERATIONAL")
        assert backend.sdo_closings >= 2
    finally:
        master.stop()
        bus.shutdown()
        other.shutdown()
