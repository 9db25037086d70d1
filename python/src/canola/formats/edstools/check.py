# SPDX-License-Identifier: Apache-2.0
"""An EDS/DCF linter: the problems :func:`canola.formats.eds.parse` finds, each a warning (the file
gives a usable dictionary but deviates from CiA 306/301) or an error (the file cannot be
used: the parser refuses it, canola odgen and canola device refuse it, or it cannot be
read). ``strict`` makes every warning an error, as ``eds.parse(strict=True)`` refuses every
deviation.

    >>> for finding in check_file("drive.eds"):
    ...     print(finding)     # drive.eds:12: [1017] DefaultValue: warning: ...
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, replace
from pathlib import Path

from canola.errors import Diagnostic, EdsError
from canola.formats import eds
from canola.formats.datatypes import NumberError, parse_value
from canola.formats.odgen import refusals

__all__ = ["Finding", "check_file", "sdo_server_problems"]


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
    """The findings of one file, in the order of their lines (those without a line last).

    Errors are what the parser refuses, and what canola's dictionary builders refuse
    (:func:`canola.formats.odgen.refusals`: ``canola odgen`` and ``canola device`` refuse
    the same file); a warning at the same entry as such an error is left out."""
    try:
        od = eds.parse(Path(path))
    except EdsError as exc:
        return [Finding(p, True) for p in exc.problems]
    refused = refusals(od)
    at = {_place(d) for d in refused}
    findings = [Finding(d, True) for d in refused]
    findings += [Finding(d, strict) for d in [*od.warnings, *sdo_server_problems(od)]
                 if _place(d) not in at]
    return sorted(findings, key=lambda f: (f.diagnostic.line is None, f.diagnostic.line or 0))


def _place(d: Diagnostic) -> tuple[str, str]:
    """The entry a diagnostic is about: (section, key), case and sub-index zeros folded."""
    section = re.sub(r"sub0*(?=[0-9a-f])", "sub", (d.section or "").lower())
    return section, (d.key or "").lower()


#: The default SDO server's COB-IDs (CiA 301 7.2.4.3.3: fixed at these + node-ID).
_SDO_SERVER_BASE = {1: ("client -> server", 0x600), 2: ("server -> client", 0x580)}


def sdo_server_problems(od: eds.ObjectDictionary) -> list[Diagnostic]:
    """0x1200's COB-IDs other than CiA 301's defaults (``$NODEID+0x600``/``+0x580``): a
    device that used them would be unreachable by every tool that assumes the default SDO
    (canola's device serves the default SDO whatever the file says)."""
    obj = od.objects.get(0x1200)
    found: list[Diagnostic] = []
    if obj is None:
        return found
    for sub, (what, base) in _SDO_SERVER_BASE.items():
        var = obj.subs.get(sub)
        if var is None:
            continue
        key = "ParameterValue" if (var.parameter_value or "").strip() else "DefaultValue"
        text = (var.parameter_value if key == "ParameterValue" else var.default_value) or ""
        if not text.strip():
            continue
        try:
            ok = _default_cob_id(text, base, od.node_id)
        except NumberError:
            continue  # not a number: the parser's warning says so
        if not ok:
            section = "1200" if obj.compact_sub_obj else f"1200sub{sub}"
            found.append(Diagnostic(
                f"COB-ID {what} {text.strip()!r} is not CiA 301's default "
                f"$NODEID+0x{base:X}: the default SDO server's COB-IDs are fixed", od.file,
                var.line, section, key))
    return found


def _default_cob_id(text: str, base: int, node_id: int | None) -> bool:
    if "$nodeid" in text.lower():
        return parse_value(text, 0x07, 1) == base + 1 and parse_value(text, 0x07, 127) == \
            base + 127
    value = parse_value(text, 0x07, 0)
    if not isinstance(value, int):
        return False
    if node_id is not None:
        return value == base + node_id
    return base + 1 <= value <= base + 127
