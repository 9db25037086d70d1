# SPDX-License-Identifier: Apache-2.0
"""DOMAIN entries of any size on a :class:`canola.Device`: the value streams through Python.

    dev = canola.Device("drive.eds", 5, bus)
    blob = DomainStream(dev, 0x2200, 0)          # held in a bytearray, any size
    dev.start()
    ...                                          # a client writes 1 MiB by SDO block transfer
    blob.value                                   # -> the bytes written

A Device keeps each DOMAIN in a RAM buffer of ``domain_size`` bytes (default 4096). A
:class:`DomainStream` replaces that buffer for one entry: the core's read/write hooks hand
it every piece of an SDO transfer (segmented or block, either direction), so the size is
bounded only by ``max_size``. A download replaces :attr:`DomainStream.value` when its last
piece arrived (an aborted transfer changes nothing); uploads read the value as it is.
The device's ``on_write`` callbacks still run after a download, and ``dev.od.read`` /
``dev.od.get`` read the whole value.

Subclass and override :meth:`DomainStream.read` / :meth:`DomainStream.write` to send the
pieces elsewhere (a file, a flash chip). Both run inside the node (under its lock): they
must be quick and must not call the device's methods; ``write`` returns 0 or an SDO abort
code.
"""

from __future__ import annotations

import threading
from typing import Any

from canola._c import ffi, lib
from canola.device import Device
from canola.errors import Error, SdoAbort

__all__ = ["ABORT_GENERAL", "ABORT_TOO_LONG", "DomainStream"]

ABORT_GENERAL = 0x08000000
#: Data type does not match, length of service parameter too high.
ABORT_TOO_LONG = 0x06070012
_UNKNOWN = 0xFFFFFFFF


@ffi.def_extern()
def canola_py_stream_read(handle: Any, offset: int, buf: Any, cap: int, n: Any,  # noqa: PLR0917
                          total: Any) -> int:
    stream: DomainStream = ffi.from_handle(handle)
    try:
        data, size = stream.read(int(offset), int(cap))
    except SdoAbort as exc:
        return exc.code
    except Exception:  # a broken callback fails the transfer, not the node
        return ABORT_GENERAL
    data = data[:cap]
    ffi.memmove(buf, data, len(data))
    n[0] = len(data)
    total[0] = _UNKNOWN if size is None else size
    return 0


@ffi.def_extern()
def canola_py_stream_write(handle: Any, offset: int, data: Any, n: int,  # noqa: PLR0917
                           total: int, last: bool) -> int:
    stream: DomainStream = ffi.from_handle(handle)
    try:
        return int(stream.write(int(offset), bytes(ffi.buffer(data, n)),
                                None if total == _UNKNOWN else int(total), bool(last)))
    except Exception:
        return ABORT_GENERAL


class DomainStream:
    """DOMAIN entry (``index``, ``sub``) of ``device``, held in memory (at most ``max_size``
    bytes; larger downloads are refused with :data:`ABORT_TOO_LONG`). ``value``: the value
    at first. Create it before or after start. Raises Error when the entry is missing or not
    a DOMAIN."""

    def __init__(self, device: Device, index: int, sub: int = 0, *, value: bytes = b"",
                 max_size: int = 64 << 20) -> None:
        if not isinstance(device, Device):
            raise Error(f"a canola.Device is needed, not {type(device).__name__}")
        if not 0 <= index <= 0xFFFF or not 0 <= sub <= 0xFF:
            raise Error(f"no entry 0x{index:X} sub {sub}")
        if not 0 <= max_size <= 0xFFFFFFFE:
            raise Error(f"max_size {max_size!r} is outside 0..0xFFFFFFFE")
        self.index = index
        self.sub = sub
        self.max_size = max_size
        self._value = bytes(value)
        self._incoming = bytearray()
        self._lock = threading.Lock()
        self._handle = ffi.new_handle(self)
        raw = device.hook_entries(lambda entries, count: lib.canola_py_stream_new(
            entries, count, index, sub, self._handle), self)
        if raw == ffi.NULL:
            raise Error(f"the device's dictionary has no DOMAIN 0x{index:04X} sub {sub}")
        self._stream = ffi.gc(raw, lib.canola_py_stream_free)
        # dev.od reads an entry into a buffer of its recorded size: keep that the value's
        self._od = device.od
        self._sized()

    def _sized(self) -> None:
        self._od.reserve(self.index, self.sub, len(self._value))

    @property
    def value(self) -> bytes:
        """The value: what the last complete download wrote."""
        with self._lock:
            return self._value

    @value.setter
    def value(self, data: bytes) -> None:
        if len(data) > self.max_size:
            raise Error(f"{len(data)} bytes: more than max_size {self.max_size}")
        with self._lock:
            self._value = bytes(data)
            self._sized()

    # ---- what the network does (called inside the node)

    def read(self, offset: int, cap: int) -> tuple[bytes, int | None]:
        """Up to ``cap`` bytes of the value from ``offset``, and the whole size (None:
        unknown). Raise SdoAbort to refuse."""
        with self._lock:
            return self._value[offset:offset + cap], len(self._value)

    def write(self, offset: int, data: bytes, total: int | None, last: bool) -> int:
        """A piece of a new value at ``offset`` (``total``: the announced size, if any);
        the value changes when the ``last`` piece arrived. Returns 0 or an abort code."""
        if offset == 0:
            self._incoming = bytearray()
            if total is not None and total > self.max_size:
                return ABORT_TOO_LONG
        if offset != len(self._incoming):
            return ABORT_GENERAL
        if len(self._incoming) + len(data) > self.max_size:
            self._incoming = bytearray()
            return ABORT_TOO_LONG
        self._incoming += data
        if last:
            with self._lock:
                self._value = bytes(self._incoming)
                self._sized()
            self._incoming = bytearray()
        return 0
