# SPDX-License-Identifier: Apache-2.0
"""CANopenDemo's heartbeat-consumer suite (test/running_canopen/heartbeat_consumer.bats,
run through cocomm) against canola's gateway: what each of its steps expects, written
here from what it checks, on a simulated bus in virtual time.

The suite's network: D1 is the gateway (node 1, the device with the command interface),
D2 a device (node 4) whose heartbeat consumer watches D1; heartbeat period 160 ms,
consumer time 240 ms. cocomm sends the lines over the gateway's text protocol and prints
the reply and the first N frames candump sees: here a TCP client sends the lines and the
frames come from the simulated bus's trace. Before this suite runs, CANopenDemo's basic
suite leaves D1 started and then sends ``0 preoperational``.

Against CANopenNode's canopend as D1 all eight steps pass; canola's gateway failed steps
1, 2, 4, 5 and 8: an NMT command to all nodes did not reach its own node (no boot-up on
``0 reset communication``, its heartbeat still said OPERATIONAL after
``0 preoperational``), and after its own reset it stayed PRE-OPERATIONAL where canopend,
an NMT master that starts itself, goes OPERATIONAL.

One difference is canopend's, not the gateway's: after a reset communication canopend
keeps the heartbeat period written before (CANopenLinux loads its parameters once, at
start), which CiA 301 sets back to its power-on value. Step 5 expects heartbeats after
the reset, so the gateway here is given 160 ms as its power-on 0x1017 (``--eds``).
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from gateway_helpers import Client, client_of, run

from canola import Device, Master
from canola.core import SimBus
from canola.gateway.masterbackend import MasterBackend
from canola.master import MASTER_EDS

EXAMPLE = Path(__file__).parents[2] / "examples" / "example_od.eds"
D1, D2 = 1, 4
HB, HB_TIMEOUT = 0xA0, 0xF0  # 160 ms, 240 ms


def _with_heartbeat(source: str, period_ms: int, where: Path) -> Path:
    """A copy of the EDS ``source`` whose 0x1017 powers on at ``period_ms``."""
    text = Path(source).read_text()
    head, _, rest = text.partition("[1017]")
    section, _, tail = rest.partition("\n\n")
    lines = [f"DefaultValue={period_ms}" if line.startswith("DefaultValue=") else line
             for line in section.splitlines()]
    where.write_text(head + "[1017]" + "\n".join(lines) + "\n\n" + tail)
    return where


@dataclass
class Network:
    bus: SimBus
    gateway: Master
    device: Device
    client: Client

    async def cocomm(self, *lines: str, window_ms: int = 500) -> tuple[list[str], list[str]]:
        """Send ``lines`` one after the other, as cocomm does: their replies, and the
        frames seen from the first line until ``window_ms`` after the last reply."""
        before = len(self.bus.trace)
        replies = [await self.client.ask(line) for line in lines]
        self.bus.run_for(window_ms * 1000)
        return replies, [line.split()[-1] for line in self.bus.trace[before:]]


@contextlib.asynccontextmanager
async def network(tmp_path: Path) -> AsyncIterator[Network]:
    """D1 (the gateway, its 0x1017 powering on at 160 ms) and D2 (0x1017 off at power-on,
    as CANopenDemo's device) on a SimBus; the gateway served over TCP, virtual time moved
    by the test alone. Then the end of CANopenDemo's basic suite: D1 started, then
    ``0 preoperational``."""
    bus = SimBus()
    gateway = Master(bus, node_id=D1,
                     eds_file=_with_heartbeat(MASTER_EDS, HB, tmp_path / "d1.eds"))
    device = Device(_with_heartbeat(str(EXAMPLE), 0, tmp_path / "d2.eds"), D2, bus)
    gateway.start()
    device.start()
    bus.run_for(10_000)
    async with client_of(MasterBackend(gateway)) as client:
        net = Network(bus, gateway, device, client)
        assert (await net.cocomm(f"[1] {D1} start", "[2] 0 preoperational"))[0] == [
            "[1] OK", "[2] OK"]
        yield net


def _ok(*seqs: int) -> list[str]:
    return [f"[{seq}] OK" for seq in seqs]


def _sdo_write(node: int, index: int, sub: int, value: int, size: int) -> list[str]:
    """The expedited download of ``value`` and its confirmation, as candump shows them."""
    cs = {1: 0x2F, 2: 0x2B, 4: 0x23}[size]
    request = bytes([cs, index & 0xFF, index >> 8, sub]) + value.to_bytes(4, "little")
    answer = bytes([0x60, index & 0xFF, index >> 8, sub, 0, 0, 0, 0])
    return [f"{0x600 + node:03X}#{request.hex().upper()}",
            f"{0x580 + node:03X}#{answer.hex().upper()}"]


def _gateway_frames(frames: list[str]) -> list[str]:
    """NMT commands and the gateway's own error control frames, in order."""
    return [f for f in frames if f.startswith(("000#", f"{0x700 + D1:03X}#"))]


def _emcy_codes(frames: list[str]) -> list[int]:
    """The error codes of D2's EMCY frames, in order."""
    return [int.from_bytes(bytes.fromhex(f[4:8]), "little") for f in frames
            if f.startswith(f"{0x80 + D2:03X}#")]


# The suite's steps: each test runs the ones before it first (virtual time: instants).

async def _step1(net: Network) -> None:
    """Heartbeat producer on D1 only: D2's heartbeat and consumer off, every node reset
    by one command to all, D1 producing; then all pre-operational."""
    replies, frames = await net.cocomm(
        f"[1] {D2} w 0x1017 0 i16 0", f"[2] {D2} w 0x1016 2 u32 0",
        "[3] 0 reset communication", f"[4] {D1} w 0x1017 0 i16 0x{HB:X}")
    assert replies == _ok(1, 2, 3, 4)
    assert frames[:4] == _sdo_write(D2, 0x1017, 0, 0, 2) + _sdo_write(D2, 0x1016, 2, 0, 4)
    assert frames[4] == "000#8200"
    assert sorted(frames[5:7]) == [f"{0x700 + D1:03X}#00", f"{0x700 + D2:03X}#00"]  # D1's too
    # started by itself after its boot-up, as an NMT master does (canopend too)
    assert _gateway_frames(frames[7:])[:1] == [f"{0x700 + D1:03X}#05"]
    replies, frames = await net.cocomm("[1] 0 preoperational", window_ms=200)
    assert replies == _ok(1)
    assert frames == ["000#8000", f"{0x700 + D1:03X}#7F"]


async def _step2(net: Network) -> None:
    """Heartbeat consumer on D2, watching D1: D1's pre-operational heartbeats go on."""
    replies, frames = await net.cocomm(f"[1] {D2} w 0x1016 2 u32 0x00{D1:02X}00{HB_TIMEOUT:02X}",
                                       window_ms=340)
    assert replies == _ok(1)
    assert frames == _sdo_write(D2, 0x1016, 2, D1 << 16 | HB_TIMEOUT, 4) + [
        f"{0x700 + D1:03X}#7F"] * 2


async def _step3(net: Network) -> None:
    """D1's heartbeat stops: D2 reports the loss (EMCY 0x8130)."""
    replies, frames = await net.cocomm(f"[1] {D1} w 0x1017 0 i16 0", window_ms=400)
    assert replies == _ok(1)
    assert _emcy_codes(frames) == [0x8130]
    assert _gateway_frames(frames) == []


async def _step4(net: Network) -> None:
    """D1's heartbeat again: pre-operational; D2's error is reset."""
    replies, frames = await net.cocomm(f"[1] {D1} w 0x1017 0 i16 0x{HB:X}", window_ms=340)
    assert replies == _ok(1)
    assert _gateway_frames(frames) == [f"{0x700 + D1:03X}#7F"] * 2
    assert _emcy_codes(frames) == [0x0000]


async def _step5(net: Network) -> None:
    """D1 resets its communication: the NMT frame, its boot-up, then OPERATIONAL (an NMT
    master starts itself) at its power-on heartbeat period."""
    replies, frames = await net.cocomm(f"[1] {D1} reset communication", window_ms=340)
    assert replies == _ok(1)
    assert _gateway_frames(frames) == [f"000#82{D1:02X}", f"{0x700 + D1:03X}#00"] + [
        f"{0x700 + D1:03X}#05"] * 2
    assert net.gateway.nmt_state == "OPERATIONAL"
    assert 0x8130 not in _emcy_codes(frames)  # its heartbeat never stopped long


async def _step8(net: Network) -> None:
    """Cleanup: D1's heartbeat off, D2's consumers off, every node reset: seven frames,
    D1's boot-up among them."""
    replies, frames = await net.cocomm(
        f"[1] {D1} w 0x1017 0 i16 0", f"[2] {D2} w 0x1016 2 u32 0",
        f"[3] {D2} w 0x1016 3 u32 0", "[4] 0 reset communication", window_ms=100)
    assert replies == _ok(1, 2, 3, 4)
    assert frames[:5] == _sdo_write(D2, 0x1016, 2, 0, 4) + _sdo_write(D2, 0x1016, 3, 0, 4) + [
        "000#8200"]
    assert sorted(frames[5:7]) == [f"{0x700 + D1:03X}#00", f"{0x700 + D2:03X}#00"]


_STEPS = [_step1, _step2, _step3, _step4, _step5]


#: The suite's steps by number (6 and 7 check D2's own consumer configuration: not the
#: gateway's business), named as in the bats file.
_NAMES = {1: "heartbeat producer on D1 only", 2: "heartbeat consumer on D2",
          3: "heartbeat producer D1 missing", 4: "heartbeat producer D1 established",
          5: "boot-up message D1", 8: "cleanup"}


@pytest.mark.parametrize("step", list(_NAMES), ids=[f"{n} {t}" for n, t in _NAMES.items()])
def test_step(tmp_path: Path, step: int) -> None:
    """Run the suite's steps before ``step`` (8 follows 5), then ``step``. As in bats, an
    earlier step's failed check does not stop the later ones: each test fails on its own
    step's checks only."""
    async def main() -> None:
        async with network(tmp_path) as net:
            for earlier in _STEPS[:min(step, 6) - 1]:
                with contextlib.suppress(AssertionError):
                    await earlier(net)
            await (_step8 if step == 8 else _STEPS[step - 1])(net)

    run(main())


def test_a_reset_from_another_node_starts_the_gateway_again() -> None:
    """The gateway follows NMT from the bus as from its clients: a reset communication to
    all from another node brings its boot-up, then OPERATIONAL by itself; a stop to its
    node-ID stops it."""
    bus = SimBus()
    gateway = Master(bus, node_id=D1)
    other = Master(bus, node_id=9, announce=False)
    gateway.start()
    other.start()
    bus.run_for(10_000)
    backend = MasterBackend(gateway)
    bus.run_for(1000)
    assert backend.nmt_state == "OPERATIONAL"
    for frame, state in [(b"\x82\x00", "OPERATIONAL"), (bytes([0x02, D1]), "STOPPED"),
                         (b"\x81\x00", "OPERATIONAL"), (b"\x80\x00", "PRE-OPERATIONAL")]:
        before = len(bus.trace)
        other.send(0x000, frame)
        bus.run_for(1000)
        assert backend.nmt_state == state, frame
        boot = [line.split()[-1] for line in bus.trace[before:]].count(f"{0x700 + D1:03X}#00")
        assert boot == (1 if frame[0] in (0x81, 0x82) else 0)
    asyncio.run(backend.local_nmt("stop"))  # the application may still stop it
    assert backend.nmt_state == "STOPPED"


def test_with_0x1f80_bit_2_the_gateway_stays_pre_operational(tmp_path: Path) -> None:
    """An NMT master whose 0x1F80 has bit 2 set does not start itself (CiA 302-2): after
    its boot-up the gateway stays PRE-OPERATIONAL until a command starts it."""
    text = Path(MASTER_EDS).read_text().replace(
        "SupportedObjects=25\n", "SupportedObjects=26\n26=0x1F80\n", 1)
    eds = tmp_path / "no_self_start.eds"
    eds.write_text(text + "\n[1F80]\nParameterName=NMT start-up\nObjectType=0x7\n"
                          "DataType=0x0007\nAccessType=rw\nDefaultValue=0x5\nPDOMapping=0\n")
    bus = SimBus()
    gateway = Master(bus, node_id=D1, eds_file=eds)
    gateway.start()
    bus.run_for(10_000)
    backend = MasterBackend(gateway)
    assert not backend.own.self_start
    for command in ("reset_comm", "reset_node"):
        asyncio.run(backend.local_nmt(command))
        bus.run_for(1000)
        assert backend.nmt_state == "PRE-OPERATIONAL", command
    asyncio.run(backend.local_nmt("start"))
    assert backend.nmt_state == "OPERATIONAL"
