"""The error tree of the canola package.

Every error canola raises on purpose derives from :class:`Error`. Problems found in an
EDS/DCF file are :class:`EdsError`; each names where it was found so that the message
reads ``FILE:LINE: [SECTION] KEY: what is wrong`` (parts that are unknown are left out).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

__all__ = ["Diagnostic", "EdsError", "Error"]


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
