# SPDX-License-Identifier: Apache-2.0
"""Program download (CiA 302-3), master side: :meth:`canola.Master.flash`.

    def shown(done, total): print(f"{done}/{total}")
    result = master.flash(5, image, progress=shown)   # FlashResult(bytes, ident, ...)

Over one SDO client channel the C core (``co_flash_start``) writes 0x1F51 = 0 (stop),
0x1F51 = 3 (clear, unless ``clear=False``), the image to 0x1F50 by SDO block transfer,
0x1F51 = 1 (start), then reads 0x1F56 (software identification) and, with ``ident``,
compares it. A failure raises :class:`FlashError` with the stage (stop, clear, data,
start, verify) and the SDO abort code.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from canola._c import check as _check
from canola._c import ffi, lib
from canola._waiting import Waiter
from canola.errors import ABORT_TEXT, Error

if TYPE_CHECKING:
    from canola._channels import SdoChannels

__all__ = ["FlashError", "FlashResult", "flash"]

Progress = Callable[[int, int], None]


@dataclass(frozen=True)
class FlashResult:
    """A download that went through: ``bytes`` acknowledged, ``ident`` the device's
    0x1F56 after the start."""

    node: int
    bytes: int
    ident: int


class FlashError(Error):
    """A download that failed: ``stage`` where (stop, clear, data, start, verify),
    ``abort`` the SDO abort code (0 for an identification that does not match:
    ``ident`` is what the device reported)."""

    def __init__(self, node: int, stage: str, abort: int, ident: int, done: int) -> None:
        self.node = node
        self.stage = stage
        self.abort = abort
        self.ident = ident
        self.bytes = done
        if abort:
            what = f"SDO abort 0x{abort:08X} ({ABORT_TEXT.get(abort, 'unknown abort code')})"
        else:
            what = f"the device reports software identification 0x{ident:08X}"
        super().__init__(f"program download to node {node} failed at {stage}: {what}")


class _Download:
    def __init__(self, waiter: Waiter, progress: Progress | None, total: int) -> None:
        self.waiter = waiter
        self.progress = progress
        self.total = total
        self.latest = 0  # acknowledged bytes, as the core or a sample last said
        self.reported = 0
        self.done = False
        self.stage = 0
        self.abort = 0
        self.ident = 0
        self.ident_ok = False
        self.bytes = 0


@ffi.def_extern()
def canola_py_flash_progress(ctx: Any, done: int, total: int) -> None:
    d: _Download = ffi.from_handle(ctx)
    del total
    d.latest = max(d.latest, int(done))


@ffi.def_extern()
def canola_py_flash_done(ctx: Any, result: Any) -> None:
    d: _Download = ffi.from_handle(ctx)
    d.stage = int(result.stage)
    d.abort = int(result.abort)
    d.ident = int(result.ident)
    d.ident_ok = bool(result.ident_ok)
    d.bytes = int(result.bytes)
    d.done = True


def flash(channels: SdoChannels, node: int, data: bytes, *, progress: Progress | None = None,
          program: int = 1, clear: bool = True, ident: int | None = None,
          timeout: float | None = None) -> FlashResult:
    """Download ``data`` as program ``program`` of ``node`` (see the module doc).
    ``progress(done, total)`` runs in the calling thread as the acknowledged bytes grow
    (sampled while waiting; the last call has ``done == total`` when the data went through).
    ``timeout`` (seconds, virtual on a SimBus) bounds the whole download; without it each
    SDO step is bounded by the master's SDO time-out."""
    if isinstance(node, bool) or not isinstance(node, int) or not 1 <= node <= 127:
        raise Error(f"node-ID {node!r} is outside 1..127")
    if node == channels.node_id:
        raise Error(f"node {node} is the master itself")
    if not isinstance(data, bytes | bytearray | memoryview):
        raise Error(f"the image is bytes, not {type(data).__name__}")
    image = bytes(data)
    if not 1 <= len(image) <= 0xFFFFFFFF:
        raise Error("the image is empty")
    if isinstance(program, bool) or not isinstance(program, int) or not 1 <= program <= 254:
        raise Error(f"program number {program!r} is outside 1..254")
    if ident is not None and not 0 <= ident <= 0xFFFFFFFF:
        raise Error(f"identification {ident!r} is outside 0..0xFFFFFFFF")
    if timeout is not None and timeout <= 0:
        raise Error(f"timeout must be positive, got {timeout}")
    engine = channels.engine
    waiter = Waiter(engine)
    waiter.check()
    busy = channels.lock_of(node)  # one transfer at a time to the node, Master.sdo's too
    if not busy.acquire(timeout=600):
        raise Error(f"SDO client of node {node} stays busy")
    try:
        d = _Download(waiter, progress, len(image))
        handle = ffi.new_handle(d)
        buf = ffi.new("uint8_t[]", len(image))
        ffi.memmove(buf, image, len(image))
        state = ffi.new("co_flash_t *")
        with engine.locked() as c_node:
            channel = channels.channel(c_node, node)
            request = ffi.new("co_flash_request_t *", {
                "channel": channel, "server": node, "program": program, "clear": clear,
                "check_ident": ident is not None, "ident": ident or 0, "data": buf,
                "len": len(image), "progress": lib.canola_py_flash_progress,
                "done": lib.canola_py_flash_done, "ctx": handle})
            err = int(lib.co_flash_start(state, c_node, request))
        if err == lib.CO_ERR_BUSY:
            raise Error("another program download is in progress")
        _check(err, f"program download to node {node}")

        def finished() -> bool:  # and report progress, in this thread, growing
            if not d.done:
                with engine.locked() as c_node:
                    if state.stage == lib.CO_FLASH_STAGE_DATA:
                        d.latest = max(d.latest, int(lib.co_sdo_client_progress(
                            c_node, channel)))
            if d.progress is not None and d.latest > d.reported:
                d.reported = min(d.latest, d.total)
                d.progress(d.reported, d.total)
            return d.done

        if not waiter.wait(finished, timeout):
            channels.abort(node)  # ends the step in progress: done runs with the abort
            waiter.wait(lambda: d.done, 5.0)
        if not d.done:  # pragma: no cover -- the core always completes on abort
            raise Error(f"program download to node {node} did not end")
        stage = ffi.string(lib.co_flash_stage_name(d.stage)).decode()
        if d.stage != lib.CO_FLASH_STAGE_DONE:
            raise FlashError(node, stage, d.abort, d.ident, d.bytes)
        return FlashResult(node, d.bytes, d.ident)
    finally:
        busy.release()
