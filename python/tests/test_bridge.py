# SPDX-License-Identifier: Apache-2.0
"""``slcan://`` buses and ``canola bus bridge``: an SLCAN adapter behind a TCP port (a fake
one here, speaking what the firmware images' UART speaks) joined to a hub channel; frames
both ways, the adapter closing, bad URLs. The firmware itself: tests/firmware (QEMU).

The bounds are a starved machine's: a ``canola`` process may take tens of seconds to start
and connect at load 40."""

from __future__ import annotations

import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator

import can
import pytest

from canola.bus.bridge import Bridge, BridgeSide, shutdown
from canola.bus.hub import HubThread
from canola.bus.open import BusError, open_bus, parse_bus_url

pytestmark = pytest.mark.realtime


WAIT_S = 60  # for a process to start and connect, or to end


class FakeAdapter:
    """An SLCAN adapter on a TCP port: answers O/C with CR, records the frame lines it is
    sent, sends the lines it is told to; one client at a time (as QEMU's serial port)."""

    def __init__(self) -> None:
        self._server = socket.create_server(("127.0.0.1", 0))
        self.port = self._server.getsockname()[1]
        self.lines: list[str] = []
        self._conn: socket.socket | None = None
        self._connected = threading.Event()
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        self._server.settimeout(WAIT_S)
        try:
            conn, _ = self._server.accept()
        except OSError:
            return
        self._conn = conn
        self._connected.set()
        conn.settimeout(0.2)
        rest = b""
        while True:
            try:
                data = conn.recv(4096)
            except TimeoutError:
                continue
            except OSError:
                return
            if not data:
                return
            rest += data
            while b"\r" in rest:
                line, rest = rest.split(b"\r", 1)
                text = line.decode()
                if text[:1] in ("O", "C"):
                    try:
                        conn.sendall(b"\r")
                    except OSError:  # the client went (python-can closes with C)
                        return
                elif text:
                    self.lines.append(text)

    def send(self, line: str) -> None:
        assert self._connected.wait(WAIT_S), "nobody connected"
        assert self._conn is not None
        self._conn.sendall(line.encode() + b"\r")

    def close(self) -> None:
        if self._conn is not None:
            self._conn.close()
        self._server.close()

    def wait_line(self, timeout: float = 30) -> str | None:
        deadline = time.monotonic() + timeout
        while not self.lines and time.monotonic() < deadline:
            time.sleep(0.02)
        return self.lines[0] if self.lines else None


@pytest.fixture
def adapter() -> Iterator[FakeAdapter]:
    fake = FakeAdapter()
    yield fake
    fake.close()


def test_slcan_urls() -> None:
    assert parse_bus_url("slcan://127.0.0.1:4000") == {
        "interface": "slcan", "channel": "socket://127.0.0.1:4000", "sleep_after_open": 0}
    assert parse_bus_url("slcan:///dev/ttyACM0")["channel"] == "/dev/ttyACM0"
    for bad in ("slcan://127.0.0.1", "slcan://", "slcan://h:99999"):
        with pytest.raises(BusError):
            parse_bus_url(bad)


def test_a_refused_adapter_is_one_line() -> None:
    with socket.create_server(("127.0.0.1", 0)) as s:
        port = s.getsockname()[1]
    with pytest.raises(BusError, match=f"cannot open slcan://127.0.0.1:{port}"):
        open_bus(url=f"slcan://127.0.0.1:{port}")


def _recv(bus: can.BusABC, timeout: float = 30) -> can.Message | None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        msg = bus.recv(0.1)
        if msg is not None:
            return msg
    return None


def test_frames_cross_the_bridge_both_ways(adapter: FakeAdapter) -> None:
    with HubThread() as hub:
        url = f"socketcand://127.0.0.1:{hub.port}/can0"
        far = open_bus(url=f"slcan://127.0.0.1:{adapter.port}")
        near = open_bus(url=url)
        peer = open_bus(url=url)
        try:
            with Bridge(BridgeSide(far, "adapter"), BridgeSide(near, url)) as bridge:
                peer.send(can.Message(arbitration_id=0x605, is_extended_id=False,
                                      data=bytes.fromhex("4000100000000000")))
                assert adapter.wait_line() == "t60584000100000000000"
                adapter.send("t58584300100091010000")
                msg = _recv(peer)
                assert msg is not None and msg.arbitration_id == 0x585
                assert bytes(msg.data) == bytes.fromhex("4300100091010000")
                adapter.send("T1ABCDEF02BEEF")
                msg = _recv(peer)
                assert msg is not None and msg.is_extended_id
                assert msg.arbitration_id == 0x1ABCDEF0 and bytes(msg.data) == b"\xbe\xef"
                assert bridge.running and bridge.error is None
                # the adapter goes away: the bridge ends by itself, saying which side
                adapter.close()
                assert bridge.wait(WAIT_S)
                assert bridge.error is not None and bridge.error.startswith("adapter: ")
        finally:
            for bus in (far, near, peer):
                shutdown(bus)


class BridgeCli:
    """``canola bus bridge`` in a subprocess, its output read as it comes (a thread)."""

    def __init__(self, adapter_port: int, hub_port: int) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "canola.cli", "bus", "bridge",
             f"slcan://127.0.0.1:{adapter_port}",
             "--bus", f"socketcand://127.0.0.1:{hub_port}/can0"],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.lines: list[str] = []
        self._joined = threading.Event()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.append(line.rstrip("\n"))
            if " joined to " in line:
                self._joined.set()

    def joined(self) -> bool:
        """True once it says both sides are open (at most WAIT_S)."""
        return self._joined.wait(WAIT_S)

    def end(self) -> int:
        """Its exit code (SIGTERM first if it still runs; killed past WAIT_S)."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        try:
            self.proc.wait(WAIT_S)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(10)
        self._reader.join(10)
        return self.proc.returncode


def test_bridge_command_stops_on_sigterm(adapter: FakeAdapter) -> None:
    with HubThread() as hub:
        cli = BridgeCli(adapter.port, hub.port)
        try:
            assert cli.joined(), cli.lines
            peer = open_bus(url=f"socketcand://127.0.0.1:{hub.port}/can0")
            try:
                got = None
                deadline = time.monotonic() + WAIT_S
                while got is None and time.monotonic() < deadline:
                    adapter.send("t70517F")  # again until the peer has joined the channel
                    got = _recv(peer, 0.5)
                assert got is not None and got.arbitration_id == 0x705, cli.lines
            finally:
                shutdown(peer)
        finally:
            code = cli.end()
    assert code == 0, cli.lines
    assert cli.lines[-1].startswith("canola bus: ") and " frames from " in cli.lines[-1]


def test_bridge_command_says_which_side_closed(adapter: FakeAdapter) -> None:
    with HubThread() as hub:
        cli = BridgeCli(adapter.port, hub.port)
        try:
            assert cli.joined(), cli.lines
            adapter.close()
            cli.proc.wait(WAIT_S)
        finally:
            code = cli.end()
    assert code == 1, cli.lines
    assert cli.lines[-1].startswith(f"canola: bus bridge: slcan://127.0.0.1:{adapter.port}: ")


def test_bridge_command_refused_adapter() -> None:
    with socket.create_server(("127.0.0.1", 0)) as s:
        port = s.getsockname()[1]
    with HubThread() as hub:
        r = subprocess.run(
            [sys.executable, "-m", "canola.cli", "bus", "bridge", f"slcan://127.0.0.1:{port}",
             "--bus", f"socketcand://127.0.0.1:{hub.port}/can0"],
            check=False, capture_output=True, text=True, timeout=WAIT_S)
    assert r.returncode == 1
    assert len(r.stderr.strip().splitlines()) == 1
    assert f"slcan://127.0.0.1:{port}" in r.stderr
