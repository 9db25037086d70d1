# SPDX-License-Identifier: Apache-2.0
"""Stored parameter files (``store_dir``) that are damaged: refused whole, and said so.

A file that fails any check (a flipped bit, a cut, random bytes, a FIFO in its place) is
ignored as a whole: the group starts with its defaults, the device sends EMCY 0xFF11
(communication) or 0xFF12 (application) after its boot-up, :meth:`Device.on_store_rejected`
hears why (or, with no callback, a warning is logged), and ``canola device --store`` prints
one line. The format itself is pinned in tests/test_storage.c and tests/test_file_storage.c.
"""

from __future__ import annotations

import logging
import os
import random
import subprocess
import sys
from pathlib import Path

import pytest
from bounded import first_line

from canola.bus.hub import HubThread
from canola.core import SimBus
from canola.device import Device, StoreRejectedEvent

EDS = Path(__file__).parent / "data" / "cli_device.eds"
SAVE = 0x65766173  # "save"


def _saved(store: Path) -> None:
    """Both files saved with 0x1017 = 777 and 0x2000 = 0x5A5A5A5A."""
    bus = SimBus()
    dev = Device(EDS, 5, bus, store_dir=store)
    dev.start()
    dev.od[0x1017][0] = 777
    dev.od[0x2000][0] = 0x5A5A5A5A
    dev.od[0x1010][1] = SAVE
    assert {p.name for p in store.iterdir()} == {"comm.params", "app.params"}


def _start(store: Path) -> tuple[SimBus, Device, list[StoreRejectedEvent]]:
    bus = SimBus()
    dev = Device(EDS, 5, bus, store_dir=store)
    events: list[StoreRejectedEvent] = []
    dev.on_store_rejected(events.append)
    dev.start()
    bus.run_for(10_000)
    return bus, dev, events


def _flip_777(path: Path) -> None:
    data = bytearray(path.read_bytes())
    at = data.index(bytes([0x17, 0x10, 0x00, 2, 0x09, 0x03]))  # 0x1017 = 777
    data[at + 5] ^= 0x01  # 777 -> 521
    path.write_bytes(bytes(data))


def test_intact_files_load_without_a_word(tmp_path: Path) -> None:
    _saved(tmp_path)
    _, dev, events = _start(tmp_path)
    assert dev.od[0x1017][0] == 777 and dev.od[0x2000][0] == 0x5A5A5A5A
    assert events == []
    assert not dev.emcy_active(0xFF11)


def test_flipped_bit_is_refused_and_reported(tmp_path: Path) -> None:
    _saved(tmp_path)
    _flip_777(tmp_path / "comm.params")
    bus, dev, events = _start(tmp_path)
    assert dev.od[0x1017][0] == 100  # the EDS default, not 521
    assert dev.od[0x2000][0] == 0x5A5A5A5A  # the other file is intact
    assert events == [StoreRejectedEvent("communication", "comm.params", "CRC mismatch",
                                         0xFF11)]
    assert dev.emcy_active(0xFF11)
    emcy = [line for line in bus.trace if " 085#" in line]
    assert emcy and emcy[0].endswith("085#11FF810400000000"), emcy  # fault 4: CRC
    # a save of the group ends the error; the next start is quiet
    dev.od[0x1010][1] = SAVE
    assert not dev.emcy_active(0xFF11)
    assert _start(tmp_path)[2] == []


@pytest.mark.parametrize("damage", ["truncated", "random", "empty", "fifo"])
def test_damaged_files_are_refused_whole(tmp_path: Path, damage: str) -> None:
    _saved(tmp_path)
    app = tmp_path / "app.params"
    data = app.read_bytes()
    if damage == "truncated":
        app.write_bytes(data[:-1])
    elif damage == "random":
        app.write_bytes(random.Random(18).randbytes(len(data)))
    elif damage == "empty":
        app.write_bytes(b"")
    else:
        app.unlink()
        os.mkfifo(app)
    _, dev, events = _start(tmp_path)
    assert dev.od[0x2000][0] == 0x11111111  # the EDS default
    assert dev.od[0x1017][0] == 777
    assert [(e.group, e.code) for e in events] == [("application", 0xFF12)]
    assert dev.emcy_active(0xFF12)


def test_without_a_callback_a_warning_is_logged(tmp_path: Path,
                                                caplog: pytest.LogCaptureFixture) -> None:
    _saved(tmp_path)
    _flip_777(tmp_path / "comm.params")
    bus = SimBus()
    dev = Device(EDS, 5, bus, store_dir=tmp_path)
    with caplog.at_level(logging.WARNING, logger="canola.node"):
        dev.start()
        bus.run_for(1000)
    assert [r.getMessage() for r in caplog.records] == [
        "device 5: stored communication parameters (comm.params) refused: CRC mismatch; "
        "defaults in use (EMCY 0xFF11)"]


@pytest.mark.slow
@pytest.mark.realtime
def test_device_command_says_so(tmp_path: Path) -> None:
    _saved(tmp_path)
    _flip_777(tmp_path / "comm.params")
    with HubThread() as hub:
        proc = subprocess.Popen(
            [sys.executable, "-m", "canola.cli", "device", "--eds", str(EDS), "--node-id", "5",
             "--store", str(tmp_path), "--bus", f"socketcand://127.0.0.1:{hub.port}/store"],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        try:
            line = first_line(proc.stderr, "canola device", 120)  # the first thing it says
        finally:
            proc.terminate()
            proc.wait(20)
    assert line.rstrip("\n") == (
        f"canola device: node 5: {tmp_path / 'comm.params'}: CRC mismatch; ignored, "
        "communication parameters start with their defaults (EMCY 0xFF11)")

