# SPDX-License-Identifier: Apache-2.0
"""Entries of an EDS/DCF named as python-canopen names them, and their values in words.

    >>> var = find_entry(od, "Identity object.Vendor-ID")   # or "0x1018:1", "1018:1"
    >>> entry_name(od, 0x1017, 0)
    'Producer heartbeat time'
    >>> value_text(var, b"\\xa0\\x0c\\x00\\x00")
    '3232'

A VAR object is named by its ParameterName, an entry of an ARRAY or RECORD by the object's
name, a dot and the entry's name (or its sub-index: ``"Identity object.1"``). Numbers work
as well: ``0x1017`` (sub-index 0) and ``0x1018:1`` (the sub-index decimal or 0x-hex).
Names match exactly, else ignoring case when that finds one entry only. Every failure is
an :class:`EntryError` with one line that says what was expected (and the nearest names).
"""

from __future__ import annotations

import difflib
from collections.abc import Callable

from canola.errors import Error
from canola.formats import values
from canola.formats.eds import Object, ObjectDictionary, ObjectType, Variable

__all__ = ["EntryError", "entry_name", "find_entry", "parse_address", "value_text"]


class EntryError(Error):
    """An entry name or address that names nothing (one-line message)."""


def parse_address(text: str) -> tuple[int, int] | None:
    """``INDEX[:SUB]`` (index hex with or without 0x, sub decimal or 0x-hex) as numbers, or
    None when ``text`` is not written so."""
    index_text, colon, sub_text = text.strip().partition(":")
    if colon and not sub_text:
        return None
    try:
        hex_digits = index_text[2:] if index_text.lower().startswith("0x") else index_text
        if not 1 <= len(hex_digits) <= 4:
            return None
        index = int(hex_digits, 16)
        sub = int(sub_text, 0) if sub_text else 0
    except ValueError:
        return None
    return (index, sub) if 0 <= sub <= 0xFF else None


def entry_name(od: ObjectDictionary, index: int, sub: int) -> str | None:
    """The python-canopen name of an entry, None when ``od`` lacks it."""
    obj = od.objects.get(index)
    var = None if obj is None else obj.subs.get(sub)
    if obj is None or var is None:
        return None
    if obj.object_type in (ObjectType.VAR, ObjectType.DOMAIN) and sub == 0:
        return obj.name
    return f"{obj.name}.{var.name}"


def find_entry(od: ObjectDictionary, text: str) -> Variable:
    """The entry ``text`` names in ``od`` (see the module text). Raises EntryError."""
    address = parse_address(text)
    if address is not None:
        index, sub = address
        obj = od.objects.get(index)
        if obj is None or sub not in obj.subs:
            raise EntryError(f"{od.file} has no entry 0x{index:04X}:{sub:02X}")
        return obj.subs[sub]
    name = text.strip()
    var = _by_name(od, name, str.__eq__) or _by_name(od, name, _same_ignoring_case)
    if var is not None:
        return var
    for obj in od.objects.values():
        if obj.object_type not in (ObjectType.VAR, ObjectType.DOMAIN) and obj.subs and (
                _same_ignoring_case(obj.name, name)):
            first = entry_name(od, obj.index, max(obj.subs))
            raise EntryError(f"{name!r} is no single entry ({obj.object_type.name}) in "
                             f"{od.file}: name one of its entries, e.g. {first!r}")
    near = difflib.get_close_matches(name, _all_names(od), n=3, cutoff=0.6)
    hint = f" (did you mean {', '.join(repr(n) for n in near)}?)" if near else ""
    raise EntryError(f"{od.file} has no entry named {name!r}{hint}")


def value_text(var: Variable | None, data: bytes) -> str:
    """``data`` as the value of ``var`` (its EDS data type), else as :func:`format_value`
    shows bytes of an unknown type."""
    code = None if var is None else var.data_type
    if code is not None:
        try:
            return values.to_text(code, values.decode(code, data))
        except values.ValueFormatError:  # unknown type, or not its size
            pass
    return values.untyped_text(data) if data else "(empty)"


def _same_ignoring_case(a: str, b: str) -> bool:
    return a.casefold() == b.casefold()


def _by_name(od: ObjectDictionary, name: str, same: Callable[[str, str], bool]) -> Variable | None:
    """The one entry called ``name`` by the comparison ``same``; EntryError when several."""
    found: list[Variable] = []
    for obj in od.objects.values():
        found.extend(_matches(obj, name, same))
    if len(found) > 1:
        where = ", ".join(f"0x{v.index:04X}:{v.subindex:02X}" for v in found[:4])
        raise EntryError(f"{od.file}: {name!r} names several entries ({where}): "
                         "use INDEX:SUB")
    return found[0] if found else None


def _matches(obj: Object, name: str, same: Callable[[str, str], bool]) -> list[Variable]:
    if obj.object_type in (ObjectType.VAR, ObjectType.DOMAIN):
        var = obj.subs.get(0)
        return [var] if var is not None and same(obj.name, name) else []
    found = []
    for dot in range(len(name)):  # object names may hold dots: try every split
        if name[dot] != "." or not same(obj.name, name[:dot]):
            continue
        sub_text = name[dot + 1:]
        for sub, var in obj.subs.items():
            if same(var.name, sub_text) or (sub_text.isdigit() and int(sub_text) == sub):
                found.append(var)
    return found


def _all_names(od: ObjectDictionary) -> list[str]:
    names = []
    for obj in od.objects.values():
        for sub in obj.subs:
            name = entry_name(od, obj.index, sub)
            if name is not None:
                names.append(name)
    return names
