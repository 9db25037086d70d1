# SPDX-License-Identifier: Apache-2.0
"""docs/cli.md's argument tables, made from the command line's own parsers
(:func:`canola.cli.build_parser`, and :func:`canola.formats.odgen.build_parser` for
``canola odgen``), so that the page lists every argument and option a command takes, with
its help text, and nothing else (``test_cli_doc.py`` compares).

Each table follows a marker line ``<!-- arguments: canola sdo read -->`` on the page;
``python tests/cli_doc.py`` (from python/) writes every table anew, and gives a section
of a command (its heading ``### `canola view` ``) that has no table yet its marker and
table."""

from __future__ import annotations

import argparse
import re
import sys
from collections import Counter
from pathlib import Path

from canola.cli import build_parser
from canola.formats import odgen

PAGE = Path(__file__).resolve().parents[2] / "docs" / "cli.md"
MARKER = re.compile(r"^<!-- arguments: (canola[a-z -]*?) -->$")
#: Options many commands share, said once on the page: where their row points (the row
#: keeps the command's own help where it says something else).
SHARED = {"--iface": "the bus", "--bus": "the bus", "--eds": "what every command shares",
          "--dcf": "what every command shares", "--announce": "what every command shares"}


def commands() -> dict[str, argparse.ArgumentParser]:
    """Every command that runs (one without sub-commands) by its words, and ``canola``
    itself (its global options)."""
    found: dict[str, argparse.ArgumentParser] = {}

    def walk(parser: argparse.ArgumentParser, words: str) -> None:
        subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        if not subs or words == "canola":
            found[words] = parser
        for action in subs:
            for name, sub in action.choices.items():
                walk(sub, f"{words} {name}")

    walk(build_parser(), "canola")
    found["canola odgen"] = odgen.build_parser("canola odgen")
    return found


def _cell(text: str) -> str:
    return " ".join(text.split()).replace("|", "\\|")


def _arguments(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    return [a for a in parser._actions if a.help != argparse.SUPPRESS and not isinstance(
        a, argparse._SubParsersAction | argparse._HelpAction)]


def _shared_help() -> dict[str, str]:
    """The help most commands give each SHARED option."""
    helps = Counter((a.option_strings[-1], a.help) for p in commands().values()
                    for a in _arguments(p) if a.option_strings)
    shared: dict[str, str] = {}
    for (option, text), _ in helps.most_common():
        if option in SHARED and option not in shared and text:
            shared[option] = text
    return shared


def table(parser: argparse.ArgumentParser, shared: dict[str, str] | None = None) -> list[str]:
    """The Markdown table of ``parser``'s arguments: each as it is typed, and its help (an
    option of ``shared`` that says what the help there says: a link to the page's section
    of it)."""
    formatter = parser._get_formatter()
    rows = ["| argument | what it is |", "| --- | --- |"]
    for action in _arguments(parser):
        if action.option_strings:
            takes = "" if action.nargs == 0 else " " + formatter._format_args(
                action, action.dest.upper())
            typed = ", ".join(f"`{s}{takes}`" for s in action.option_strings)
        else:
            typed = f"`{formatter._format_args(action, action.dest)}`"
        typed = typed.replace("|", "\\|")  # even in code, a table's cell ends at a bare |
        help_text = _cell(formatter._expand_help(action)) if action.help else ""
        option = action.option_strings[-1] if action.option_strings else ""
        if shared and option in shared and shared[option] == action.help:
            section = SHARED[option]
            help_text = f"[{section}](#{section.replace(' ', '-')})"
        rows.append(f"| {typed} | {help_text} |")
    return rows


_HEADING = re.compile(r"^#{2,4} `(canola[a-z -]*?)`$")


def _with_markers(lines: list[str], parsers: dict[str, argparse.ArgumentParser]) -> list[str]:
    """``lines`` with a marker at the end of each command's section (a heading
    ``### `canola WORDS` ``) that has none yet: a command that came with a section of
    prose gets its table from the next ``python tests/cli_doc.py``."""
    out: list[str] = []
    pending: str | None = None  # the command whose section is open and has no marker
    for line in lines:
        heading = line.startswith("#")
        if heading and pending is not None:
            out += [f"<!-- arguments: {pending} -->", ""]
        if heading:
            m = _HEADING.match(line)
            pending = m.group(1) if m and m.group(1) in parsers else None
        elif MARKER.match(line):
            pending = None
        out.append(line)
    if pending is not None:
        out += ["", f"<!-- arguments: {pending} -->"]
    return out


def render(text: str) -> str:
    """``text`` (the page) with every table after a marker made anew, and a marker and
    table for each command's section that has none."""
    parsers = commands()
    shared = _shared_help()
    out: list[str] = []
    lines = _with_markers(text.splitlines(), parsers)
    i = 0
    while i < len(lines):
        out.append(lines[i])
        m = MARKER.match(lines[i])
        i += 1
        if m is None:
            continue
        words = m.group(1)
        if words not in parsers:
            raise SystemExit(f"{PAGE.name}: no command '{words}'")
        while i < len(lines) and lines[i].startswith("|"):
            i += 1  # the old table
        out.extend(table(parsers[words], shared))
    return "\n".join(out) + "\n"


def listed(text: str) -> list[str]:
    """The commands the page has a table for."""
    return [m.group(1) for line in text.splitlines() if (m := MARKER.match(line))]


if __name__ == "__main__":
    page = PAGE.read_text(encoding="utf-8")
    new = render(page)
    if new != page:
        PAGE.write_text(new, encoding="utf-8")
        print(f"{PAGE}: tables written")
    missing = sorted(set(commands()) - set(listed(new)))
    if missing:
        print(f"{PAGE}: no table for {', '.join(missing)}", file=sys.stderr)
        sys.exit(1)
