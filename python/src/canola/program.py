# SPDX-License-Identifier: Apache-2.0
"""Program download (CiA 302-3), device side: a :class:`canola.Device` that takes a new
program over the network.

    dev = canola.Device("drive.eds", 5, bus)      # the EDS has 0x1F50, 0x1F51, 0x1F56,
    slot = ProgramSlot(dev, on_image=flash_it)    # 0x1F57 (sub-index 1 = program 1)
    dev.start()

The C core runs the objects (``co_program_*``): 0x1F50 takes the image in pieces (SDO
segmented or block, any size: it is streamed, not held by the dictionary), 0x1F51 stops,
starts, resets and clears the program, 0x1F56 reads the software identification, 0x1F57
the flash status. :class:`ProgramSlot` collects the pieces in memory; when the last one
arrives, ``on_image(image)`` runs and its return value (or, if None, the image's CRC-32)
becomes the identification. Subclass and override :meth:`ProgramSlot.write` /
:meth:`ProgramSlot.control` to send the pieces elsewhere. Both run inside the node (under
its lock): they must be quick and must not call the device's methods; return 0 or an SDO
abort code.
"""

from __future__ import annotations

import zlib
from collections.abc import Callable
from typing import Any

from canola._c import ffi, lib
from canola.device import Device
from canola.errors import Error

__all__ = ["ABORT_GENERAL", "ABORT_HARDWARE", "ProgramSlot"]

ABORT_GENERAL = 0x08000000
ABORT_HARDWARE = 0x06060000

_COMMANDS = {0: "stop", 1: "start", 2: "reset", 3: "clear"}


@ffi.def_extern()
def canola_py_prog_write(ctx: Any, offset: int, data: Any, n: int, total: int,  # noqa: PLR0917
                         last: bool) -> int:
    slot: ProgramSlot = ffi.from_handle(ctx)
    try:
        return int(slot.write(int(offset), bytes(ffi.buffer(data, n)),
                              None if total == 0xFFFFFFFF else int(total), bool(last)))
    except Exception:  # a broken callback refuses the piece
        return ABORT_GENERAL


@ffi.def_extern()
def canola_py_prog_control(ctx: Any, command: int) -> int:
    slot: ProgramSlot = ffi.from_handle(ctx)
    try:
        return int(slot.control(int(command)))
    except Exception:
        return ABORT_GENERAL


class ProgramSlot:
    """Program ``program`` (sub-index of 0x1F50..0x1F57) of ``device``: ``running`` at
    power-on with identification ``ident``. Create it before or after start. Raises
    Error when the device's dictionary lacks 0x1F50/0x1F51 with that sub-index.
    ``max_size`` bounds the image held in memory (larger ones are refused)."""

    def __init__(self, device: Device, *, program: int = 1, running: bool = True,
                 ident: int = 0, on_image: Callable[[bytes], int | None] | None = None,
                 max_size: int = 64 << 20) -> None:
        if not isinstance(device, Device):
            raise Error(f"a canola.Device is needed, not {type(device).__name__}")
        if isinstance(program, bool) or not isinstance(program, int) or not 1 <= program <= 254:
            raise Error(f"program number {program!r} is outside 1..254")
        if not 0 <= ident <= 0xFFFFFFFF:
            raise Error(f"identification {ident!r} is outside 0..0xFFFFFFFF")
        self.program = program
        self.on_image = on_image
        self.max_size = max_size
        self.image: bytes | None = None  # the last image received whole
        self.commands: list[str] = []  # 0x1F51 commands, as names, in order
        self._buf = bytearray()
        self._handle = ffi.new_handle(self)
        raw = device.hook_entries(lambda entries, count: lib.canola_py_prog_new(
            entries, count, program, running, ident, self._handle), self)
        if raw == ffi.NULL:
            raise Error(f"the device's dictionary has no 0x1F50/0x1F51 sub-index {program}")
        self._prog = ffi.gc(raw, lib.canola_py_prog_free)

    # ---- what the network does (called inside the node)

    def write(self, offset: int, data: bytes, total: int | None, last: bool) -> int:
        """A piece of the image at ``offset`` (``total``: the announced size, if any)."""
        if offset == 0:
            self._buf = bytearray()
        if offset != len(self._buf) or len(self._buf) + len(data) > self.max_size:
            return ABORT_GENERAL
        self._buf += data
        if last:
            self.image = bytes(self._buf)
            self._buf = bytearray()
            ident = self.on_image(self.image) if self.on_image is not None else None
            lib.canola_py_prog_set_ident(self._prog,
                                         zlib.crc32(self.image) if ident is None else ident)
        return 0

    def control(self, command: int) -> int:
        """A 0x1F51 command: 0 stop, 1 start, 2 reset, 3 clear (checked by the core)."""
        self.commands.append(_COMMANDS.get(command, str(command)))
        if command == 3:
            self.image = None
        return 0

    # ---- state

    @property
    def ident(self) -> int:
        """0x1F56: the software identification."""
        return int(lib.canola_py_prog_ident(self._prog))

    @property
    def running(self) -> bool:
        """0x1F51 as read: the program runs."""
        return int(lib.canola_py_prog_state(self._prog)) == 1

    @property
    def status(self) -> int:
        """0x1F57: bit 0 download in progress, bits 1..7 status (0 ok, 1 no program,
        5 write error)."""
        return int(lib.canola_py_prog_status(self._prog))
