# SPDX-License-Identifier: Apache-2.0
"""The error tree of the canola package.

Every error canola raises on purpose derives from :class:`Error`. Problems found in an
EDS/DCF file are :class:`EdsError`; each names where it was found so that the message
reads ``FILE:LINE: [SECTION] KEY: what is wrong`` (parts that are unknown are left out).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

__all__ = ["ABORT_TEXT", "Diagnostic", "EdsError", "Error", "SdoAbort", "SdoTimeout"]


class Error(Exception):
    """Base class of every error raised by canola."""


@dataclass(frozen=True)
class Diagnostic:
    """One problem in an EDS/DCF file, with the place it was found."""

    message: str
    file: str | None = None
    line: int | None = None
    section: str | None = None
    key: str | None = None

    def __str__(self) -> str:
        where = ""
        if self.file is not None:
            where = self.file + ":"
            if self.line is not None:
                where += f"{self.line}:"
        elif self.line is not None:
            where = f"line {self.line}:"
        parts = [where] if where else []
        if self.section is not None:
            parts.append(f"[{self.section}]")
        if self.key is not None:
            parts.append(f"{self.key}:")
        parts.append(self.message)
        return " ".join(parts)


class EdsError(Error):
    """An EDS/DCF file that cannot be used (or, in strict mode, that breaks CiA 306).

    ``file``, ``line``, ``section`` and ``key`` locate the (first) problem; ``problems``
    lists every problem found, one :class:`Diagnostic` each, and the message has one line
    per problem.
    """

    def __init__(
        self,
        message: str = "",
        *,
        file: str | None = None,
        line: int | None = None,
        section: str | None = None,
        key: str | None = None,
        problems: Sequence[Diagnostic] = (),
    ) -> None:
        if not problems:
            problems = (Diagnostic(message, file, line, section, key),)
        first = problems[0]
        self.problems: tuple[Diagnostic, ...] = tuple(problems)
        self.file = first.file
        self.line = first.line
        self.section = first.section
        self.key = first.key
        self.reason = first.message
        super().__init__("\n".join(str(p) for p in self.problems))


#: CiA 301 texts of the SDO abort codes (those the canola core uses).
ABORT_TEXT: dict[int, str] = {
    0x05030000: "Toggle bit not alternated",
    0x05040000: "SDO protocol timed out",
    0x05040001: "Client/server command specifier not valid or unknown",
    0x05040002: "Invalid block size",
    0x05040003: "Invalid sequence number",
    0x05040004: "CRC error",
    0x05040005: "Out of memory",
    0x06010000: "Unsupported access to an object",
    0x06010001: "Attempt to read a write only object",
    0x06010002: "Attempt to write a read only object",
    0x06020000: "Object does not exist in the object dictionary",
    0x06040041: "Object cannot be mapped to the PDO",
    0x06040042: "The number and length of the objects to be mapped would exceed PDO length",
    0x06040043: "General parameter incompatibility reason",
    0x06040047: "General internal incompatibility in the device",
    0x06060000: "Access failed due to a hardware error",
    0x06070010: "Data type does not match, length of service parameter does not match",
    0x06070012: "Data type does not match, length of service parameter too high",
    0x06070013: "Data type does not match, length of service parameter too low",
    0x06090011: "Sub-index does not exist",
    0x06090030: "Invalid value for parameter (download only)",
    0x06090031: "Value of parameter written too high (download only)",
    0x06090032: "Value of parameter written too low (download only)",
    0x06090036: "Maximum value is less than minimum value",
    0x060A0023: "Resource not available: SDO connection",
    0x08000000: "General error",
    0x08000020: "Data cannot be transferred or stored to the application",
    0x08000021: "Data cannot be transferred or stored to the application because of local "
                "control",
    0x08000022: "Data cannot be transferred or stored to the application because of the "
                "present device state",
    0x08000023: "Object dictionary dynamic generation fails or no object dictionary is "
                "present",
    0x08000024: "No data available",
}


class SdoAbort(Error):  # noqa: N818 -- the CiA name of the event
    """An object dictionary access (local or over SDO) ended with a CiA 301 abort code.

    ``code`` is the abort code; ``text`` its CiA 301 meaning ("unknown abort code" for
    codes not in :data:`ABORT_TEXT`). For an SDO transfer of a :class:`canola.Master`:
    ``node`` is the server, ``by_server`` is True when the server sent the abort (False:
    the master ended the transfer itself, e.g. on a bad answer) and ``after_s`` is how long
    the transfer had run; all three are None for a local access.
    """

    def __init__(self, code: int, *, node: int | None = None, by_server: bool | None = None,
                 after_s: float | None = None) -> None:
        self.code = code
        self.text = ABORT_TEXT.get(code, "unknown abort code")
        self.node = node
        self.by_server = by_server
        self.after_s = after_s
        message = f"SDO abort 0x{code:08X}: {self.text}"
        if node is not None and after_s is not None:
            who = f"node {node}" if by_server else "the master"
            message += f" (sent by {who} after {after_s:.2f} s)"
        super().__init__(message)


class SdoTimeout(SdoAbort):
    """The server did not answer in time: the master ended the transfer with abort code
    0x05040000 (SDO protocol timed out) itself, after ``timeout_ms`` without an answer (or
    the transfer's whole ``timeout``). A server that sends 0x05040000 raises
    :class:`SdoAbort` with ``by_server`` True instead."""

    def __init__(self, node: int, timeout_ms: int, after_s: float | None = None) -> None:
        super().__init__(0x05040000, node=node, by_server=False, after_s=after_s)
        self.timeout_ms = timeout_ms
        took = f", after {after_s:.2f} s" if after_s is not None else ""
        self.args = (f"no response from node {node} (SDO time-out {timeout_ms} ms{took})",)

    def __str__(self) -> str:
        return str(self.args[0])
