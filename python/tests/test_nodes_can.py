"""canola.Device and canola.Master on python-can buses: the bus thread, the lock, callbacks."""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path

import can
import pytest
from conftest import wait_until

from canola import Device, Error, Master

pytestmark = pytest.mark.realtime

INTEROP = Path(__file__).parent / "data" / "interop.eds"


def _threads() -> set[str]:
    return {t.name for t in threading.enumerate() if t.name.startswith("canola-")}


def test_threads_start_and_stop(can_bus: Callable[[], can.BusABC]) -> None:
    with Device(INTEROP, 5, can_bus()) as device, Master(can_bus(), node_id=1) as master:
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
    master = Master(can_bus(), node_id=1)
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
