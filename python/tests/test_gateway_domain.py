# SPDX-License-Identifier: Apache-2.0
"""1 MiB through the gateway by SDO block transfer: a canola.Device whose DOMAIN streams
(canola.domain.DomainStream) on a simulated bus (virtual time)."""

from __future__ import annotations

import base64
import os
from pathlib import Path

import pytest
from gateway_helpers import Client, run
from test_gateway_master import serve

from canola import Device, Master
from canola.core import SimBus
from canola.domain import ABORT_TOO_LONG, DomainStream
from canola.errors import Error

SAMPLE = Path(__file__).parent / "golden" / "sample.eds"
GW = 127


@pytest.mark.slow
def test_one_mib_domain_block_write_and_read_back() -> None:
    async def main() -> None:
        bus = SimBus()
        master = Master(bus, node_id=GW)
        device = Device(SAMPLE, 2, bus)
        blob = DomainStream(device, 0x2200, 0, max_size=2 << 20)
        master.start()
        device.start()
        bus.run_for(10_000)
        written: list[tuple[int, int, object]] = []
        device.on_write(lambda index, sub, value: written.append((index, sub, value)))
        async with serve(master) as (address, _):
            c = await Client.connect(address)
            assert await c.ask("[1] set sdo_block 1") == "[1] OK"
            data = os.urandom(1 << 20)
            text = base64.b64encode(data).decode()
            assert await c.ask(f"[2] 2 w 0x2200 0 d {text}", timeout=600) == "[2] OK"
            assert blob.value == data
            bus.run_for(1000)
            assert written == [(0x2200, 0, data)]
            assert device.od.read(0x2200, 0) == data
            assert await c.ask("[3] 2 r 0x2200 0 d", timeout=600) == f"[3] {text}"
            # segmented too (small), and a download over max_size is refused, value kept
            assert await c.ask("[4] set sdo_block 0") == "[4] OK"
            assert await c.ask("[5] 2 w 0x2200 0 hex 01 02 03 04 05 06 07 08 09") == "[5] OK"
            assert blob.value == bytes(range(1, 10))
            blob.max_size = 8
            assert await c.ask("[6] 2 w 0x2200 0 hex 01 02 03 04 05 06 07 08 09") == \
                f"[6] ERROR:0x{ABORT_TOO_LONG:08X}"
            assert await c.ask("[7] 2 r 0x2200 0 hex") == "[7] 01 02 03 04 05 06 07 08 09"
            await c.close()

    run(main(), timeout=1200)  # wall-clock bounds of a virtual-time run: a starved machine


def test_domain_stream_application_side() -> None:
    device = Device(SAMPLE, 2, SimBus(), domain_size=16)
    blob = DomainStream(device, 0x2200, 0, value=b"first", max_size=100_000)
    assert device.od.read(0x2200, 0) == b"first"
    blob.value = bytes(50_000)  # more than the device's domain_size
    assert device.od.read(0x2200, 0) == bytes(50_000)
    device.od.write(0x2200, 0, b"\x01" * 70_000)
    assert blob.value == b"\x01" * 70_000
    with pytest.raises(Error, match="more than max_size"):
        blob.value = bytes(100_001)
    with pytest.raises(Error, match="no DOMAIN 0x1018 sub 1"):
        DomainStream(device, 0x1018, 1)
    with pytest.raises(Error, match="no DOMAIN 0x5000 sub 0"):
        DomainStream(device, 0x5000, 0)
    with pytest.raises(Error, match=r"canola\.Device is needed"):
        DomainStream(object(), 0x2200, 0)  # type: ignore[arg-type]

