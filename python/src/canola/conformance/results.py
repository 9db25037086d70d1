# SPDX-License-Identifier: Apache-2.0
"""What a run gives: one :class:`Result` per check, gathered in a :class:`Report`."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

from canola.conformance.registry import Check

__all__ = ["Finding", "Interrupted", "Report", "Result", "Status"]


class Status(enum.Enum):
    PASSED = "PASSED"
    FAILED = "FAILED"
    SKIPPED = "SKIPPED"


@dataclass(frozen=True)
class Finding:
    """One deviation: ``what`` was tested, what was ``expected``, what the node did
    (``got``), the frames around it (trace lines, oldest first), and the ``clause`` it
    deviates from when it is narrower than the check's."""

    what: str
    expected: str
    got: str
    frames: tuple[str, ...] = ()
    clause: str = ""

    @property
    def text(self) -> str:
        """``what: expected X, got Y [clause]``."""
        rule = f" [{self.clause}]" if self.clause else ""
        return f"{self.what}: expected {self.expected}, got {self.got}{rule}"


@dataclass
class Result:
    """The outcome of one check. ``reason`` says why it was skipped (or, for a failure that
    ended the check, what stopped it); ``notes`` say what was measured or covered."""

    check: Check
    status: Status
    reason: str = ""
    findings: list[Finding] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def summary(self) -> str:
        """One line: the reason, the first finding, or the notes."""
        if self.status is Status.SKIPPED:
            return self.reason
        if self.status is Status.FAILED:
            if self.findings:
                more = f" (+{len(self.findings) - 1} more)" if len(self.findings) > 1 else ""
                return self.findings[0].text + more
            return self.reason
        return "; ".join(self.notes)


@dataclass
class Report:
    """A run against node ``node_id`` described by ``eds``, on ``bus`` (a description)."""

    node_id: int
    eds: str
    bus: str
    timing: str
    results: list[Result] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    #: The check a Ctrl-C interrupted ("" when the run ended by itself).
    interrupted: str = ""

    def count(self, status: Status) -> int:
        return sum(1 for r in self.results if r.status is status)

    @property
    def passed(self) -> bool:
        """True when no check failed."""
        return self.count(Status.FAILED) == 0

    def result(self, name: str) -> Result:
        """The result of check ``name`` (KeyError when it did not run)."""
        for r in self.results:
            if r.check.name == name:
                return r
        raise KeyError(name)

    def names(self, status: Status) -> set[str]:
        """The names of the checks that ended with ``status``."""
        return {r.check.name for r in self.results if r.status is status}

    @property
    def totals(self) -> str:
        """``40 passed, 2 failed, 3 skipped``."""
        return ", ".join(f"{self.count(s)} {s.value.lower()}" for s in Status)


class Interrupted(KeyboardInterrupt):
    """A run ended by Ctrl-C: :attr:`report` holds the checks that ran before."""

    def __init__(self, report: Report) -> None:
        super().__init__(f"interrupted during {report.interrupted}")
        self.report = report
