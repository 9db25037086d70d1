# SPDX-License-Identifier: Apache-2.0
"""canola's socketcand client: a python-can bus on a socketcand server (``canola bus serve``
or the daemon) in raw mode, for the buses :func:`canola.bus.open.open_bus` opens.

It reads the server's stream as a stream: the handshake's ``< ok >`` and the frames that
follow it may arrive in one TCP segment (a server sends frames as soon as the channel is
joined, and a busy machine runs the client late), and frames cut anywhere are joined.
python-can's own socketcand client compares each handshake reply with what one recv()
returned, so a frame that shares the reply's segment fails the connection (``Expected
'< ok >' got: '< ok >< frame ... >'``).
"""

from __future__ import annotations

import collections
import re
import select
import socket
import threading
import time
from typing import Any

import can

from canola.bus.socketcand import (
    Frame,
    ProtocolError,
    format_send,
    parse_server_element,
    split_elements,
)

__all__ = ["SocketcandBus"]

_READ = 4096

#: The element a server sends most: a data frame with an 11-bit identifier, matched whole
#: (what the general parser would accept of it, nothing more); anything else takes the
#: general path (canola.bus.socketcand), which also finds what is wrong.
_DATA_FRAME = re.compile(rb"[ \t\r\n]*< frame ([0-9A-Fa-f]{1,3}) ([0-9]{1,12}\.[0-9]{6}) "
                         rb"((?:[0-9A-Fa-f]{2}){0,8}) >")


class SocketcandBus(can.BusABC):
    """Connected, channel ``channel`` opened and in raw mode once constructed; every step of
    the connection bounded by ``timeout`` seconds. With a ``token``, ``< auth TOKEN >``
    goes first (canola's hub asks for it: :mod:`canola.access`). Raises OSError (no server
    to connect to) or can.CanError (no answer, a refusal, not the protocol)."""

    def __init__(self, host: str, port: int, channel: str, timeout: float = 3.0, *,
                 token: str | None = None, **kwargs: Any) -> None:
        self._channel = channel
        self._rest = b""
        self._frames: collections.deque[can.Message] = collections.deque()
        self._send_lock = threading.Lock()
        #: True once the server closed the connection (seen by a receive).
        self.lost = False
        self._sock = socket.create_connection((host, port), timeout=timeout)
        # one frame per element, each awaited by somebody: no coalescing delay (Nagle)
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        try:
            deadline = time.monotonic() + timeout
            self._expect("hi", deadline)
            if token:
                self._sock.sendall(f"< auth {token} >".encode("ascii", "replace"))
                self._expect("ok", deadline)
            self._sock.sendall(f"< open {channel} >".encode("ascii"))
            self._expect("ok", deadline)
            self._sock.sendall(b"< rawmode >")
            self._expect("ok", deadline)
            self._sock.settimeout(None)
        except BaseException:
            self._sock.close()
            raise
        self.channel_info = f"socketcand {channel} on {host}:{port}"
        super().__init__(channel=channel, **kwargs)

    # ---- the stream

    def _read(self, wait: float | None) -> list[str]:
        """The elements completed by what arrives within ``wait`` seconds (None: block);
        frames among them are queued, the rest returned."""
        ready, _, _ = select.select([self._sock], [], [], wait)
        if not ready:
            return []
        data = self._sock.recv(_READ)
        if not data:
            self.lost = True
            return []
        data = self._rest + data
        pos, frames, channel = 0, self._frames, self._channel
        while True:  # the common case without the general parser: ~5x less work
            m = _DATA_FRAME.match(data, pos)
            if m is None:
                break
            can_id = int(m[1], 16)
            if can_id > 0x7FF:
                break  # the general path says why
            payload = bytes.fromhex(m[3].decode())
            frames.append(can.Message(timestamp=float(m[2]), arbitration_id=can_id,
                                      is_extended_id=False, dlc=len(payload), data=payload,
                                      channel=channel, check=False))
            pos = m.end()
        if pos:
            data = data[pos:]
        try:
            elements, self._rest = split_elements(data)
            others = []
            for element in elements:
                _, frame, stamp = parse_server_element(element)
                if frame is None:
                    others.append(element)
                else:
                    self._frames.append(_message(frame, stamp, self._channel))
        except ProtocolError as exc:
            self._rest = b""
            raise can.CanOperationError(f"socketcand server sent {exc}") from None
        return others

    def _expect(self, verb: str, deadline: float) -> None:
        while not self.lost:
            left = deadline - time.monotonic()
            if left <= 0:
                raise can.CanInitializationError(f"no '< {verb} >' from the server")
            for element in self._read(left):
                if element.split()[1] != verb:
                    raise can.CanInitializationError(f"expected '< {verb} >', got {element!r}")
                verb = ""  # one reply consumed: later ones are out of turn
            if not verb:
                return
        raise can.CanInitializationError("the server closed the connection")

    # ---- python-can

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        if not self._frames and not self.lost:
            self._read(timeout)  # replies in raw mode (an echo, an error) are not frames
        return (self._frames.popleft() if self._frames else None), False

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        if msg.is_extended_id or msg.is_remote_frame or not 0 <= msg.arbitration_id <= 0x7FF \
                or len(msg.data) > 8:  # the rest, checked, by the general formatter
            frame = Frame(msg.arbitration_id, b"" if msg.is_remote_frame else bytes(msg.data),
                          extended=msg.is_extended_id, rtr=msg.is_remote_frame, dlc=msg.dlc)
            text = format_send(frame)
        else:  # what format_send writes for an 11-bit data frame
            data = bytes(msg.data)
            hexes = " " + data.hex(" ").upper() if data else ""
            text = f"< send {msg.arbitration_id:03X} {len(data)}{hexes} >"
        with self._send_lock:
            try:
                self._sock.sendall(text.encode("ascii"))
            except OSError as exc:
                raise can.CanOperationError(f"socketcand send failed: {exc}") from exc

    def shutdown(self) -> None:
        super().shutdown()
        self._sock.close()


def _message(frame: Frame, stamp: float, channel: str) -> can.Message:
    return can.Message(timestamp=stamp, arbitration_id=frame.can_id,
                       is_extended_id=frame.extended, is_remote_frame=frame.rtr,
                       dlc=frame.dlc if frame.rtr else len(frame.data),
                       data=None if frame.rtr else frame.data, channel=channel)
