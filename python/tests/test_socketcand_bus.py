# SPDX-License-Identifier: Apache-2.0
"""canola's socketcand client (canola.bus.open.open_bus of a socketcand:// URL) against a
scripted server: the stream read as a stream, whatever the TCP segments."""

from __future__ import annotations

import socket
import threading
from collections.abc import Callable, Iterator

import can
import pytest

from canola.bus.open import BusError, connection_lost, open_bus

Script = Callable[[socket.socket], None]


def _element(conn: socket.socket) -> str:
    """The next element the client sent (they are short: read up to its '>')."""
    text = b""
    while not text.endswith(b">"):
        byte = conn.recv(1)
        assert byte, f"closed after {text!r}"
        text += byte
    return text.decode("ascii").strip()


@pytest.fixture
def server() -> Iterator[Callable[[Script], str]]:
    """Serve one connection by a script in a thread: the URL to open."""
    threads: list[threading.Thread] = []
    listeners: list[socket.socket] = []

    def serve(script: Script) -> str:
        listener = socket.create_server(("127.0.0.1", 0))
        listeners.append(listener)

        def run() -> None:
            conn, _ = listener.accept()
            with conn:
                script(conn)

        threads.append(threading.Thread(target=run, daemon=True))
        threads[-1].start()
        return f"socketcand://127.0.0.1:{listener.getsockname()[1]}/net"

    yield serve
    for thread in threads:
        thread.join(10)
    for listener in listeners:
        listener.close()
    assert not any(t.is_alive() for t in threads)


def test_frames_in_the_segment_of_the_handshake_reply(server: Callable[[Script], str]
                                                      ) -> None:
    """A busy machine reads the rawmode '< ok >' late: the frames sent after it arrive in
    the same read (python-can's own client failed: "Expected '< ok >' got: '< ok >< frame
    701 ... 7F >'"). They are frames, and frames cut anywhere are joined."""
    sent: list[str] = []
    done = threading.Event()

    def script(conn: socket.socket) -> None:
        conn.sendall(b"< hi >")
        sent.append(_element(conn))
        conn.sendall(b"< ok >")
        sent.append(_element(conn))
        conn.sendall(b"< ok >< frame 701 1.000000 7F >< fra")
        sent.append(_element(conn))  # the client's send
        conn.sendall(b"me 00000181 2.500000 0102 >< rtr 7E5 3.000000 2 >")
        done.wait(10)  # then the server goes away

    bus = open_bus(url=server(script), native=False)
    try:
        first = bus.recv(10)
        assert first is not None
        assert (first.arbitration_id, bytes(first.data), first.timestamp) == (0x701, b"\x7f",
                                                                              1.0)
        bus.send(can.Message(arbitration_id=0x605, is_extended_id=False, data=b"\x40\x18"))
        second, third = bus.recv(10), bus.recv(10)
        assert second is not None and third is not None
        assert (second.arbitration_id, second.is_extended_id, bytes(second.data)) == (
            0x181, True, b"\x01\x02")
        assert (third.arbitration_id, third.is_remote_frame, third.dlc) == (0x7E5, True, 2)
        assert sent == ["< open net >", "< rawmode >", "< send 605 2 40 18 >"]
        assert not connection_lost(bus)
        done.set()
        assert bus.recv(10) is None  # the server closed: nothing more, at once
        assert connection_lost(bus)
    finally:
        done.set()
        bus.shutdown()


def test_refused_and_silent_servers(server: Callable[[Script], str]) -> None:
    def refuses(conn: socket.socket) -> None:
        conn.sendall(b"< hi >")
        _element(conn)
        conn.sendall(b"< error no such channel >")

    with pytest.raises(BusError, match=r"cannot open socketcand://.*/net: expected '< ok >', "
                                       r"got '< error no such channel >'"):
        open_bus(url=server(refuses), native=False)

    release = threading.Event()

    def silent(conn: socket.socket) -> None:
        release.wait(10)

    url = server(silent)
    try:
        with pytest.raises(BusError, match=r"cannot open .*: no '< hi >' from the server"):
            open_bus(url=url, timeout=0.5, native=False)
    finally:
        release.set()
