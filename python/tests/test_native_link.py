# SPDX-License-Identifier: Apache-2.0
"""canola's C link (canola.bus.native.NativeBus, canola._native): the master and the device
each on a bus whose socket C owns, the frames crossing a real socket: a socketcand
connection to the hub, or SocketCAN on the interface the SocketCAN tier names
(CANOLA_VCAN). Its failure modes: the server going away mid-transfer, the bus closed
while a call waits, Ctrl-C, a callback that raises, a callback that calls back."""

from __future__ import annotations

import _thread
import logging
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import can
import pytest
from conftest import VCAN, wait_until

from canola import Device, Master
from canola.bus.hub import HubThread
from canola.bus.native import NativeBus
from canola.errors import BusLostError, Error

pytestmark = [pytest.mark.realtime, pytest.mark.vcan]  # the SocketCAN tier: on vcan0

INTEROP = Path(__file__).parent / "data" / "interop.eds"

#: A node-ID nobody answers on: a transfer to it waits until its time-out.
SILENT = 99


@pytest.fixture
def native() -> Iterator[tuple[Callable[[], NativeBus], HubThread | None]]:
    """A factory of C-link buses on one channel (the hub's, or CANOLA_VCAN), and the hub."""
    made: list[NativeBus] = []
    hub = None if VCAN else HubThread().start()

    def make() -> NativeBus:
        if VCAN:
            bus = NativeBus.socketcan(VCAN)
        else:
            assert hub is not None
            bus = NativeBus.socketcand(f"socketcand://127.0.0.1:{hub.port}/can0", timeout=10)
        made.append(bus)
        return bus

    try:
        yield make, hub
    finally:
        for bus in made:
            bus.shutdown()
        if hub is not None:
            hub.stop()


def test_master_and_device_on_c_links(native: tuple[Callable[[], NativeBus], None]) -> None:
    make, _ = native
    master_bus = make()
    with Master(master_bus, node_id=1) as master, Device(INTEROP, 5, make()) as device:
        sdo = master.sdo(5)
        assert sdo.read(0x1018, 4, "u32") == 0x12345678
        sdo.write(0x2006, 0, "u16", 606)
        assert device.od[0x2006][0] == 606
        name = sdo.upload(0x1008, 0)  # segmented
        assert name.rstrip(b"\0") == str(device.od[0x1008][0]).encode() and len(name) > 4
        assert sdo.upload(0x1008, 0, block=True) == name
        for _ in range(50):  # one after another: the waiting thread reads the answers
            assert sdo.read(0x1018, 4, "u32") == 0x12345678
        with pytest.raises(Error, match="no response from node 7"):
            master.sdo(7).upload(0x1018, 4, timeout=0.3)
    io = master_bus.io
    assert io.frames_in >= 55 and io.frames_out >= 55
    assert io.waiter_rounds > 0  # answers read by the waiting thread, in C


def test_frames_and_callbacks_reach_python(native: tuple[Callable[[], NativeBus], None],
                                           caplog: pytest.LogCaptureFixture) -> None:
    make, _ = native
    with Master(make(), node_id=1) as master:
        boots: list[int] = []
        refused: list[BaseException] = []
        frames: list[int] = []

        @master.on_bootup
        def calls_back(node: int) -> None:
            boots.append(node)
            try:  # the link's thread runs this: a blocking call would wait for itself
                master.sdo(node).read(0x1018, 4, "u32")
            except Error as exc:
                refused.append(exc)

        @master.on_bootup
        def raises(node: int) -> None:
            raise RuntimeError("a callback that raises")

        master.on_frame(lambda f: frames.append(f.can_id), 0x705)
        caplog.set_level(logging.ERROR, "canola")
        device_bus = make()
        with Device(INTEROP, 5, device_bus):
            assert wait_until(lambda: boots == [5] and len(refused) == 1 and frames, 30)
            assert "wait for itself" in str(refused[0])
            assert "a callback that raises" in caplog.text
            assert master.sdo(5).read(0x1018, 4, "u32") == 0x12345678  # still works
            assert frames[0] == 0x705


def _lost_while_waiting(bus: NativeBus, cut: Callable[[], object]) -> BaseException:
    """What an SDO upload to a silent node raised when ``cut()`` ran while it waited (it
    must end within a bound: a dead bus never hangs a call)."""
    raised: list[BaseException] = []
    with Master(bus, node_id=1) as master:
        def run() -> None:
            try:
                # only cut() ends it: neither the answer's time-out nor the whole one first
                master.sdo(SILENT).upload(0x1018, 1, timeout=120, answer_timeout=60)
            except BaseException as exc:  # what the call raised is the point
                raised.append(exc)

        thread = threading.Thread(target=run, daemon=True)
        thread.start()
        time.sleep(0.3)
        cut()
        thread.join(30)
        assert not thread.is_alive()
    assert len(raised) == 1
    return raised[0]


def test_the_server_going_away_mid_transfer(native: tuple[Callable[[], NativeBus],
                                                          HubThread | None]) -> None:
    make, hub = native
    if hub is None:
        pytest.skip("a SocketCAN interface cannot go away here")
    bus = make()
    raised = _lost_while_waiting(bus, hub.stop)
    assert isinstance(raised, BusLostError), raised
    assert bus.lost and bus.error()


def test_close_while_a_transfer_waits(native: tuple[Callable[[], NativeBus], None]) -> None:
    make, _ = native
    bus = make()
    raised = _lost_while_waiting(bus, bus.shutdown)
    assert isinstance(raised, BusLostError) and "closed" in str(raised), raised


def test_ctrl_c_while_a_transfer_waits(native: tuple[Callable[[], NativeBus], None]) -> None:
    make, _ = native
    with Master(make(), node_id=1) as master, Device(INTEROP, 5, make()):
        timer = threading.Timer(0.3, _thread.interrupt_main)
        timer.start()
        began = time.monotonic()
        with pytest.raises(KeyboardInterrupt):
            # only Ctrl-C ends it: neither the answer's time-out nor the whole one comes first
            master.sdo(SILENT).upload(0x1018, 1, timeout=120, answer_timeout=60)
        assert time.monotonic() - began < 60
        timer.join(10)
        # the channel was freed: the next transfer to the same server starts
        with pytest.raises(Error, match="no response"):
            master.sdo(SILENT).upload(0x1018, 1, timeout=0.3)
        assert master.sdo(5).read(0x1018, 4, "u32") == 0x12345678


def test_python_can_readers_see_the_frames(native: tuple[Callable[[], NativeBus],
                                                         None]) -> None:
    make, _ = native
    watch = make()
    with Device(INTEROP, 5, make()):
        seen = None
        end = time.monotonic() + 30
        while seen is None and time.monotonic() < end:
            msg = watch.recv(0.5)
            if msg is not None and msg.arbitration_id == 0x705:
                seen = msg
        assert seen is not None and bytes(seen.data) == b"\x00"  # the boot-up


def test_a_reader_that_does_not_wait_still_reads(native: tuple[Callable[[], NativeBus],
                                                               None]) -> None:
    """recv(0) on a bus object without nodes (no thread of its own reads it) takes what the
    bus holds: a trace drained with recv(0) sees every frame (canola demo's listener)."""
    make, _ = native
    watch, sender = make(), make()
    for i in range(20):
        sender.send(can.Message(arbitration_id=0x181, data=bytes([i]), is_extended_id=False))
    seen: list[int] = []
    end = time.monotonic() + 30
    while len(seen) < 20 and time.monotonic() < end:
        msg = watch.recv(0.0)
        if msg is None:
            time.sleep(0.01)
        elif msg.arbitration_id == 0x181:
            seen.append(msg.data[0])
    assert seen == list(range(20))
