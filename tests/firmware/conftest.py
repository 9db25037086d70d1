# SPDX-License-Identifier: Apache-2.0
"""The firmware stage (make test-firmware): each QEMU example image booted once per test
class, on the software bus (examples/firmware/qemu_rig.py). The images come from
``make firmware`` (build-fw/BOARD/firmware.elf); QEMU's output goes to build-fw/BOARD/qemu.log."""

from __future__ import annotations

import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BUILD = ROOT / "build-fw"
sys.path.insert(0, str(ROOT / "examples" / "firmware"))

from qemu_rig import Rig  # noqa: E402 -- the example's folder is not a package


@pytest.fixture(scope="class")
def rig(request: pytest.FixtureRequest) -> Iterator[Rig]:
    board = request.cls.board
    elf = BUILD / board / "firmware.elf"
    if not elf.is_file():
        pytest.fail(f"no image at {elf}: make firmware builds it")
    with open(BUILD / board / "qemu.log", "w") as log, Rig(board, elf, log=log) as running:
        yield running
