# SPDX-License-Identifier: Apache-2.0
"""A report as text: the check list (``--list``), a live line per check for a terminal,
Markdown (grouped, with each failure's expected, got and frames), JUnit XML."""

from __future__ import annotations

import sys
import xml.etree.ElementTree as ET
from typing import TextIO

from canola.conformance.registry import GROUPS, Check
from canola.conformance.results import Report, Result, Status

__all__ = ["LiveProgress", "check_list", "junit", "markdown", "verdict"]

_SHOWN_FINDINGS = 10


def check_list(checks: list[Check]) -> str:
    """One line per check: name, clause, what passes; grouped."""
    lines = []
    group = None
    width = max((len(c.name) for c in checks), default=0)
    for c in checks:
        if c.group != group:
            group = c.group
            lines.append(f"{group}: {GROUPS[group]}")
        extra = " [--destructive]" if c.destructive else ""
        lines.append(f"  {c.name:<{width}}  {c.clause}{extra}")
        lines.append(f"  {'':<{width}}  {c.title}")
    return "\n".join(lines) + "\n"


class LiveProgress:
    """``progress`` for :func:`canola.conformance.run`: one line per check on ``stream``;
    on a terminal the running check's name shows first and its line is then rewritten."""

    def __init__(self, stream: TextIO | None = None) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.tty = self.stream.isatty()

    def __call__(self, done: int, total: int, check: Check, result: Result | None) -> None:
        count = f"[{done + (result is None):>{len(str(total))}}/{total}]"
        if result is None:
            if self.tty:
                self.stream.write(f"{count} {check.name} ...")
                self.stream.flush()
            return
        line = f"{count} {result.status.value:<7} {check.name}"
        if result.status is Status.FAILED:
            line += f" [{check.clause}]"
        summary = result.summary
        if summary:
            line += f"  {summary}"
        self.stream.write(("\r\x1b[K" if self.tty else "") + line + "\n")
        self.stream.flush()


def verdict(report: Report) -> str:
    """PASSED, FAILED, or INTERRUPTED (Ctrl-C: the checks that ran are in the report)."""
    if report.interrupted:
        return "INTERRUPTED"
    return "PASSED" if report.passed else "FAILED"


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def markdown(report: Report) -> str:
    """The report in Markdown: a summary, a table per group, then the failures in detail."""
    out = [f"# CANopen conformance: node {report.node_id}", "",
           f"- EDS: `{report.eds}`", f"- bus: {report.bus}", f"- timing: {report.timing}",
           f"- result: **{verdict(report)}** ({report.totals})"]
    out += [f"- {note}" for note in report.notes]
    groups = list(dict.fromkeys(r.check.group for r in report.results))
    for group in groups:
        out += ["", f"## {group}: {GROUPS[group]}", "", "| check | clause | result | details |",
                "| --- | --- | --- | --- |"]
        for r in (r for r in report.results if r.check.group == group):
            out.append(f"| `{r.check.name}` | {_cell(r.check.clause)} | {r.status.value} | "
                       f"{_cell(r.summary) or _cell(r.check.title)} |")
    failed = [r for r in report.results if r.status is Status.FAILED]
    if failed:
        out += ["", "## Failures"]
    for r in failed:
        out += ["", f"### `{r.check.name}` ({r.check.clause})", "", r.check.title + "."]
        if r.reason and not r.findings:
            out += ["", r.reason]
        for f in r.findings[:_SHOWN_FINDINGS]:
            out += ["", f"- **{f.what}**", f"  - expected: {f.expected}", f"  - got: {f.got}"]
            if f.clause:
                out.append(f"  - clause: {f.clause}")
            if f.frames:
                out += ["", "  ```", *(f"  {line}" for line in f.frames), "  ```"]
        if len(r.findings) > _SHOWN_FINDINGS:
            out += ["", f"... and {len(r.findings) - _SHOWN_FINDINGS} more findings"]
    return "\n".join(out) + "\n"


def junit(report: Report) -> str:
    """The report as JUnit XML: a testsuite per group, a testcase per check (failure with
    the findings and frames, or skipped with the reason)."""
    root = ET.Element("testsuites", name=f"canola conformance node {report.node_id}",
                      tests=str(len(report.results)),
                      failures=str(report.count(Status.FAILED)),
                      skipped=str(report.count(Status.SKIPPED)))
    groups = list(dict.fromkeys(r.check.group for r in report.results))
    for group in groups:
        results = [r for r in report.results if r.check.group == group]
        suite = ET.SubElement(root, "testsuite", name=group, tests=str(len(results)),
                              failures=str(sum(r.status is Status.FAILED for r in results)),
                              skipped=str(sum(r.status is Status.SKIPPED for r in results)),
                              time=f"{sum(r.seconds for r in results):.3f}")
        for r in results:
            case = ET.SubElement(suite, "testcase", classname=f"conformance.{group}",
                                 name=r.check.name, time=f"{r.seconds:.3f}")
            ET.SubElement(case, "properties").append(
                ET.Element("property", name="clause", value=r.check.clause))
            if r.status is Status.SKIPPED:
                ET.SubElement(case, "skipped", message=r.reason)
            elif r.status is Status.FAILED:
                failure = ET.SubElement(case, "failure", message=r.summary)
                failure.text = "\n\n".join(
                    f"{f.what}\nexpected: {f.expected}\ngot: {f.got}\n"
                    + (f"clause: {f.clause}\n" if f.clause else "") + "\n".join(f.frames)
                    for f in r.findings) or r.reason
            elif r.notes:
                ET.SubElement(case, "system-out").text = "\n".join(r.notes)
    ET.indent(root)
    return ET.tostring(root, encoding="unicode", xml_declaration=True) + "\n"
