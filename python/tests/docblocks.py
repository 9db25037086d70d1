# SPDX-License-Identifier: Apache-2.0
"""The manual's pages as the tests read them: README.md and docs/*.md, their fenced code
blocks, their links and GitHub's anchors of their headings.

A block is what sits between two fences (```` ```LANG ```` and ```` ``` ````). The kinds the
tests act on (``test_doc_blocks.py``, ``test_doc_links.py``):

- ``sh``: commands, one a line (a line ending in ``\\`` goes on), each run or checked;
- ``console``: ``$ COMMAND`` lines, each followed by the output the page shows for it;
- ``python``: a program, run; a ``text`` block right after it (blank lines between at
  most) is the output the page shows for it;
- every other kind (``c``, ``cmake``, ``yaml``, ``text``, none) is read, not run.

A line ``<!-- not run: WHY -->`` right before a block (a reader's own hardware, a host
elsewhere, a fragment) makes an ``sh`` or ``python`` block one the tests check without
running it, and a ``c`` block one they do not compile (``Block.not_run``: WHY).
"""

from __future__ import annotations

import re
import shlex
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"

_FENCE = re.compile(r"^(`{3,})(\S*)\s*$")
_NOT_RUN = re.compile(r"^<!-- not run: (.+) -->$")


def pages() -> list[Path]:
    """The pages whose blocks the tests run: the README, CONTRIBUTING.md and every page of
    docs/."""
    return [ROOT / "README.md", ROOT / "CONTRIBUTING.md", *sorted(DOCS.glob("*.md"))]


def page_name(page: Path) -> str:
    return page.relative_to(ROOT).as_posix() if page.is_relative_to(ROOT) else page.name


@dataclass
class Step:
    """One command of a block: its text (continuations joined), the output the page shows
    for it (console blocks; None: not shown), and the page's line it starts on."""

    command: str
    shown: list[str] | None
    line: int

    def words(self) -> list[str]:
        """The command as a shell splits it, without its comment."""
        return shlex.split(self.command, comments=True)


@dataclass
class Block:
    page: Path
    line: int  # the line of the opening fence (1-based)
    lang: str
    text: str
    output: list[str] | None = None  # python: the text block after it
    not_run: str | None = None  # why the block is checked, not run
    steps: list[Step] = field(default_factory=list)  # sh and console

    @property
    def where(self) -> str:
        return f"{page_name(self.page)}:{self.line}"


def blocks(page: Path) -> list[Block]:
    """The fenced blocks of ``page`` in order; a ``text`` block that shows a python
    block's output is that block's ``output``, not a block of its own."""
    lines = page.read_text(encoding="utf-8").splitlines()
    found: list[Block] = []
    previous_end = -1  # the line index of the last block's closing fence
    i = 0
    while i < len(lines):
        m = _FENCE.match(lines[i])
        if m is None:
            i += 1
            continue
        fence, lang = m.groups()
        end = i + 1
        while end < len(lines) and lines[end].rstrip() != fence:
            end += 1
        if end == len(lines):
            raise AssertionError(f"{page_name(page)}:{i + 1}: a block that is never closed")
        body = lines[i + 1:end]
        last = found[-1] if found else None
        if (lang == "text" and last is not None and last.lang == "python"
                and last.output is None
                and all(not line.strip() for line in lines[previous_end + 1:i])):
            last.output = body
        else:
            block = Block(page, i + 1, lang, "\n".join(body) + "\n")
            m_not_run = _NOT_RUN.match(lines[i - 1].strip()) if i else None
            block.not_run = m_not_run.group(1) if m_not_run else None
            if lang == "sh":
                block.steps = _sh_steps(body, i + 2)
            elif lang == "console":
                block.steps = _console_steps(body, i + 2, block.where)
            found.append(block)
        previous_end = end
        i = end + 1
    return found


def _joined(body: list[str], first: int) -> list[tuple[int, str]]:
    """(line number, text) of each logical line: a trailing backslash joins the next."""
    out: list[tuple[int, str]] = []
    pending: tuple[int, str] | None = None
    for n, line in enumerate(body, first):
        if pending is not None:
            start, text = pending
            text = text[:-1].rstrip() + " " + line.strip()
        else:
            start, text = n, line
        pending = (start, text) if text.rstrip().endswith("\\") else None
        if pending is None:
            out.append((start, text))
    assert pending is None, f"line {pending[0]}: a continuation with nothing after it"
    return out


def _sh_steps(body: list[str], first: int) -> list[Step]:
    return [Step(text.strip(), None, n) for n, text in _joined(body, first)
            if text.strip() and not text.lstrip().startswith("#")]


def _console_steps(body: list[str], first: int, where: str) -> list[Step]:
    steps: list[Step] = []
    for n, text in _joined(body, first):
        if text.startswith("$ "):
            steps.append(Step(text[2:].strip(), [], n))
        elif steps:
            shown = steps[-1].shown
            assert shown is not None
            shown.append(text)
        elif text.strip():
            raise AssertionError(f"{where}: output before the first '$ ' command: {text!r}")
    for step in steps:  # the blank lines that end an output are not part of it
        while step.shown and not step.shown[-1].strip():
            step.shown.pop()
    return steps


# ---- output as the page shows it

def shows(shown: list[str], actual: str) -> str | None:
    """None when every line ``shown`` appears among the lines of ``actual`` in the same
    order (other lines may come between); ``...`` in a shown line stands for any text, a
    line of ``...`` alone for any lines. Else the first shown line not found."""
    lines = [line.rstrip() for line in actual.splitlines()]
    at = 0
    for want in shown:
        if want.strip() in ("", "..."):
            continue
        pattern = re.compile(".*".join(re.escape(part) for part in want.rstrip().split("...")))
        while at < len(lines) and not pattern.fullmatch(lines[at]):
            at += 1
        if at == len(lines):
            return want
        at += 1
    return None


# ---- links and anchors

_HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
_LINK = re.compile(r"(?<!!)\[(?:[^\]\[]|\[[^\]]*\])*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
_CODE_SPAN = re.compile(r"(`+).*?\1")


def prose(page: Path) -> list[tuple[int, str]]:
    """(line number, text) of the page's lines outside its fenced blocks, code spans
    blanked (a link or heading inside code is no link)."""
    out: list[tuple[int, str]] = []
    fence: str | None = None
    for n, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
        m = _FENCE.match(line)
        if fence is None and m is not None:
            fence = m.group(1)
            continue
        if fence is not None:
            if line.rstrip() == fence:
                fence = None
            continue
        out.append((n, line))
    return out


def anchor(heading: str) -> str:
    """GitHub's anchor of a heading's text: the text as it reads (code marks and link
    targets gone), lower case, without punctuation but ``-`` and ``_``, spaces as ``-``."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # a link reads as its text
    text = re.sub(r"<[^>]+>", "", text)
    text = text.replace("`", "").lower()
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def anchors(page: Path) -> set[str]:
    """Every anchor GitHub makes for the page's headings (a repeated one gets -1, -2...)."""
    seen: dict[str, int] = {}
    out: set[str] = set()
    for _, line in prose(page):
        m = _HEADING.match(line)
        if m is None:
            continue
        slug = anchor(m.group(2))
        count = seen.get(slug, 0)
        seen[slug] = count + 1
        out.add(slug if count == 0 else f"{slug}-{count}")
    return out


def links(page: Path) -> list[tuple[int, str]]:
    """(line number, target) of every Markdown link of the page's prose."""
    found: list[tuple[int, str]] = []
    for n, line in prose(page):
        for m in _LINK.finditer(_CODE_SPAN.sub(lambda s: " " * len(s.group(0)), line)):
            found.append((n, m.group(1)))
    return found
