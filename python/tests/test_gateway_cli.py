# SPDX-License-Identifier: Apache-2.0
"""``canola gateway`` / ``python -m canola.gateway`` as processes (simulated network)."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import signal
import subprocess
import sys
from pathlib import Path

import can
import pytest
from conftest import wait_until
from gateway_helpers import Client, gateway_process, run

from canola import Device
from canola.cli import main as canola_main
from canola.gateway.cli import _serve

pytestmark = pytest.mark.realtime

SAMPLE = Path(__file__).parent / "golden" / "sample.eds"
SIM = ["--simulate", str(SAMPLE), "--sim-node", "2", "--sim-node", "3"]


@pytest.mark.slow
def test_stdio_script() -> None:
    script = ("[1] 2 r 0x1008 0 vs\n# comment\n[2] set node 3\n[3] r 0x1000 0 u32\n"
              "[4] 2 w 0x200C 0 u32 0x10\n[5] 2 r 0x200C 0 x32\nnonsense\n[6] 9 9 9 r\n"
              "[7] 127 stop\n[8] 127 r 0x1017 0 u16\n")
    done = subprocess.run([sys.executable, "-m", "canola.gateway", *SIM, "--listen", "stdio"],
                          input=script.encode(), capture_output=True, timeout=300, check=True)
    # one reply per line, each ended by CR LF; the comment's is empty, the line without
    # [seq] has the last sequence number seen (as CANopenNode's gateway answers)
    assert done.stdout.decode().split("\r\n") == [
        '[1] "canola sample"', "", "[2] OK", "[3] 401", "[4] OK", "[5] 0x00000010",
        "[5] ERROR:101", "[6] ERROR:101", "[7] OK", "[8] 0", ""]


@pytest.mark.slow
def test_tcp_process_and_sigterm() -> None:
    with gateway_process(*SIM) as (proc, address):
        async def main() -> None:
            c = await Client.connect(address)
            assert await c.ask("[1] 3 r 0x1018 1 u32") == "[1] 3232"
            await c.close()

        run(main())
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=300) == 0


def test_canola_command_arguments() -> None:
    assert canola_main(["gateway", "--listen", "udp:1", *SIM]) == 2
    assert canola_main(["gateway", "--iface", "can0", "--bus", "virtual://x"]) == 2
    assert canola_main(["gateway", "--node-id", "200", *SIM]) == 2
    assert canola_main(["gateway", "--max-clients", "0", *SIM]) == 2
    assert canola_main(["gateway", "--idle-timeout", "-1", *SIM]) == 2
    assert canola_main(["gateway", "--idle-timeout", "soon", *SIM]) == 2
    assert canola_main(["gateway", "--max-queued", "1000", *SIM]) == 2  # a line must fit
    assert canola_main(["gateway", "--max-queued-total", "5000000", *SIM]) == 2


def test_listen_on_unix_socket_in_process(tmp_path: Path) -> None:
    args = argparse.Namespace(simulate=str(SAMPLE), sim_node=[2], node_id=None, eds=None,
                              listen=f"unix:{tmp_path / 'gw.sock'}", max_clients=2,
                              max_line=1000, iface=None, bus=None, sdo_timeout=1000)

    async def main() -> None:
        task = asyncio.create_task(_serve(args))
        path = tmp_path / "gw.sock"
        async with asyncio.timeout(20):
            while not path.exists():
                await asyncio.sleep(0.01)
        c = await Client.connect(f"unix:{path}")
        assert await c.ask("[1] 2 r 0x1000 0 u32") == "[1] 401"
        await c.close()
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task

    run(main())


def test_real_bus_through_canola_master(tmp_path: Path) -> None:
    """``--bus virtual://CHANNEL``: canola.Master on python-can, a canola.Device peer."""
    channel = f"gw-cli-{tmp_path.name}"
    device = Device(SAMPLE, 2, can.Bus(interface="virtual", channel=channel))
    device.start()
    path = tmp_path / "gw.sock"
    args = argparse.Namespace(simulate=None, sim_node=[], node_id=None, eds=None,
                              listen=f"unix:{path}", max_clients=2, max_line=1000, iface=None,
                              bus=f"virtual://{channel}", sdo_timeout=1000)

    async def main() -> None:
        task = asyncio.create_task(_serve(args))
        async with asyncio.timeout(20):
            while not path.exists():
                await asyncio.sleep(0.01)
        c = await Client.connect(f"unix:{path}")
        assert await c.ask("[1] 2 r 0x1018 1 u32") == "[1] 3232"
        assert await c.ask("[2] 127 r 0x1000 0 u32") == "[2] 0"  # the master's own
        assert await c.ask("[3] 2 start") == "[3] OK"
        await c.close()
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task

    try:
        run(main())
        # "OK" says the frame was sent; the device's own bus thread applies it a moment later
        assert wait_until(lambda: device.nmt_state == "OPERATIONAL"), device.nmt_state
    finally:
        device.stop()
        device.bus.shutdown()
