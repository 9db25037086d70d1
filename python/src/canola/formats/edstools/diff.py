# SPDX-License-Identifier: Apache-2.0
"""What differs between two dictionaries (``canola eds diff``): objects and entries only
in one of them, and entries whose name, data type, access, PDO mapping, default or
(DCF) value differ; or, with :func:`diff_live`, between a dictionary's values and those a
device gives by SDO.

    >>> for d in diff(eds.parse(Path("v1.eds")), eds.parse(Path("v2.eds"))):
    ...     print(d)       # 0x1017:00 Producer heartbeat time: default: A 0, B 100
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass

from canola.errors import SdoAbort
from canola.formats import eds, values
from canola.formats.concise import wire
from canola.formats.datatypes import DATA_TYPES
from canola.formats.edstools.table import type_name

__all__ = ["Difference", "diff", "diff_live"]

#: Abort codes that say the device has no such object / sub-index (CiA 301).
_NO_OBJECT, _NO_SUB = 0x06020000, 0x06090011
_TIMED_OUT = 0x05040000
_TEXTS = (0x09, 0x0B)  # compared as text: a device may pad a string with NULs
_DOMAIN = 0x0F


@dataclass(frozen=True)
class Difference:
    """One difference. ``sub`` is None for a whole object. ``what`` is ``only in A``,
    ``only in B``, or the property that differs (``object type``, ``name``, ``type``,
    ``access``, ``PDO mapping``, ``default``, ``value``, ``read``), with A's and B's
    texts of it."""

    index: int
    sub: int | None
    name: str
    what: str
    a: str | None = None
    b: str | None = None

    def __str__(self) -> str:
        where = f"0x{self.index:04X}" + ("" if self.sub is None else f":{self.sub:02X}")
        text = f"{where} {self.name}: {self.what}"
        if not self.what.startswith("only in"):
            text += f": A {_shown(self.a)}, B {_shown(self.b)}"
        return text

    def as_dict(self) -> dict[str, object]:
        return {"index": self.index, "sub": self.sub, "name": self.name, "what": self.what,
                "a": self.a, "b": self.b}


def _shown(text: str | None) -> str:
    """A text as the line shows it: quoted where it would not read as one."""
    if text is None:
        return "(none)"
    return repr(text) if text == "" or ", " in text or text != text.strip() else text


def diff(a: eds.ObjectDictionary, b: eds.ObjectDictionary) -> list[Difference]:
    """The differences of ``b`` from ``a``, in index and sub-index order."""
    out: list[Difference] = []
    for index in sorted(a.objects.keys() | b.objects.keys()):
        obj_a, obj_b = a.objects.get(index), b.objects.get(index)
        if obj_a is None or obj_b is None:
            out.append(_only(index, None, obj_a, obj_b))
            continue
        out += _object_differences(obj_a, obj_b)
    return out


def _only(index: int, sub: int | None, in_a: eds.Object | eds.Variable | None,
          in_b: eds.Object | eds.Variable | None) -> Difference:
    """The difference of an object or entry that only one side has."""
    only = in_a or in_b
    assert only is not None
    return Difference(index, sub, only.name, "only in A" if in_b is None else "only in B")


def _object_differences(obj_a: eds.Object, obj_b: eds.Object) -> Iterator[Difference]:
    index = obj_a.index
    if obj_a.object_type != obj_b.object_type:
        yield Difference(index, None, obj_a.name, "object type", obj_a.object_type.name,
                         obj_b.object_type.name)
    if obj_a.object_type != eds.ObjectType.VAR and obj_a.name != obj_b.name:
        yield Difference(index, None, obj_a.name, "name", obj_a.name, obj_b.name)
    for sub in sorted(obj_a.subs.keys() | obj_b.subs.keys()):
        var_a, var_b = obj_a.subs.get(sub), obj_b.subs.get(sub)
        if var_a is None or var_b is None:
            yield _only(index, sub, var_a, var_b)
            continue
        for what, text_a, text_b in _differing(var_a, var_b):
            yield Difference(index, sub, var_a.name, what, text_a, text_b)


def _differing(a: eds.Variable, b: eds.Variable
               ) -> Iterator[tuple[str, str | None, str | None]]:
    """(property, A's text, B's text) of each property in which the entries differ."""
    for what, text_a, text_b in (
            ("name", a.name, b.name),
            ("type", type_name(a.data_type), type_name(b.data_type)),
            ("access", a.access_type, b.access_type),
            ("PDO mapping", _yes(a.pdo_mapping), _yes(b.pdo_mapping))):
        if text_a != text_b:
            yield what, text_a, text_b
    for what, text_a, text_b, value_a, value_b in (
            ("default", a.default_value, b.default_value, a.default, b.default),
            ("value", a.parameter_value, b.parameter_value, a.value, b.value)):
        # equal values written differently (0x10 and 16) are no difference
        if text_a != text_b and (value_a is None or value_a != value_b):
            yield what, text_a, text_b


def _yes(flag: bool) -> str:
    return "yes" if flag else "no"


def diff_live(a: eds.ObjectDictionary, read: Callable[[int, int], bytes]
              ) -> list[Difference]:
    """The differences of a device's values from ``a``'s (ParameterValue, else
    DefaultValue, evaluated with ``a.node_id``): every readable entry with a value is read
    with ``read(index, sub)``, which returns the bytes or raises
    :class:`~canola.errors.SdoAbort`. An object or sub-index the device lacks is
    ``only in A``; another abort is a ``read`` difference. A time-out is raised."""
    out: list[Difference] = []
    for index in sorted(a.objects):
        obj = a.objects[index]
        for sub in sorted(obj.subs):
            found = _live_entry(obj.subs[sub], read, a.node_id)
            if found is None:
                continue
            out.append(found)
            if found.what == "only in A" and found.sub is None:
                break  # the device has no such object: one line for it
    return out


def _live_entry(var: eds.Variable, read: Callable[[int, int], bytes],
                node_id: int | None) -> Difference | None:
    code = var.data_type
    text = var.parameter_value if var.parameter_value is not None else var.default_value
    if (code not in DATA_TYPES or code == _DOMAIN or var.access_type == "wo"
            or text is None or text.strip() == ""):
        return None
    try:
        expected = wire(code, text, node_id)
    except (ValueError, UnicodeEncodeError):
        return None  # a value the file cannot give (eds check says why)
    try:
        data = read(var.index, var.subindex)
    except SdoAbort as exc:
        if exc.code == _TIMED_OUT:
            raise
        if exc.code in (_NO_OBJECT, _NO_SUB):
            sub = None if exc.code == _NO_OBJECT else var.subindex
            return Difference(var.index, sub, var.name, "only in A")
        return Difference(var.index, var.subindex, var.name, "read", _text(code, expected),
                          f"SDO abort 0x{exc.code:08X}: {exc.text}")
    same = (_text(code, expected) == _text(code, data) if code in _TEXTS
            else expected == data)
    if same:
        return None
    return Difference(var.index, var.subindex, var.name, "value", _text(code, expected),
                      _text(code, data))


def _text(code: int, data: bytes) -> str:
    """Wire bytes as the value's text (a number above 9 in hex too: COB-IDs, mappings);
    their hex when they are not of the type."""
    try:
        value = values.decode(code, data)
    except values.ValueFormatError:
        return data.hex()
    if isinstance(value, int) and not isinstance(value, bool) and value > 9:
        return f"{value} (0x{value:X})"
    return values.to_text(code, value)
