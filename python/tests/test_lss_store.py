# SPDX-License-Identifier: Apache-2.0
"""An LSS store configuration (CiA 305) keeps the node-ID a device with ``store_dir`` was
given: through a reset node and a new start, whatever ``node_id`` says.

CiA 305: configure node-ID sets the pending node-ID, which becomes active at the next reset
communication; store configuration makes it the one the device starts with (power-on, and
reset node, which brings back the stored node-ID). A configured node-ID not stored is gone
after a reset node. In virtual time, on the simulated bus.
"""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from canola.core import SimBus
from canola.device import Device
from canola.master import Master

EDS = Path(__file__).parent / "data" / "cli_device.eds"


def _net(store: Path, node_id: int = 5) -> tuple[SimBus, Master, Device]:
    bus = SimBus()
    master = Master(bus, node_id=1)
    device = Device(EDS, node_id, bus, store_dir=store)
    master.start()
    device.start()
    bus.run_for(10_000)
    master.lss.timeout_ms = 20
    return bus, master, device


def _configure(master: Master, node_id: int, *, store: bool) -> None:
    master.lss.switch_global("configuration")
    master.lss.configure_node_id(node_id)
    if store:
        master.lss.store()
    master.lss.switch_global("waiting")


def test_stored_node_id_survives_reset_node_and_restart(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    bus, master, device = _net(tmp_path)
    _configure(master, 9, store=True)
    assert (tmp_path / "lss.params").read_text() == "canola-lss 1 node-id 9 bit-timing 255\n"
    master.nmt(5, "reset-node")
    bus.run_for(10_000)
    assert device.node_id == 9
    assert "709#00" in [line.split()[-1] for line in bus.trace]
    assert master.sdo(9).read(0x1018, 1, "u32") == 0xCA0

    # configured to 11 but not stored: a reset node brings back the stored 9
    _configure(master, 11, store=False)
    master.nmt(9, "reset-node")
    bus.run_for(10_000)
    assert device.node_id == 9

    # a new start with node_id 5: the stored node-ID wins, and it is said
    with caplog.at_level(logging.WARNING, logger="canola.device"):
        _, master2, device2 = _net(tmp_path, 5)
    assert device2.node_id == 9
    assert master2.sdo(9).read(0x1018, 1, "u32") == 0xCA0
    assert [r.getMessage() for r in caplog.records] == [
        f"device: node-ID 9, stored by LSS in {tmp_path / 'lss.params'} (not 5)"]


def test_damaged_lss_file_is_said_and_ignored(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    (tmp_path / "lss.params").write_text("canola-lss 1 node-id 300 bit-timing 255\n")
    with caplog.at_level(logging.WARNING, logger="canola.device"):
        _, master, device = _net(tmp_path, 5)
    assert device.node_id == 5
    assert master.sdo(5).read(0x1018, 1, "u32") == 0xCA0
    assert [r.getMessage() for r in caplog.records] == [
        f"device: {tmp_path / 'lss.params'}: damaged (not a line of canola-lss 1): ignored, "
        "node-ID 5"]
