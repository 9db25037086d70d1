# SPDX-License-Identifier: Apache-2.0
"""A python-can bus whose socket canola owns in C (``port/python/py_io.c``): a SocketCAN
interface or a socketcand connection, for the buses :func:`canola.bus.open.open_bus`
opens by URL (``socketcan://IFACE``, ``socketcand://HOST:PORT/CHANNEL``).

The canola nodes on it (:class:`canola.Master`, :class:`canola.Device`) take the fast
path (:mod:`canola._native`): C reads and writes the socket with the GIL released and
no Python object per frame. Other python-can users of the same bus object (``recv``,
``send``, a ``can.Notifier``, ``canola bus dump``) see every frame read from the bus, as
on any python-can bus: C keeps the last 4096 for them (older ones are dropped when
nobody reads; ``dropped`` counts them). The frames the canola nodes send are not
received back, as on SocketCAN without loopback.

Threading: ``send`` and ``recv`` may be called from any thread; ``recv`` waits in C
without the GIL. ``shutdown`` closes the socket: a canola node's call waiting on it raises
:class:`canola.errors.BusLostError`; ``recv`` returns None at once once the bus failed or
was closed (``lost`` is then true, as on :class:`canola.bus.socketcand_bus.SocketcandBus`)."""

from __future__ import annotations

import threading
import time
import weakref
from typing import Any

import can

from canola._c import CData, ffi, lib
from canola._native import NativeLink

__all__ = ["NativeBus"]

_WHY = 256
_DONE, _FAILED = int(lib.CANOLA_PY_IO_DONE), int(lib.CANOLA_PY_IO_FAILED)
_EXT, _RTR = int(lib.CO_FRAME_EXT), int(lib.CO_FRAME_RTR)


class NativeBus(can.BusABC):
    """Open with :meth:`socketcan` or :meth:`socketcand`; raises OSError (no such
    interface, no server) with the C side's one-line reason."""

    @classmethod
    def socketcan(cls, ifname: str, **kwargs: Any) -> NativeBus:
        why = ffi.new("char[]", _WHY)
        io = lib.canola_py_io_socketcan(ifname.encode(), why, _WHY)
        if io == ffi.NULL:
            raise OSError(ffi.string(why).decode("utf-8", "replace"))
        return cls(io, ifname, f"SocketCAN {ifname} (canola's C link)", **kwargs)

    @classmethod
    def socketcand(cls, url: str, token: str | None = None, timeout: float = 3.0,
                   **kwargs: Any) -> NativeBus:
        why = ffi.new("char[]", _WHY)
        io = lib.canola_py_io_socketcand(url.encode(), (token or "").encode(),
                                         max(1, round(timeout * 1000)), why, _WHY)
        if io == ffi.NULL:
            raise OSError(ffi.string(why).decode("utf-8", "replace"))
        return cls(io, url.rsplit("/", 1)[-1], f"socketcand {url} (canola's C link)", **kwargs)

    def __init__(self, io: CData, channel: str, info: str, **kwargs: Any) -> None:
        self.io = io
        self._channel = channel
        self.channel_info = info
        self._link: NativeLink | None = None
        self._link_lock = threading.Lock()
        self._closed = False
        weakref.finalize(self, lib.canola_py_io_free, io)
        super().__init__(channel=channel, **kwargs)

    def native_link(self) -> NativeLink:
        """The link of the canola nodes on this bus (one, made on first use)."""
        with self._link_lock:
            if self._link is None:
                self._link = NativeLink(self, self.io)
            return self._link

    @property
    def lost(self) -> bool:
        """True once the bus failed or was closed."""
        return bool(self.io.failed)

    @property
    def dropped(self) -> int:
        """Frames dropped because no python-can reader took them in time."""
        return int(self.io.ring_dropped)

    def error(self) -> str:
        """Why the bus failed ("" while it works)."""
        return ffi.string(lib.canola_py_io_error(self.io)).decode("utf-8", "replace")

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        until = (1 << 63) if timeout is None else int((time.monotonic() + timeout) * 1e6)
        f, stamp = ffi.new("co_frame_t *"), ffi.new("uint64_t *")  # per call: any thread
        rc = int(lib.canola_py_io_recv(self.io, f, stamp, until))
        if rc != _DONE:  # FAILED: nothing more, at once (``lost`` says so, as SocketcandBus)
            return None, False
        rtr = bool(f.flags & _RTR)
        return can.Message(timestamp=int(stamp[0]) / 1e6, arbitration_id=int(f.id),
                           is_extended_id=bool(f.flags & _EXT), is_remote_frame=rtr,
                           dlc=int(f.len), data=b"" if rtr else bytes(f.data[0:f.len]),
                           channel=self._channel), False

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        if msg.is_fd or msg.is_error_frame or msg.dlc > 8:
            raise can.CanOperationError(f"{self.channel_info} carries classic CAN frames only")
        f = ffi.new("co_frame_t *")
        f.id = msg.arbitration_id
        f.flags = (_EXT if msg.is_extended_id else 0) | (_RTR if msg.is_remote_frame else 0)
        f.len = msg.dlc
        if not msg.is_remote_frame:
            ffi.memmove(f.data, bytes(msg.data), min(len(msg.data), 8))
        end = time.monotonic() + (timeout or 0.0)
        while True:
            err = int(lib.canola_py_io_send(self.io, f))
            if err == lib.CO_OK:
                return
            if err == lib.CO_ERR_STATE:
                raise can.CanOperationError(f"{self.channel_info}: {self.error()}")
            if err == lib.CO_ERR_ARG:
                raise can.CanOperationError(f"{self.channel_info} cannot carry {msg}")
            if time.monotonic() >= end:
                raise can.CanOperationError(f"{self.channel_info}: the bus takes nothing now")
            time.sleep(0.001)

    def shutdown(self) -> None:
        if not self._closed:
            self._closed = True
            lib.canola_py_io_close(self.io)
        super().shutdown()
