# SPDX-License-Identifier: Apache-2.0
"""Line-level reading of CiA 306 files: sections of ``key=value`` entries with line numbers.

Rules (the ones real files need):

- bytes are decoded as UTF-8 when they are valid UTF-8 (a BOM is dropped), else Latin-1;
- lines end in CRLF, LF or CR, mixed;
- blank lines and lines whose first non-blank character is ``;`` (CiA 306) or ``#`` (seen
  in real files) are comments;
- ``[name]`` opens a section; spaces inside the brackets are trimmed;
- ``key = value``: the first ``=`` splits, both sides are trimmed. ``;`` inside a value is
  kept (it may be part of a string); the EDS layer strips ``;`` comments from numbers;
- anything else (a line without ``=``, a key before the first section, a duplicate section)
  is an :class:`~canola.errors.EdsError` naming the file and line.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from canola.errors import EdsError

_LINE_END = re.compile(r"\r\n|\r|\n")


@dataclass
class Entry:
    key: str
    value: str
    line: int


@dataclass
class Section:
    name: str
    line: int
    entries: dict[str, Entry] = field(default_factory=dict)
    duplicates: list[Entry] = field(default_factory=list)

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


def read_sections(text: str, file: str) -> list[Section]:
    """Split ``text`` into sections; raise EdsError for lines that are none of the forms."""
    sections: list[Section] = []
    seen: dict[str, Section] = {}
    current: Section | None = None
    for number, raw in enumerate(_LINE_END.split(text), start=1):
        line = raw.strip()
        if not line or line.startswith((";", "#")):
            continue
        if line.startswith("["):
            if not line.endswith("]"):
                raise EdsError("section header without closing ']'", file=file, line=number)
            name = line[1:-1].strip()
            if not name:
                raise EdsError("empty section name", file=file, line=number)
            folded = name.lower()
            if folded in seen:
                first = seen[folded].line
                raise EdsError(
                    f"duplicate section (first at line {first})",
                    file=file,
                    line=number,
                    section=name,
                )
            current = Section(name, number)
            seen[folded] = current
            sections.append(current)
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
        if folded in current.entries:
            current.duplicates.append(current.entries[folded])
        current.entries[folded] = entry
    return sections
