# SPDX-License-Identifier: Apache-2.0
"""Who ended an SDO transfer: a server's abort 0x05040000 is the server's (SdoAbort, sent
by the node, after how long), never reported as the master's own time-out (SdoTimeout),
which a silent server gets."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator

import can
import pytest

from canola import Master, SdoAbort, SdoTimeout

pytestmark = pytest.mark.realtime

SERVER = 5


def _abort(code: int) -> bytes:
    return bytes([0x80, 0x18, 0x10, 0x01]) + code.to_bytes(4, "little")


@pytest.fixture
def aborting_server(can_bus: Callable[[], can.BusABC]) -> Iterator[tuple[Master, list[float]]]:
    """A master, and a server (raw python-can) that answers every request to node SERVER
    with abort 0x05040000 after 0.2 s; the times it answered at."""
    server = can_bus()
    stop = threading.Event()
    answered: list[float] = []

    def serve() -> None:
        while not stop.is_set():
            msg = server.recv(0.05)
            if msg is not None and msg.arbitration_id == 0x600 + SERVER:
                time.sleep(0.2)
                server.send(can.Message(arbitration_id=0x580 + SERVER, data=_abort(0x05040000),
                                        is_extended_id=False))
                answered.append(time.monotonic())

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    master = Master(can_bus(), node_id=1, sdo_timeout_ms=10_000)
    master.start()
    try:
        yield master, answered
    finally:
        master.stop()
        stop.set()
        thread.join(5.0)


def test_a_servers_abort_0x05040000_is_the_servers(
        aborting_server: tuple[Master, list[float]]) -> None:
    master, answered = aborting_server
    began = time.monotonic()
    with pytest.raises(SdoAbort) as exc:
        master.sdo(SERVER).upload(0x1018, 1)
    assert not isinstance(exc.value, SdoTimeout)  # failed before: reported as a time-out
    assert exc.value.code == 0x05040000
    assert exc.value.by_server is True
    assert exc.value.node == SERVER
    assert answered and exc.value.after_s is not None
    assert 0.15 <= exc.value.after_s <= time.monotonic() - began + 0.01
    assert "sent by node 5 after" in str(exc.value)


def test_a_silent_server_is_the_masters_time_out(can_bus: Callable[[], can.BusABC]) -> None:
    master = Master(can_bus(), node_id=1, sdo_timeout_ms=300)
    master.start()
    try:
        began = time.monotonic()
        with pytest.raises(SdoTimeout) as exc:
            master.sdo(SERVER).upload(0x1018, 1)
        took = time.monotonic() - began
    finally:
        master.stop()
    assert exc.value.by_server is False and exc.value.node == SERVER
    assert exc.value.after_s is not None and 0.3 <= exc.value.after_s <= took + 0.01
    assert str(exc.value).startswith("no response from node 5 (SDO time-out 300 ms, after ")



def test_a_callback_run_while_waiting_cannot_wait_for_itself(
        can_bus: Callable[[], can.BusABC]) -> None:
    """The thread that waits for an answer runs the callbacks of what it receives: one that
    makes a blocking call to the same node is refused at once (it would wait for the
    transfer it runs inside), one to another node works."""
    master = Master(can_bus(), node_id=1, sdo_timeout_ms=300)
    other = can_bus()
    outcome: list[str] = []

    @master.on_frame
    def nested(frame: object) -> None:
        del frame
        try:
            master.sdo(SERVER).upload(0x1018, 1)
        except Exception as exc:  # the test reports it
            outcome.append(str(exc))

    master.start()
    try:
        request_seen = threading.Event()

        def poke() -> None:  # a frame arrives while the master waits for node SERVER
            end = time.monotonic() + 10.0
            while time.monotonic() < end and not request_seen.is_set():
                msg = other.recv(0.05)
                if msg is not None and msg.arbitration_id == 0x600 + SERVER:
                    request_seen.set()
                    other.send(can.Message(arbitration_id=0x181, data=b"\x01",
                                           is_extended_id=False))
        thread = threading.Thread(target=poke, daemon=True)
        thread.start()
        with pytest.raises(SdoTimeout):
            master.sdo(SERVER).upload(0x1018, 1)
        thread.join(10.0)
    finally:
        master.stop()
    assert outcome and "would wait for itself" in outcome[0]
