# SPDX-License-Identifier: Apache-2.0
"""An EDS/DCF linter: the problems :func:`canola.formats.eds.parse` finds, each a warning (the file
gives a usable dictionary but deviates from CiA 306/301) or an error (the file cannot be
used: the parser refuses it, or it cannot be read). ``strict`` makes every warning an
error, as ``eds.parse(strict=True)`` refuses every deviation.

    >>> for finding in check_file("drive.eds"):
    ...     print(finding)     # drive.eds:12: [1017] DefaultValue: warning: ...
"""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from pathlib import Path

from canola.errors import Diagnostic, EdsError
from canola.formats import eds

__all__ = ["Finding", "check_file"]


@dataclass(frozen=True)
class Finding:
    """One problem of a file: where and what (a :class:`~canola.errors.Diagnostic`), and
    whether it is an error."""

    diagnostic: Diagnostic
    error: bool

    def __str__(self) -> str:
        """``FILE:LINE: [SECTION] KEY: error|warning: MESSAGE`` (unknown parts left out)."""
        kind = "error" if self.error else "warning"
        return str(replace(self.diagnostic, message=f"{kind}: {self.diagnostic.message}"))


def check_file(path: str | os.PathLike[str], *, strict: bool = False) -> list[Finding]:
    """The findings of one file, in the order of their lines (those without a line last)."""
    try:
        od = eds.parse(Path(path))
    except EdsError as exc:
        return [Finding(p, True) for p in exc.problems]
    findings = [Finding(d, strict) for d in od.warnings]
    return sorted(findings, key=lambda f: (f.diagnostic.line is None, f.diagnostic.line or 0))
