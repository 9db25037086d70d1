# SPDX-License-Identifier: Apache-2.0
"""canola-node (the C device of port/linux, with its own socketcand client) on the hub,
driven by the canola command.

Needs the canola-node program: CANOLA_NODE_BIN, or build/canola-node as ``make`` builds it
(the Linux port's branch brings it). Without it the tests are skipped and say so.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from cli_helpers import cli

from canola.bus.hub import HubThread

ROOT = Path(__file__).resolve().parents[2]
NODE_BIN = Path(os.environ.get("CANOLA_NODE_BIN", ROOT / "build" / "canola-node"))

pytestmark = [pytest.mark.slow, pytest.mark.realtime,
              pytest.mark.skipif(not NODE_BIN.is_file(),
                                 reason=f"no canola-node program at {NODE_BIN}")]


@pytest.fixture
def c_node() -> Iterator[tuple[str, subprocess.Popen[str]]]:
    with HubThread() as hub:
        url = f"socketcand://127.0.0.1:{hub.port}/cnode"
        proc = subprocess.Popen([str(NODE_BIN), "--bus", url, "--node-id", "12",
                                 "--heartbeat", "100"], stderr=subprocess.PIPE, text=True)
        try:
            deadline = time.monotonic() + 60
            while not any(c.channel == "cnode" for c in hub.hub.clients()):
                assert time.monotonic() < deadline and proc.poll() is None
                time.sleep(0.02)
            yield url, proc
        finally:
            proc.send_signal(signal.SIGTERM)
            try:
                _, err = proc.communicate(timeout=300)
            finally:
                if proc.poll() is None:
                    proc.kill()
                    proc.wait(10)
            assert proc.returncode == 0, err
            assert "stopped by SIGTERM" in err


def test_c_node_through_the_hub(capsys: pytest.CaptureFixture[str],
                                c_node: tuple[str, subprocess.Popen[str]]) -> None:
    url, _ = c_node
    code, out, _ = cli(capsys, "scan", "--bus", url, "--json", "--timeout", "3000")
    assert code == 0 and [n["node"] for n in json.loads(out)] == [12]
    assert cli(capsys, "sdo", "read", "12", "0x1018:1", "--bus", url)[:2] == (0, "0x00000CA0\n")
    code, out, _ = cli(capsys, "sdo", "read", "12", "0x1008:0", "vs", "--bus", url)
    assert code == 0 and out.strip()
    assert cli(capsys, "sdo", "write", "12", "0x1017:0", "u16", "150", "--bus", url)[0] == 0
    assert cli(capsys, "sdo", "read", "12", "0x1017:0", "u16", "--bus", url)[1] == "150\n"
    assert cli(capsys, "nmt", "start", "12", "--bus", url)[0] == 0
    # heartbeats every 100 ms: the last of 2 s tells the state (how regular they are is
    # the benchmark's business, not a test's)
    code, out, _ = cli(capsys, "monitor", "--bus", url, "--json", "--duration", "2")
    node = json.loads(out)["nodes"][0]
    assert (node["node"], node["state"]) == (12, "OPERATIONAL")
    assert 0 < node["heartbeat_gap"] < 2


def test_c_node_proves_the_token_of_a_hub_that_asks(capsys: pytest.CaptureFixture[str],
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """A hub with a token: canola-node without it is refused and says why; with
    CANOLA_TOKEN (or --token) it joins, and a canola command with the same variable
    reaches it."""
    token = "c-node-token-0123456789"
    with HubThread(token=token) as hub:
        url = f"socketcand://127.0.0.1:{hub.port}/cnode"
        env = {k: v for k, v in os.environ.items() if k != "CANOLA_TOKEN"}
        refused = subprocess.run([str(NODE_BIN), "--bus", url, "--node-id", "12"], env=env,
                                 capture_output=True, text=True, timeout=60, check=False)
        assert refused.returncode == 1
        assert "authentication required" in refused.stderr, refused.stderr
        proc = subprocess.Popen([str(NODE_BIN), "--bus", url, "--node-id", "12"],
                                env={**env, "CANOLA_TOKEN": token}, stderr=subprocess.PIPE,
                                text=True)
        try:
            deadline = time.monotonic() + 60
            while not any(c.channel == "cnode" for c in hub.hub.clients()):
                assert time.monotonic() < deadline and proc.poll() is None
                time.sleep(0.02)
            monkeypatch.setenv("CANOLA_TOKEN", token)
            assert cli(capsys, "sdo", "read", "12", "0x1018:1", "--bus", url)[:2] == (
                0, "0x00000CA0\n")
        finally:
            proc.kill()
            proc.communicate(timeout=60)
