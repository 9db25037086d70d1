# SPDX-License-Identifier: Apache-2.0
"""Reading candump output: the log format (``candump -l``) and the screen format.

    (1700000000.123456) can0 705#05            log format; ``705#R`` remote, ``705#R1`` DLC
    (1700000000.123456)  can0  705   [1]  05   screen format with -t a/d/z (time optional)
      can0  705   [1]  remote request

Classic CAN only (CAN FD ``##`` lines are refused). :func:`parse_line` returns None for
blank lines and ``#`` comments and raises :class:`CandumpError` (with the line) otherwise.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass
from typing import TextIO

from canola.errors import Error

__all__ = ["CandumpError", "LogFrame", "parse_line", "read_log"]

_LOG = re.compile(r"\((\d+(?:\.\d+)?)\)\s+(\S+)\s+([0-9A-Fa-f]{1,8})#(R\d?|[0-9A-Fa-f]*)\s*")
_SCREEN = re.compile(
    r"(?:\((\d+(?:\.\d+)?)\)\s+)?(\S+)\s+([0-9A-Fa-f]{1,8})\s+\[(\d)\]"
    r"(?:\s+(remote request|(?:[0-9A-Fa-f]{2}(?:\s+|$))*))?\s*")


class CandumpError(Error):
    """A line that is not candump output."""


@dataclass(frozen=True)
class LogFrame:
    timestamp: float | None
    channel: str
    can_id: int
    data: bytes
    extended: bool
    rtr: bool


def parse_line(line: str) -> LogFrame | None:
    text = line.strip()
    if not text or text.startswith("#"):
        return None
    m = _LOG.fullmatch(text)
    if m is not None:
        stamp, channel, ident, payload = m.groups()
        rtr = payload.startswith("R")
        if not rtr and len(payload) % 2:
            raise CandumpError(f"odd number of hex digits: {text[:80]}")
        data = b"" if rtr else bytes.fromhex(payload)
        return _frame(float(stamp), channel, ident, data, rtr, text=text)
    m = _SCREEN.fullmatch(text)
    if m is not None:
        stamp, channel, ident, dlc, payload = m.groups()
        payload = payload or ""
        rtr = payload == "remote request"
        data = b"" if rtr else bytes.fromhex("".join(payload.split()))
        if not rtr and len(data) != int(dlc):
            raise CandumpError(f"[{dlc}] but {len(data)} data bytes: {text[:80]}")
        return _frame(float(stamp) if stamp else None, channel, ident, data, rtr, text=text)
    raise CandumpError(f"not a candump line: {text[:80]}")


def _frame(stamp: float | None, channel: str, ident: str, data: bytes, rtr: bool, *,
           text: str) -> LogFrame:
    can_id = int(ident, 16)
    extended = len(ident) > 3
    if len(data) > 8 or can_id > (0x1FFFFFFF if extended else 0x7FF):
        raise CandumpError(f"not a classic CAN frame: {text[:80]}")
    return LogFrame(stamp, channel, can_id, data, extended, rtr)


def read_log(stream: TextIO, name: str = "-") -> Iterator[LogFrame]:
    """Frames of a candump file; errors name ``name:LINE``."""
    for number, line in enumerate(stream, 1):
        try:
            frame = parse_line(line)
        except CandumpError as exc:
            raise CandumpError(f"{name}:{number}: {exc}") from None
        if frame is not None:
            yield frame
