# SPDX-License-Identifier: Apache-2.0
"""A select whose answer the master never sees (lost, or later than its time-out) may have
switched the device to configuration all the same: inquire and set_node_id switch every
device back to waiting whatever happened, so no device is left in configuration."""

from __future__ import annotations

import threading
from collections.abc import Callable

import can
import pytest

from canola import Master
from canola.errors import Error
from canola.lss import LssAddress

pytestmark = pytest.mark.realtime

WAITING = bytes([0x04, 0x00]) + bytes(6)  # switch state global: waiting (CiA 305)


@pytest.mark.parametrize("call", ["inquire", "set_node_id"])
def test_a_lost_select_answer_leaves_no_device_in_configuration(
        can_bus: Callable[[], can.BusABC], call: str) -> None:
    device = can_bus()  # a device that switches but whose answer is lost: it never answers
    seen: list[bytes] = []
    stop = threading.Event()

    def listen() -> None:
        while not stop.is_set():
            msg = device.recv(0.05)
            if msg is not None and msg.arbitration_id == 0x7E5:
                seen.append(bytes(msg.data))

    thread = threading.Thread(target=listen, daemon=True)
    thread.start()
    master = Master(can_bus(), node_id=1)
    master.start()
    try:
        lss = master.lss
        address = LssAddress(1, 2, 3, 4)
        with pytest.raises(Error, match="no device with address"):
            if call == "inquire":
                lss.inquire(address)
            else:
                lss.set_node_id(address, 9)
    finally:
        master.stop()
        stop.set()
        thread.join(5.0)
    selects = [i for i, data in enumerate(seen) if data[0] in (0x40, 0x41, 0x42, 0x43)]
    assert len(selects) == 4  # the select's four frames went out
    assert WAITING in seen[selects[-1] + 1:]  # failed before: nothing after the select
