# SPDX-License-Identifier: Apache-2.0
"""canola.Device and canola.Master on python-can buses: the bus thread, the lock, callbacks."""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Callable
from pathlib import Path

import can
import pytest
from conftest import SDO_TIMEOUT_MS, wait_until

from canola import Device, Error, Master

pytestmark = pytest.mark.realtime

INTEROP = Path(__file__).parent / "data" / "interop.eds"


def _threads() -> set[str]:
    return {t.name for t in threading.enumerate() if t.name.startswith("canola-")}


def test_threads_start_and_stop(can_bus: Callable[[], can.BusABC]) -> None:
    with (Device(INTEROP, 5, can_bus()) as device,
          Master(can_bus(), node_id=1, sdo_timeout_ms=SDO_TIMEOUT_MS) as master):
        assert {"canola-device-5", "canola-master-1"} <= _threads()
        assert master.sdo(5).read(0x1018, 4, "u32") == 0x12345678
        device.stop()
        assert "canola-device-5" not in _threads()
        with pytest.raises(Error, match="no response from node 5"):
            master.sdo(5).upload(0x1018, 4, timeout=0.2)
        device.start()  # resumes the thread
        assert master.sdo(5).read(0x1018, 4, "u32") == 0x12345678
    assert not _threads() & {"canola-device-5", "canola-master-1"}


def test_callbacks_run_outside_the_lock(can_bus: Callable[[], can.BusABC]) -> None:
    device = Device(INTEROP, 5, can_bus())
    master = Master(can_bus(), node_id=1, sdo_timeout_ms=SDO_TIMEOUT_MS)
    seen: list[object] = []

    def on_write(index: int, sub: int, value: object) -> None:
        # calls back into the node: it would deadlock if callbacks ran under the lock
        seen.append((index, sub, value, device.od[0x2006][0], device.nmt_state))
        device.od[0x2005][0] = 9
        seen.append(threading.current_thread().name)

    device.on_write(on_write)
    with device, master:
        master.sdo(5).write(0x2006, 0, "u16", 4321)
        assert wait_until(lambda: len(seen) == 2)
        assert seen[0] == (0x2006, 0, 4321, 4321, "PRE-OPERATIONAL")
        assert seen[1] == "canola-device-5"
        assert master.sdo(5).read(0x2005, 0, "u8") == 9


def test_blocking_call_from_own_callback_is_refused(can_bus: Callable[[], can.BusABC]) -> None:
    master = Master(can_bus(), node_id=1)
    device = Device(INTEROP, 5, can_bus())
    outcome: list[str] = []

    def on_boot(node: int) -> None:
        try:
            master.sdo(node).upload(0x1000, 0)
            outcome.append("returned")
        except Error as exc:
            outcome.append(str(exc))

    master.on_bootup(on_boot)
    with master, device:
        assert wait_until(lambda: len(outcome) == 1)
    assert "would wait for itself" in outcome[0]


def test_stop_during_a_transfer_ends_it(can_bus: Callable[[], can.BusABC]) -> None:
    master = Master(can_bus(), node_id=1, sdo_timeout_ms=60000)
    watch = can_bus()
    result: list[BaseException | bytes] = []

    def read() -> None:
        try:
            result.append(master.sdo(42).upload(0x1000, 0))
        except BaseException as exc:
            result.append(exc)

    with master:
        reader = threading.Thread(target=read)
        reader.start()
        # the request is on the bus: the transfer is under way (nobody answers node 42)
        while (msg := watch.recv(30)) is not None and msg.arbitration_id != 0x600 + 42:
            pass
        assert msg is not None
    reader.join(30)
    assert not reader.is_alive()
    assert isinstance(result[0], Error) and "stopped" in str(result[0])


# ---- several canola nodes on one python-can bus object: one engine


def test_one_thread_drives_every_node_of_a_bus(can_bus: Callable[[], can.BusABC]) -> None:
    before = set(threading.enumerate())
    shared = can_bus()
    master = Master(shared, node_id=1)
    first = Device(INTEROP, 5, shared)
    second = Device(INTEROP, 6, shared)
    with master, first, second:
        added = set(threading.enumerate()) - before
        assert [t.name for t in added] == ["canola-master-1+device-5+device-6"]
        # the request reaches the device of the same bus object, the answer the master
        assert master.sdo(5).read(0x1018, 4, "u32") == 0x12345678
        master.sdo(6).write(0x2006, 0, "u16", 606)
        assert second.od[0x2006][0] == 606 and first.od[0x2006][0] == 6
        other = Device(INTEROP, 7, can_bus())  # another bus object: a thread of its own
        with other:
            assert len(set(threading.enumerate()) - before) == 2
            assert master.sdo(7).read(0x1018, 4, "u32") == 0x12345678
        assert len(set(threading.enumerate()) - before) == 1
        first.stop()  # the others go on, on the same thread
        assert [t.name for t in set(threading.enumerate()) - before] == [
            "canola-master-1+device-6"]
        with pytest.raises(Error, match="no response from node 5"):
            master.sdo(5).upload(0x1018, 4, timeout=0.2)
        assert master.sdo(6).read(0x2006, 0, "u16") == 606
    assert wait_until(lambda: not set(threading.enumerate()) - before)


def _next(watch: can.BusABC, wanted: set[int]) -> tuple[int, bytes] | None:
    """The next frame ``watch`` receives with an identifier in ``wanted`` (heartbeats and
    the like skipped), None after 5 s without one."""
    while (msg := watch.recv(5)) is not None:
        if msg.arbitration_id in wanted:
            return msg.arbitration_id, bytes(msg.data)
    return None


def test_nodes_of_a_bus_reach_the_others_on_it(can_bus: Callable[[], can.BusABC]) -> None:
    shared, watch = can_bus(), can_bus()
    master = Master(shared, node_id=1)
    device = Device(INTEROP, 5, shared)
    boots: list[int] = []
    master.on_bootup(boots.append)
    with master:
        assert _next(watch, {0x701}) == (0x701, b"\x00")
        device.start()  # its boot-up: to the master at once, and to python-can
        assert wait_until(lambda: boots == [5])
        assert _next(watch, {0x705}) == (0x705, b"\x00")
        master.sdo(5).upload(0x1018, 4)
        assert _next(watch, {0x605, 0x585}) == (0x605, b"\x40\x18\x10\x04\0\0\0\0")
        assert _next(watch, {0x605, 0x585}) == (0x585, b"\x43\x18\x10\x04\x78\x56\x34\x12")
        watch.send(can.Message(arbitration_id=0x000, data=b"\x01\x05", is_extended_id=False))
        assert wait_until(lambda: device.nmt_state == "OPERATIONAL")  # from outside too
        device.stop()


def test_callbacks_of_a_shared_bus_run_in_order_outside_the_lock(
        can_bus: Callable[[], can.BusABC]) -> None:
    shared = can_bus()
    device = Device(INTEROP, 5, shared)
    master = Master(shared, node_id=1)
    seen: list[object] = []

    def on_write(index: int, sub: int, value: object) -> None:
        seen.append(value)
        device.od[0x2005][0] = int(str(value)) % 200  # calls back: no deadlock

    device.on_write(on_write)
    with device, master:
        for value in (1, 2, 3):
            master.sdo(5).write(0x2006, 0, "u16", value)
        assert wait_until(lambda: len(seen) == 3)
        assert seen == [1, 2, 3]
        assert master.sdo(5).read(0x2005, 0, "u8") == 3


def test_asyncio_on_a_shared_bus(can_bus: Callable[[], can.BusABC]) -> None:
    shared = can_bus()
    with Device(INTEROP, 5, shared) as device, Master(shared, node_id=1) as master:
        async def main() -> list[bytes]:
            await master.sdo(5).adownload(0x2006, 0, b"\x39\x05")
            return await asyncio.gather(*(master.sdo(5).aupload(0x1018, 4) for _ in range(20)))

        assert asyncio.run(main()) == [b"\x78\x56\x34\x12"] * 20
        assert device.od[0x2006][0] == 0x539


def test_a_node_observes_the_frames_it_sends(can_bus: Callable[[], can.BusABC]) -> None:
    """on_frame_sent on python-can, which does not hand a bus object its own frames: the
    device's frames only (not the master's on the same bus object), in order."""
    shared = can_bus()
    device = Device(INTEROP, 5, shared)
    master = Master(shared, node_id=1)
    sent: list[tuple[int, bytes]] = []
    device.on_frame_sent(lambda frame: sent.append((frame.can_id, frame.data)))
    with device, master:
        assert master.sdo(5).upload(0x1018, 4) == b"\x78\x56\x34\x12"
        device.emcy_raise(0x5000)
        assert wait_until(lambda: len(sent) == 3)
        assert sent == [(0x705, b"\x00"), (0x585, b"\x43\x18\x10\x04\x78\x56\x34\x12"),
                        (0x085, b"\x00\x50\x01\0\0\0\0\0")]
