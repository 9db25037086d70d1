# SPDX-License-Identifier: Apache-2.0
"""Line-level reading of CiA 306 files: sections of ``key=value`` entries with line numbers.

Rules (the ones real files need):

- bytes are decoded as UTF-8 when they are valid UTF-8 (a BOM is dropped), else Latin-1;
- lines end in CRLF, LF or CR, mixed;
- blank lines and lines whose first non-blank character is ``;`` (CiA 306) or ``#`` (seen
  in real files) are comments;
- ``[name]`` opens a section; spaces inside the brackets are trimmed; a ``;``/``#`` comment
  after the ``]`` is dropped (a note);
- ``key = value``: the first ``=`` splits, both sides are trimmed. ``;`` and ``#`` inside a
  value are kept (they may be part of a string); the EDS layer strips comments from
  numbers and names;
- a section that comes again (same name, any case) continues the first: its keys are
  added, a later value of a key wins (a note, as tolerant INI readers do);
- a key given twice in a section: the later value wins (kept as a duplicate: at most
  :data:`KEPT_DUPLICATES` of them are kept per section, the rest only counted, so that a
  file of repeated keys costs no more memory than a file of distinct ones);
- anything else (a line without ``=``, a key before the first section) is an
  :class:`~canola.errors.EdsError` naming the file and line.

Notes (``Section.notes``: line, message) are deviations the reader read past; the EDS layer
makes them warnings (or, when strict, errors).
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass, field

from canola.errors import EdsError

_LINE_END = re.compile(r"\r\n|\r|\n")


#: Duplicate keys kept per section (for their warnings); more are only counted.
KEPT_DUPLICATES = 32


@dataclass(slots=True)
class Entry:
    key: str
    value: str
    line: int


@dataclass(slots=True)
class Section:
    name: str
    line: int
    entries: dict[str, Entry] = field(default_factory=dict)
    duplicates: list[Entry] = field(default_factory=list)
    more_duplicates: int = 0  # beyond KEPT_DUPLICATES
    notes: list[tuple[int, str]] = field(default_factory=list)

    def get(self, key: str) -> Entry | None:
        return self.entries.get(key.lower())

    def value(self, key: str) -> str | None:
        entry = self.entries.get(key.lower())
        return None if entry is None else entry.value


def decode(data: bytes) -> str:
    """UTF-8 when valid (BOM dropped), otherwise Latin-1 (which never fails)."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def _lines(text: str) -> Iterator[tuple[int, str]]:
    """(number, line) of ``text``, one at a time (a list of every line of a large file
    would cost more than the file)."""
    start = number = 0
    for end in _LINE_END.finditer(text):
        number += 1
        yield number, text[start:end.start()]
        start = end.end()
    yield number + 1, text[start:]


def read_sections(text: str, file: str) -> list[Section]:
    """Split ``text`` into sections; raise EdsError for lines that are none of the forms."""
    sections: list[Section] = []
    seen: dict[str, Section] = {}
    current: Section | None = None
    for number, raw in _lines(text):
        line = raw.strip()
        if not line or line.startswith((";", "#")):
            continue
        if line.startswith("["):
            current = _header(line, number, file, seen, sections)
            continue
        key, sep, value = line.partition("=")
        key = key.strip()
        if not sep or not key:
            raise EdsError(
                f"line is neither [section], key=value nor comment: {line[:40]!r}",
                file=file,
                line=number,
                section=None if current is None else current.name,
            )
        if current is None:
            raise EdsError("key=value before the first section", file=file, line=number, key=key)
        entry = Entry(key, value.strip(), number)
        folded = key.lower()
        old = current.entries.get(folded)
        if old is not None:
            if len(current.duplicates) < KEPT_DUPLICATES:
                current.duplicates.append(old)
            else:
                current.more_duplicates += 1
        current.entries[folded] = entry
    return sections


def _header(line: str, number: int, file: str, seen: dict[str, Section],
            sections: list[Section]) -> Section:
    """The section a ``[name]`` line opens (or continues)."""
    end = line.find("]")
    if end < 0:
        raise EdsError("section header without closing ']'", file=file, line=number)
    rest = line[end + 1:].strip()
    if rest and not rest.startswith((";", "#")):
        raise EdsError(f"text after the section header: {rest[:40]!r}", file=file,
                       line=number)
    name = line[1:end].strip()
    if not name:
        raise EdsError("empty section name", file=file, line=number)
    folded = name.lower()
    section = seen.get(folded)
    if section is not None:
        section.notes.append((number, f"section [{name}] again (first at line "
                                      f"{section.line}): its keys are added, later values "
                                      "win"))
    else:
        section = Section(name, number)
        seen[folded] = section
        sections.append(section)
    if rest:
        section.notes.append((number, "comment after the section header ignored"))
    return section
