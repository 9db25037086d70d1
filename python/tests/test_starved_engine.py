# SPDX-License-Identifier: Apache-2.0
"""A starved machine: frames that arrived count before a time-out is judged. The engine's
thread is held off (the test holds the link's lock, as a busy host deschedules it) while
an unrelated frame and then the frame the time-out waits for queue in python-can; once it
runs, the engine ingests both at their bus time before it polls the timers, so neither the
SDO server nor the SDO client times out on a frame that was on the bus in time."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from pathlib import Path

import can
import pytest

from canola import Device, Master

pytestmark = pytest.mark.realtime

INTEROP = Path(__file__).parent / "data" / "interop.eds"
NODE = 5
HELD_S = 0.4  # the engine held off: 4 time-outs of 100 ms


def _msg(can_id: int, data: bytes) -> can.Message:
    return can.Message(arbitration_id=can_id, data=data, is_extended_id=False)


def _answer(bus: can.BusABC, can_id: int) -> bytes:
    end = time.monotonic() + 10.0
    while time.monotonic() < end:
        msg = bus.recv(0.5)
        if msg is not None and msg.arbitration_id == can_id:
            return bytes(msg.data)
    raise AssertionError(f"no frame on 0x{can_id:03X} within 10 s")


def test_the_sdo_server_takes_the_segment_that_arrived_in_time(
        can_bus: Callable[[], can.BusABC]) -> None:
    device = Device(INTEROP, NODE, can_bus(), sdo_timeout_ms=100)
    client = can_bus()
    device.start()
    try:
        text = b"0123456789"
        size = len(text).to_bytes(4, "little")
        client.send(_msg(0x600 + NODE, bytes([0x21, 0x09, 0x20, 0]) + size))
        assert _answer(client, 0x580 + NODE)[0] == 0x60
        client.send(_msg(0x600 + NODE, bytes([0x00]) + text[:7]))
        assert _answer(client, 0x580 + NODE)[0] == 0x20
        with device._engine.link.lock:  # type: ignore[union-attr]  # the engine held off
            client.send(_msg(0x700 + 9, b"\x05"))  # another node's heartbeat comes first
            client.send(_msg(0x600 + NODE, bytes([0x19]) + text[7:] + bytes(4)))  # the last
            time.sleep(HELD_S)
        answer = _answer(client, 0x580 + NODE)
        assert answer[0] == 0x30, f"answer {answer.hex()}"  # failed before: abort 0x05040000
        assert device.od[0x2009, 0] == text.decode()
    finally:
        device.stop()


def test_the_sdo_client_takes_the_answer_that_arrived_in_time(
        can_bus: Callable[[], can.BusABC]) -> None:
    master = Master(can_bus(), node_id=1, sdo_timeout_ms=100)
    server = can_bus()
    master.start()
    grab, held = threading.Event(), threading.Event()
    result: list[object] = []

    def upload() -> None:
        try:
            result.append(master.sdo(NODE).upload(0x1018, 1))
        except Exception as exc:  # the test reports it
            result.append(exc)

    def serve() -> None:
        request = _answer(server, 0x600 + NODE)
        assert request[0] == 0x40
        grab.set()
        if held.wait(10.0):
            server.send(_msg(0x700 + 9, b"\x05"))  # another node's heartbeat comes first
            server.send(_msg(0x580 + NODE, bytes([0x43, 0x18, 0x10, 0x01, 0x2A, 0, 0, 0])))

    worker = threading.Thread(target=upload, daemon=True)
    answerer = threading.Thread(target=serve, daemon=True)
    try:
        answerer.start()
        worker.start()
        assert grab.wait(10.0)
        with master._engine.link.lock:  # type: ignore[union-attr]  # the engine held off
            held.set()
            time.sleep(HELD_S)
        worker.join(10.0)
        answerer.join(10.0)
    finally:
        master.stop()
    assert result == [b"\x2a\x00\x00\x00"]  # failed before: SdoTimeout
