# SPDX-License-Identifier: Apache-2.0
"""The socketcand hub with python-can's own socketcand interface as the clients."""

from __future__ import annotations

import socket
import subprocess
import sys
import time
from collections.abc import Iterator

import can
import pytest
from bounded import first_line
from cli_helpers import cli

from canola.bus import hub as hub_module
from canola.bus.hub import Hub, HubThread, exposed_addresses
from canola.bus.socketcand import Frame, parse_server_element, split_elements

TOKEN = "hub-test-token-0123456789"

pytestmark = pytest.mark.realtime


@pytest.fixture
def hub() -> Iterator[HubThread]:
    with HubThread(queue_limit=64) as h:
        yield h


def _bus(port: int, channel: str = "bus0") -> can.BusABC:
    return can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel=channel)


def _recv_all(bus: can.BusABC, count: int, timeout: float = 5.0) -> list[can.Message]:
    got: list[can.Message] = []
    deadline = time.monotonic() + timeout
    while len(got) < count and time.monotonic() < deadline:
        msg = bus.recv(0.1)
        if msg is not None:
            got.append(msg)
    return got


def _settle() -> None:
    time.sleep(0.15)  # past the hub's rawmode settle delay


def _raw(port: int) -> socket.socket:
    s = socket.create_connection(("127.0.0.1", port), timeout=30)  # a bound, not a wait
    assert s.recv(64) == b"< hi >"
    return s


def _recv_until(s: socket.socket, marker: bytes, timeout: float = 30.0) -> bytes:
    s.settimeout(timeout)
    data = b""
    while marker not in data:
        chunk = s.recv(4096)
        if not chunk:
            break
        data += chunk
    return data


def test_frames_reach_every_other_client_on_the_channel(hub: HubThread) -> None:
    a, b, c = _bus(hub.port), _bus(hub.port), _bus(hub.port)
    other = _bus(hub.port, "bus1")
    try:
        _settle()
        a.send(can.Message(arbitration_id=0x123, data=b"\x11\x22", is_extended_id=False))
        a.send(can.Message(arbitration_id=0x1ABCDEF0, data=b"", is_extended_id=True))
        for peer in (b, c):
            got = _recv_all(peer, 2)
            assert [(m.arbitration_id, bytes(m.data), m.is_extended_id) for m in got] == [
                (0x123, b"\x11\x22", False), (0x1ABCDEF0, b"", True)]
        assert a.recv(0.2) is None  # not to the sender
        assert other.recv(0.2) is None  # channels are separate buses
        other.send(can.Message(arbitration_id=0x7FF, data=bytes(8), is_extended_id=False))
        assert a.recv(0.2) is None
    finally:
        for bus in (a, b, c, other):
            bus.shutdown()


def test_handshake_errors_and_echo(hub: HubThread) -> None:
    s = _raw(hub.port)
    s.sendall(b"< rawmode >")
    assert b"< error" in _recv_until(s, b">")
    assert s.recv(64) == b""  # disconnected
    s = _raw(hub.port)
    s.sendall(b"< open x >< echo >< subscribe 0 0 123 >")
    data = _recv_until(s, b"not offered")
    assert data.startswith(b"< ok >< echo >< error ")
    s.sendall(b"< rawmode >")
    assert _recv_until(s, b"< ok >") == b"< ok >"  # still connected
    s.close()


def test_garbage_and_abrupt_disconnects_do_not_disturb_others(hub: HubThread) -> None:
    a, b = _bus(hub.port), _bus(hub.port)
    try:
        _settle()
        for junk in (b"GET / HTTP/1.0\r\n\r\n", b"< open bus0 >< rawmode >< send 999 0 >",
                     b"< open bus0 >< rawmode >< send 12" + b"3" * 500, b"\xff\xfe\x00"):
            s = _raw(hub.port)
            s.sendall(junk)
            reply = _recv_until(s, b"< error")
            assert b"< error" in reply
            s.close()
        for _ in range(5):  # connect, join, vanish mid-element
            s = _raw(hub.port)
            s.sendall(b"< open bus0 >< rawmode >< send 12")
            s.close()
        a.send(can.Message(arbitration_id=0x181, data=b"\x01", is_extended_id=False))
        got = _recv_all(b, 1)
        assert [(m.arbitration_id, bytes(m.data)) for m in got] == [(0x181, b"\x01")]
        # the junk senders never delivered a frame
        assert b.recv(0.2) is None
    finally:
        a.shutdown()
        b.shutdown()
    deadline = time.monotonic() + 5
    while hub.hub.clients() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert hub.hub.clients() == []


def test_slow_client_loses_frames_but_stalls_nobody(hub: HubThread) -> None:
    slow = _raw(hub.port)
    slow.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    slow.sendall(b"< open bus0 >< rawmode >")
    assert _recv_until(slow, b"< ok >< ok >") == b"< ok >< ok >"
    a, b = _bus(hub.port), _bus(hub.port)
    try:
        _settle()
        count = 20000
        start = time.monotonic()
        received = 0
        for burst in range(0, count, 32):  # a bus has no flow control: pace like a real one
            for i in range(burst, burst + 32):
                a.send(can.Message(arbitration_id=0x200, data=i.to_bytes(2, "little"),
                                   is_extended_id=False))
            received += len(_recv_all(b, 32))
        assert received == count  # the fast reader got everything
        assert time.monotonic() - start < 120  # a stall would cost 5 s per burst
        stats = {s.peer: s for s in hub.hub.clients()}
        slow_stats = stats[f"127.0.0.1:{slow.getsockname()[1]}"]
        assert slow_stats.dropped > 0  # the slow reader lost frames, counted
        assert slow_stats.delivered + slow_stats.dropped == count
        # bounded: what the slow client can still read is at most queue + socket buffers
        slow.setblocking(False)
        pending = b""
        time.sleep(0.3)
        while True:
            try:
                chunk = slow.recv(65536)
            except BlockingIOError:
                break
            if not chunk:
                break
            pending += chunk
        assert pending.count(b"< frame") <= slow_stats.delivered
    finally:
        a.shutdown()
        b.shutdown()
        slow.close()


@pytest.mark.slow
def test_serve_command_in_a_subprocess() -> None:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    proc = subprocess.Popen([sys.executable, "-m", "canola.cli", "bus", "serve", "--port",
                             str(port)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    try:
        line = first_line(proc.stdout, "canola bus serve")
        assert f"127.0.0.1:{port}" in line
        a, b = _bus(port), _bus(port)
        _settle()
        a.send(can.Message(arbitration_id=0x701, data=b"\x05", is_extended_id=False))
        assert [bytes(m.data) for m in _recv_all(b, 1)] == [b"\x05"]
        a.shutdown()
        b.shutdown()
    finally:
        proc.terminate()
        assert proc.wait(10) == 0


@pytest.mark.slow
def test_port_in_use_is_one_line_error() -> None:
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        proc = subprocess.run([sys.executable, "-m", "canola.cli", "bus", "serve", "--port",
                               str(port)], capture_output=True, text=True, timeout=300,
                              check=False)
    assert proc.returncode != 0
    assert len(proc.stderr.strip().splitlines()) == 1
    assert "Traceback" not in proc.stderr


def test_remote_frames_and_raw_clients(hub: HubThread) -> None:
    a, b = _raw(hub.port), _raw(hub.port)
    for s in (a, b):
        s.sendall(b"< open rtr >< rawmode >")
        assert _recv_until(s, b"< ok >< ok >") == b"< ok >< ok >"
    time.sleep(0.15)
    a.sendall(b"< sendrtr 70C 1 >< send 1FFFFFFF 1 AA >\n< send 0 0 >")
    data = _recv_until(b, b"  >")  # the last one, with no data
    elements, rest = split_elements(data)
    assert rest == b""
    got = [parse_server_element(e)[:2] for e in elements]
    assert got == [("rtr", Frame(0x70C, rtr=True, dlc=1)),
                   ("frame", Frame(0x1FFFFFFF, b"\xaa", extended=True)),
                   ("frame", Frame(0, b""))]
    a.close()
    b.close()


def test_silent_clients_are_closed_but_open_ones_may_idle() -> None:
    with HubThread(handshake_timeout=0.3) as h:
        silent, opened = _raw(h.port), _raw(h.port)
        opened.sendall(b"< open idle >")
        assert _recv_until(opened, b"< ok >") == b"< ok >"
        assert b"handshake" in _recv_until(silent, b" >")
        assert silent.recv(64) == b""
        time.sleep(0.5)
        opened.sendall(b"< echo >")  # in BCM mode, sending only: still welcome
        assert _recv_until(opened, b"< echo >") == b"< echo >"
        silent.close()
        opened.close()


def test_client_that_does_not_read_its_replies_is_disconnected() -> None:
    """``< echo >`` after ``< echo >`` without reading a reply: the hub's queue for that
    client stays bounded, the client is disconnected and counted, the others carry on."""
    with HubThread(queue_limit=64, reply_limit=64, write_buffer=4096) as h:
        greedy = socket.socket()
        greedy.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)  # before connect
        greedy.connect(("127.0.0.1", h.port))
        greedy.settimeout(5)
        assert greedy.recv(64) == b"< hi >"
        greedy.sendall(b"< open bus0 >")
        assert _recv_until(greedy, b"< ok >") == b"< ok >"
        sent = 0
        deadline = time.monotonic() + 60
        closed = False
        while not closed and time.monotonic() < deadline:
            try:
                greedy.sendall(b"< echo >" * 64)
                sent += 64
            except (ConnectionError, TimeoutError):
                closed = True
        greedy.close()
        assert closed, f"{sent} echoes sent, never disconnected"
        while h.hub.clients() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert h.hub.clients() == []
        assert h.hub.overflows == 1
        stats = h.hub.departed[-1]
        assert stats.overflowed
        assert stats.peak <= 64 + 64  # the queue never outgrew its bounds
        # the hub serves the next client as before
        s = _raw(h.port)
        s.sendall(b"< open bus0 >< echo >")
        assert _recv_until(s, b"< echo >") == b"< ok >< echo >"
        s.close()


def test_replies_to_a_reading_client_are_never_cut() -> None:
    """A client that pipelines many commands and reads the replies is served in full."""
    with HubThread(queue_limit=8, reply_limit=8) as h:
        s = _raw(h.port)
        s.sendall(b"< open bus0 >")
        assert _recv_until(s, b"< ok >") == b"< ok >"
        got = b""
        for _ in range(50):
            s.sendall(b"< echo >" * 200)
            got += _recv_until(s, b"< echo >" * 200)
        assert got.count(b"< echo >") == 50 * 200
        s.close()
        assert h.hub.overflows == 0


def test_non_loopback_addresses_are_named() -> None:
    assert exposed_addresses("0.0.0.0") == ["0.0.0.0"]
    assert exposed_addresses("192.0.2.7") == ["192.0.2.7"]
    assert exposed_addresses("::") == ["::"]
    for loopback in ("127.0.0.1", "127.0.0.2", "::1", "localhost"):
        assert exposed_addresses(loopback) == [], loopback
    with pytest.raises(ValueError, match="every address"):
        exposed_addresses("")
    with pytest.raises(ValueError, match="every address"):
        Hub("")


def test_serve_beyond_loopback_only_with_a_token(capsys: pytest.CaptureFixture[str],
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """Every address that is not loopback is refused in one line without a token (before:
    a warning, and the hub served anyone); with one (--token or CANOLA_TOKEN) it is
    served, and a note says the traffic is not encrypted. Loopback needs none."""
    served: list[tuple[str, str | None]] = []
    monkeypatch.setattr(hub_module, "serve",
                        lambda host, port, **kw: served.append((host, kw.get("token"))))
    monkeypatch.delenv("CANOLA_TOKEN", raising=False)
    for host in ("0.0.0.0", "::", "192.0.2.7"):
        code, out, err = cli(capsys, "bus", "serve", "--host", host)
        assert code == 2 and out == ""
        assert err.startswith(f"canola bus serve: error: --host {host} listens on {host}, "
                              "which is not loopback: set a token"), err
        assert len(err.splitlines()) == 1
        code, out, err = cli(capsys, "bus", "serve", "--host", host, "--token", TOKEN)
        assert code == 0 and out == ""
        assert err.startswith(f"canola bus: --host {host}: listening on {host}, not "
                              "loopback: clients must send the token"), err
    monkeypatch.setenv("CANOLA_TOKEN", TOKEN)
    assert cli(capsys, "bus", "serve", "--host", "0.0.0.0")[0] == 0
    code, _, err = cli(capsys, "bus", "serve", "--host", "0.0.0.0", "--token", "short")
    assert code == 2 and "--token must be 16..64 characters" in err
    monkeypatch.delenv("CANOLA_TOKEN")
    code, _, err = cli(capsys, "bus", "serve", "--host", "127.0.0.1")
    assert code == 0 and err == ""
    assert served == [("0.0.0.0", TOKEN), ("::", TOKEN), ("192.0.2.7", TOKEN),
                      ("0.0.0.0", TOKEN), ("127.0.0.1", None)]


@pytest.mark.slow
def test_empty_host_is_refused_in_one_line() -> None:
    proc = subprocess.run([sys.executable, "-m", "canola.cli", "bus", "serve", "--host", "",
                           "--port", "0"], capture_output=True, text=True, timeout=300,
                          check=False)
    assert proc.returncode == 2
    assert proc.stderr.splitlines() == [
        "canola bus serve: error: --host '' would listen on every address: give one "
        "(127.0.0.1: this machine only)"]
