# SPDX-License-Identifier: Apache-2.0
"""The socketcand text protocol: splitting a byte stream into elements, parsing and formatting.

Pure functions, no I/O: the hub (:mod:`canola.bus.hub`) and the fuzz target use them. The subset
spoken here is what python-can's ``socketcand`` interface and canola's C client need:

- server greeting ``< hi >``; client ``< auth TOKEN >`` (canola's hub, where it asks for
  one: :mod:`canola.access`), server ``< ok >``; client ``< open CHANNEL >`` (1..16 characters of
  ``A-Z a-z 0-9 _ . -``), server ``< ok >``; ``< rawmode >`` / ``< bcmmode >``, server ``< ok >``;
  ``< echo >`` answered by itself.
- client ``< send ID LEN B0 B1 ... >``: ID hex (8 hex digits = 29-bit identifier, otherwise
  11-bit and at most 0x7FF), LEN 0..8, then exactly LEN bytes in hex (1 or 2 digits each);
  ``< sendrtr ID LEN >`` a remote request.
- server ``< frame ID SECS.USECS DATA >``: ID as 3 (11-bit) or 8 (29-bit) upper-case hex
  digits, DATA the bytes as one run of upper-case hex (nothing between the two spaces when
  there are none); ``< rtr ID SECS.USECS LEN >`` a remote request; ``< error TEXT >``.

Everything else is a :class:`ProtocolError` whose message is one line.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = [
    "MAX_ELEMENT",
    "Command",
    "Frame",
    "ProtocolError",
    "format_error",
    "format_frame",
    "format_send",
    "parse_command",
    "parse_server_element",
    "split_elements",
]

#: Longest element accepted (the longest legal one, an extended send with 8 bytes, is 43).
MAX_ELEMENT = 128

_CHANNEL = re.compile(r"[A-Za-z0-9_.\-]{1,16}")
_HEX = re.compile(r"[0-9A-Fa-f]+")
_TIME = re.compile(r"[0-9]{1,12}\.[0-9]{6}")


class ProtocolError(ValueError):
    """Input that is not the socketcand protocol (one-line message)."""


@dataclass(frozen=True)
class Frame:
    """One classic CAN frame. ``dlc`` is the data length of a remote request (data empty)."""

    can_id: int
    data: bytes = b""
    extended: bool = False
    rtr: bool = False
    dlc: int = -1

    def __post_init__(self) -> None:
        limit = 0x1FFFFFFF if self.extended else 0x7FF
        if not 0 <= self.can_id <= limit:
            raise ProtocolError(f"CAN identifier 0x{self.can_id:X} out of range")
        if len(self.data) > 8:
            raise ProtocolError(f"{len(self.data)} data bytes (at most 8)")
        if self.rtr and self.data:
            raise ProtocolError("a remote request carries no data")
        if self.dlc == -1:
            object.__setattr__(self, "dlc", len(self.data))
        if not 0 <= self.dlc <= 8 or (not self.rtr and self.dlc != len(self.data)):
            raise ProtocolError(f"length {self.dlc} does not fit the frame")


@dataclass(frozen=True)
class Command:
    """One parsed client element: ``verb`` and, for send/sendrtr, the frame; for open the
    channel; for auth the token."""

    verb: str
    channel: str = ""
    frame: Frame | None = None
    token: str = ""


def split_elements(buffer: bytes) -> tuple[list[str], bytes]:
    """Cut the complete ``< ... >`` elements off the front of ``buffer``.

    Returns the elements (text between and including the brackets, outer whitespace removed)
    and the unconsumed rest (an element not yet complete). Whitespace between elements is
    skipped. Raises :class:`ProtocolError` for anything else between elements, non-ASCII
    bytes, a ``<`` inside an element, or an element (or an incomplete rest) longer than
    :data:`MAX_ELEMENT`.
    """
    elements: list[str] = []
    pos = 0
    n = len(buffer)
    while True:
        while pos < n and buffer[pos] in b" \t\r\n":
            pos += 1
        if pos >= n:
            return elements, b""
        if buffer[pos] != 0x3C:  # '<'
            raise ProtocolError(f"expected '<', got {bytes(buffer[pos:pos + 1])!r}")
        end = buffer.find(b">", pos)
        inner_lt = buffer.find(b"<", pos + 1, end if end >= 0 else n)
        if inner_lt >= 0:
            raise ProtocolError("'<' inside an element")
        if end < 0:
            if n - pos > MAX_ELEMENT:
                raise ProtocolError(f"element longer than {MAX_ELEMENT} characters")
            return elements, bytes(buffer[pos:])
        if end + 1 - pos > MAX_ELEMENT:
            raise ProtocolError(f"element longer than {MAX_ELEMENT} characters")
        raw = bytes(buffer[pos:end + 1])
        if any((b < 0x20 and b != 0x09) or b > 0x7E for b in raw):
            raise ProtocolError("control or non-ASCII character in an element")
        elements.append(raw.decode("ascii"))
        pos = end + 1


def _words(element: str) -> list[str]:
    if not (element.startswith("<") and element.endswith(">")):
        raise ProtocolError(f"not an element: {element[:40]!r}")
    words = element[1:-1].split()
    if not words:
        raise ProtocolError("empty element")
    return words


def _hex(word: str, what: str) -> int:
    if not _HEX.fullmatch(word):
        raise ProtocolError(f"{what} {word[:20]!r} is not hexadecimal")
    return int(word, 16)


def _frame_id(word: str) -> tuple[int, bool]:
    value = _hex(word, "CAN identifier")
    extended = len(word) == 8
    if not extended and len(word) > 3:
        raise ProtocolError(f"CAN identifier {word!r}: 1..3 hex digits (11-bit) or 8 (29-bit)")
    if not extended and value > 0x7FF:
        raise ProtocolError(f"CAN identifier {word!r} out of the 11-bit range")
    if extended and value > 0x1FFFFFFF:
        raise ProtocolError(f"CAN identifier {word!r} out of the 29-bit range")
    return value, extended


def _length(word: str) -> int:
    if not word.isascii() or not word.isdigit() or len(word) > 2:
        raise ProtocolError(f"length {word[:20]!r} is not 0..8")
    value = int(word)
    if value > 8:
        raise ProtocolError(f"length {value} is not 0..8")
    return value


def parse_command(element: str) -> Command:
    """Parse one element a client sent (as :func:`split_elements` returns it)."""
    words = _words(element)
    verb = words[0]
    if verb in ("rawmode", "bcmmode", "echo", "controlmode", "isotpmode"):
        if len(words) != 1:
            raise ProtocolError(f"'{verb}' takes no arguments")
        return Command(verb)
    if verb == "auth":
        if len(words) != 2:
            raise ProtocolError("usage: < auth TOKEN >")
        return Command(verb, token=words[1])
    if verb == "open":
        if len(words) != 2 or not _CHANNEL.fullmatch(words[1]):
            raise ProtocolError("usage: < open CHANNEL > (1..16 of A-Z a-z 0-9 _ . -)")
        return Command(verb, channel=words[1])
    if verb == "send":
        if len(words) < 3:
            raise ProtocolError("usage: < send ID LEN DATA... >")
        can_id, extended = _frame_id(words[1])
        length = _length(words[2])
        if len(words) != 3 + length:
            raise ProtocolError(f"length {length} but {len(words) - 3} data bytes")
        data = bytes(_byte(w) for w in words[3:])
        return Command(verb, frame=Frame(can_id, data, extended))
    if verb == "sendrtr":
        if len(words) != 3:
            raise ProtocolError("usage: < sendrtr ID LEN >")
        can_id, extended = _frame_id(words[1])
        return Command(verb, frame=Frame(can_id, b"", extended, rtr=True, dlc=_length(words[2])))
    if verb in ("add", "update", "delete", "filter", "muxfilter", "subscribe", "unsubscribe",
                "statistics", "isotpconf", "sendpdu", "fdsend"):
        return Command(verb)  # known to socketcand, not offered by this hub
    raise ProtocolError(f"unknown command {verb[:20]!r}")


def _byte(word: str) -> int:
    if len(word) > 2:
        raise ProtocolError(f"data byte {word[:20]!r} has more than 2 hex digits")
    return _hex(word, "data byte")


def _id_text(frame: Frame) -> str:
    return f"{frame.can_id:08X}" if frame.extended else f"{frame.can_id:03X}"


def format_frame(frame: Frame, timestamp: float) -> str:
    """The server's element for a received frame (``< frame ... >`` or ``< rtr ... >``)."""
    secs = int(timestamp)
    usecs = min(round((timestamp - secs) * 1e6), 999_999)
    stamp = f"{secs}.{usecs:06d}"
    if frame.rtr:
        return f"< rtr {_id_text(frame)} {stamp} {frame.dlc} >"
    return f"< frame {_id_text(frame)} {stamp} {frame.data.hex().upper()} >"


def format_send(frame: Frame) -> str:
    """The client's element to transmit ``frame``."""
    if frame.rtr:
        return f"< sendrtr {_id_text(frame)} {frame.dlc} >"
    data = "".join(f" {b:02X}" for b in frame.data)
    return f"< send {_id_text(frame)} {len(frame.data)}{data} >"


def format_error(text: str) -> str:
    """``< error TEXT >`` with the text made safe (one line, no brackets, bounded)."""
    clean = " ".join(text.replace("<", "(").replace(">", ")").split())[:100]
    return f"< error {clean} >"


def parse_server_element(element: str) -> tuple[str, Frame | None, float]:
    """Parse one element a server sent: (``"frame"``/``"rtr"``, frame, timestamp) or
    (verb, None, 0.0) for ``hi``, ``ok``, ``error ...``, ``echo``. For clients and tests."""
    words = _words(element)
    verb = words[0]
    if verb == "frame":
        if len(words) not in (3, 4):
            raise ProtocolError("usage: < frame ID SECS.USECS DATA >")
        can_id, extended = _frame_id(words[1])
        if not _TIME.fullmatch(words[2]):
            raise ProtocolError(f"time stamp {words[2][:20]!r} is not SECS.USECS")
        hexdata = words[3] if len(words) == 4 else ""
        if len(hexdata) % 2 or (hexdata and not _HEX.fullmatch(hexdata)):
            raise ProtocolError("frame data is not whole hex bytes")
        return verb, Frame(can_id, bytes.fromhex(hexdata), extended), float(words[2])
    if verb == "rtr":
        if len(words) != 4 or not _TIME.fullmatch(words[2]):
            raise ProtocolError("usage: < rtr ID SECS.USECS LEN >")
        can_id, extended = _frame_id(words[1])
        return verb, Frame(can_id, b"", extended, rtr=True, dlc=_length(words[3])), float(
            words[2])
    return verb, None, 0.0
