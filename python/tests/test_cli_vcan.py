# SPDX-License-Identifier: Apache-2.0
"""A device and the canola command on one bus, in separate processes: SocketCAN when
CANOLA_VCAN names an interface (the SocketCAN tier runs these with -m vcan), otherwise a hub
(``canola bus serve`` in a subprocess), so the same test runs everywhere."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from cli_helpers import cli

pytestmark = [pytest.mark.slow, pytest.mark.realtime]

EDS = Path(__file__).parent / "data" / "cli_device.eds"
PY = sys.executable


def _wait_line(proc: subprocess.Popen[str], pattern: str, timeout: float = 90) -> str:
    assert proc.stdout is not None
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        if re.search(pattern, line):
            return line
    raise AssertionError(f"no {pattern!r} from {proc.args}")


@pytest.fixture(scope="module")
def bus_opts() -> Iterator[list[str]]:
    vcan = os.environ.get("CANOLA_VCAN")
    if vcan:
        yield ["--iface", vcan]
        return
    hub = subprocess.Popen([PY, "-m", "canola.cli", "bus", "serve", "--port", "0"],
                           stdout=subprocess.PIPE, text=True)
    try:
        port = re.search(r":(\d+) ", _wait_line(hub, "hub on"))
        assert port is not None
        yield ["--bus", f"socketcand://127.0.0.1:{port.group(1)}/vcantier"]
    finally:
        hub.terminate()
        hub.wait(10)


@pytest.mark.vcan
def test_device_and_cli_processes(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                  bus_opts: list[str]) -> None:
    dev = subprocess.Popen([PY, "-m", "canola.cli", "device", "--eds", str(EDS), "--node-id",
                            "33", "--sdo-timeout", "5000", *bus_opts], stdout=subprocess.PIPE,
                           text=True)
    # answers come late under emulation (the SocketCAN tier) or on a busy machine: the
    # time-outs are generous (an answer ends the wait)
    slow = ["--timeout", "5000"]
    try:
        _wait_line(dev, "node 33: PRE-OPERATIONAL")
        assert cli(capsys, "sdo", "read", "33", "0x1018:1", *bus_opts, *slow)[:2] == (
            0, "0x00000CA0\n")
        assert cli(capsys, "sdo", "write", "33", "0x2001:0", "i16", "-42", *bus_opts,
                   *slow)[0] == 0
        assert cli(capsys, "sdo", "read", "33", "0x2001:0", "i16", *bus_opts, *slow)[1] == "-42\n"
        blob = os.urandom(1500)
        (tmp_path / "in.bin").write_bytes(blob)
        assert cli(capsys, "sdo", "download", "33", "0x2004:0", str(tmp_path / "in.bin"),
                   *bus_opts, *slow)[::2] == (0, "")
        assert cli(capsys, "sdo", "upload", "33", "0x2004:0", str(tmp_path / "out.bin"),
                   *bus_opts, *slow)[::2] == (0, "")
        assert (tmp_path / "out.bin").read_bytes() == blob
        code, out, err = cli(capsys, "sdo", "read", "34", "0x1000:0", "--timeout", "200",
                             *bus_opts)
        assert (code, out) == (1, "")
        assert err.startswith("canola: no response from node 34 (SDO time-out 200 ms, after ")
        code, out, _ = cli(capsys, "scan", *bus_opts, "--json", *slow)  # collects for 5 s
        assert 33 in [n["node"] for n in json.loads(out)]
        assert cli(capsys, "nmt", "start", "33", *bus_opts)[0] == 0
        _wait_line(dev, "node 33: OPERATIONAL")
        code, out, _ = cli(capsys, "monitor", *bus_opts, "--json", "--duration", "2")
        nodes = {n["node"]: n for n in json.loads(out)["nodes"]}
        assert nodes[33]["state"] == "OPERATIONAL"
    finally:
        dev.send_signal(signal.SIGTERM)
        assert dev.wait(10) == 0
