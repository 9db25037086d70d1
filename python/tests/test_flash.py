# SPDX-License-Identifier: Apache-2.0
"""Master.flash (CiA 302-3 program download) to a canola.Device with a ProgramSlot, on the
simulated bus and on python-can."""

from __future__ import annotations

import random
import zlib
from collections.abc import Callable

import can
import pytest
from managed import EDS, model

from canola import Device, Error, Master
from canola.core import SimBus
from canola.flash import FlashError
from canola.program import ABORT_HARDWARE, ProgramSlot


def _image(size: int) -> bytes:
    return random.Random(size).randbytes(size)


@pytest.fixture
def net() -> tuple[SimBus, Master, Device, ProgramSlot]:
    bus = SimBus(1_000_000)
    master = Master(bus, node_id=1)
    device = Device(model(), 5, bus)
    slot = ProgramSlot(device, ident=0x1111)
    master.start()
    device.start()
    bus.run_for(10_000)
    return bus, master, device, slot


def test_flash_with_progress(net: tuple[SimBus, Master, Device, ProgramSlot]) -> None:
    bus, master, _, slot = net
    image = _image(300 * 1024)
    assert slot.running and slot.ident == 0x1111
    seen: list[tuple[int, int]] = []
    start = bus.now_us
    result = master.flash(5, image, progress=lambda done, total: seen.append((done, total)))
    assert result.bytes == len(image)
    assert result.ident == zlib.crc32(image) == slot.ident
    assert slot.image == image
    assert slot.commands == ["stop", "clear", "start"]
    assert slot.running and slot.status == 0
    # progress: growing, many steps, ends at the whole image
    assert len(seen) > 100
    assert all(total == len(image) for _, total in seen)
    done = [d for d, _ in seen]
    assert done == sorted(done) and done[-1] == len(image) and done[0] < len(image) // 50
    assert bus.now_us - start > 2_000_000  # 300 KiB at 1 Mbit/s take seconds of bus time
    # 0x1F56/0x1F57 over SDO as any tool reads them
    assert master.sdo(5).read(0x1F56, 1, "u32") == zlib.crc32(image)
    assert master.sdo(5).read(0x1F57, 1, "u32") == 0
    assert master.sdo(5).read(0x1F51, 1, "u8") == 1


def test_flash_ident_check_and_options(net: tuple[SimBus, Master, Device, ProgramSlot]
                                       ) -> None:
    _, master, _, slot = net
    image = b"\x01\x02\x03" * 100
    assert master.flash(5, image, ident=zlib.crc32(image), clear=False).ident == slot.ident
    assert slot.commands == ["stop", "start"]
    with pytest.raises(FlashError, match="failed at verify: the device reports software "
                                         "identification") as info:
        master.flash(5, image, ident=0xDEADBEEF)
    assert (info.value.stage, info.value.abort) == ("verify", 0)
    assert info.value.ident == zlib.crc32(image)


def test_flash_refused(net: tuple[SimBus, Master, Device, ProgramSlot]) -> None:
    _, master, _, slot = net

    def broken(offset: int, data: bytes, total: int | None, last: bool) -> int:
        return ABORT_HARDWARE

    slot.write = broken  # type: ignore[method-assign]
    with pytest.raises(FlashError, match=r"at data: SDO abort 0x06060000") as info:
        master.flash(5, _image(5000))
    assert info.value.stage == "data" and info.value.abort == ABORT_HARDWARE
    assert slot.status >> 1 == 5  # write error
    assert not slot.running


def test_flash_errors(net: tuple[SimBus, Master, Device, ProgramSlot]) -> None:
    bus, master, _, _ = net
    plain = Device(EDS, 6, bus)
    for node, data, match in ((0, b"x", "outside 1..127"), (1, b"x", "master itself"),
                              (5, b"", "empty"), (5, "text", "bytes, not str")):
        with pytest.raises(Error, match=match):
            master.flash(node, data)  # type: ignore[arg-type]
    with pytest.raises(Error, match="program number"):
        master.flash(5, b"x", program=0)
    with pytest.raises(Error, match="timeout must be positive"):
        master.flash(5, b"x", timeout=0)
    with pytest.raises(FlashError, match="at stop: SDO abort 0x05040000"):
        master.flash(9, b"x")  # nobody there
    plain.start()
    with pytest.raises(FlashError, match="at stop: SDO abort 0x06090011"):
        master.flash(6, b"x", program=2)  # 0x1F51 has no sub-index 2
    with pytest.raises(Error, match="no 0x1F50/0x1F51 sub-index 2"):
        ProgramSlot(plain, program=2)
    with pytest.raises(FlashError, match="at data: SDO abort 0x05040000"):
        master.flash(5, _image(200_000), timeout=0.2)  # virtual seconds
    assert master.flash(5, b"ok").bytes == 2  # the device is usable after an abort


@pytest.mark.realtime
def test_flash_on_python_can(can_bus: Callable[[], can.BusABC]) -> None:
    master = Master(can_bus(), node_id=1, sdo_timeout_ms=5000)
    device = Device(model(), 5, can_bus())
    slot = ProgramSlot(device)
    image = _image(40 * 1024)
    seen: list[int] = []
    with master, device:
        result = master.flash(5, image, progress=lambda done, total: seen.append(done))
    assert result.ident == zlib.crc32(image) and slot.image == image
    # sampled while waiting (20 times a second): a few steps, growing, ending whole
    assert len(seen) >= 2 and seen == sorted(set(seen)) and seen[-1] == len(image)
