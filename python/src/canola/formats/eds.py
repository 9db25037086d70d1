# SPDX-License-Identifier: Apache-2.0
"""Read, check and write CiA 306 electronic data sheets (EDS) and device configuration files (DCF).

``parse(source, strict=False, node_id=None)`` builds an :class:`ObjectDictionary`;
``write(od, dcf=False)`` gives the file text back. Problems come in two kinds:

- a broken file (a line that is not ``[section]``, ``key=value`` or a ``;``/``#`` comment, a
  duplicate section, a sub-object section without its object, a number that the structure
  needs, such as ObjectType, DataType, CompactSubObj or an object-list entry, that cannot be
  read) raises :class:`~canola.errors.EdsError` naming file and line, in both modes;
- a deviation from CiA 306 that still leaves a usable model (missing mandatory keys, counts
  that do not match, unknown AccessType or DataType, values that are not numbers of their
  type or out of its range (a ``$NODEID`` value with the node-ID unknown: for node-ID 1 or
  127), limits out of range, a synthesised sub0, an empty file, a section named like an
  object whose index is beyond 0xFFFF or sub-index beyond 0xFF (kept as an other section),
  a SubNumber that is no UNSIGNED8, no 0x1000, 0x1001 or 0x1018, a PDO mapping that breaks
  CiA 301 (see :mod:`canola.formats._eds_pdo`), ...) is collected: ``strict=True`` raises one
  EdsError listing all of them, one per line; otherwise they are in ``od.warnings``.

Every problem is a :class:`~canola.errors.Diagnostic` (message, file, line, section, key),
so that a tool can print or sort them. Whatever the input and its size, :func:`parse`
ends in an ObjectDictionary or an EdsError: numbers longer than
:data:`~canola.formats.datatypes.MAX_LITERAL` characters are not numbers, and no count read from the
file drives a loop beyond the file's own size.

Accepted forms: section and key names in any case (``[1a00]``, ``[1018SUB1]``,
``parametername``), spaces around ``=`` and at line ends, CRLF/LF/CR, UTF-8 or Latin-1 text,
numbers in decimal, ``0x`` hex or leading-``0`` octal with an optional sign, ``$NODEID``
(any case) added to or subtracted from constants on either side. A ``;`` or ``#`` starts a
comment at the start of a line; after a *numeric* value or a keyword
(``DefaultValue=0x180 ; note``, ``DataType=0x0007 # UNSIGNED32``, ``AccessType=rw # read``)
and after a section header (``[1003sub1] # repeat``) it is dropped with a warning, while in
strings it is kept as text. A section that comes again is merged into the first (later
values win) with a warning, as tolerant INI readers (Python's configparser with
``strict=False``) do; ``strict=True`` refuses all of these like every other deviation.

Input is bounded: a path must name a regular file (a FIFO, a device such as ``/dev/zero``,
a folder is refused before a byte is read) of at most
:data:`~canola.files.EDS_MAX_BYTES` (64 MiB), and bytes or text given directly are held
to the same size; memory stays a small multiple of the file's size (duplicate keys are
counted, not kept, beyond a few per section).
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from enum import IntEnum
from pathlib import Path

from canola.errors import Diagnostic, EdsError
from canola.files import EDS_MAX_BYTES, FileError, read_file
from canola.formats._eds_pdo import mapping_problems
from canola.formats._ini import Entry, Section, decode, read_sections
from canola.formats.datatypes import (
    DATA_TYPES,
    INTEGER_TYPES,
    REAL_TYPES,
    NumberError,
    Value,
    fit_signed,
    parse_integer,
    parse_value,
)

__all__ = [
    "ACCESS_TYPES",
    "Object",
    "ObjectDictionary",
    "ObjectType",
    "SubObject",
    "Variable",
    "parse",
    "write",
]

ACCESS_TYPES = frozenset({"ro", "wo", "rw", "rwr", "rww", "const"})


class ObjectType(IntEnum):
    """Object codes of CiA 301 as written in ``ObjectType=``."""

    NULL = 0x0
    DOMAIN = 0x2
    DEFTYPE = 0x5
    DEFSTRUCT = 0x6
    VAR = 0x7
    ARRAY = 0x8
    RECORD = 0x9


_COMPOUND = (ObjectType.ARRAY, ObjectType.RECORD, ObjectType.DEFSTRUCT)


@dataclass
class Variable:
    """One value of the dictionary: a VAR object (sub-index 0) or a sub-object.

    ``default_value``/``low_limit``/``high_limit``/``parameter_value`` are the texts as
    written; ``default``/``low``/``high``/``value`` are those evaluated for the data type and
    the node-ID (None when empty, unreadable, or ``$NODEID`` with no node-ID known).
    """

    index: int
    subindex: int
    name: str
    data_type: int | None = None
    access_type: str | None = None
    default_value: str | None = None
    low_limit: str | None = None
    high_limit: str | None = None
    pdo_mapping: bool = False
    obj_flags: int | None = None
    parameter_value: str | None = None
    denotation: str | None = None
    default: Value | None = None
    low: Value | None = None
    high: Value | None = None
    value: Value | None = None
    extra: dict[str, str] = field(default_factory=dict)
    line: int | None = field(default=None, compare=False)


SubObject = Variable


@dataclass
class Object:
    """An object at one index. A VAR keeps its value as ``subs[0]``."""

    index: int
    name: str
    object_type: ObjectType
    subs: dict[int, Variable] = field(default_factory=dict)
    obj_flags: int | None = None
    extra: dict[str, str] = field(default_factory=dict)
    compact_sub_obj: int | None = field(default=None, compare=False)
    line: int | None = field(default=None, compare=False)


@dataclass
class ObjectDictionary:
    """The content of one EDS or DCF."""

    file_info: dict[str, str] = field(default_factory=dict)
    device_info: dict[str, str] = field(default_factory=dict)
    device_commissioning: dict[str, str] | None = None
    dummy_usage: dict[int, bool] = field(default_factory=dict)
    comments: list[str] = field(default_factory=list)
    objects: dict[int, Object] = field(default_factory=dict)
    other_sections: dict[str, dict[str, str]] = field(default_factory=dict)
    node_id: int | None = None
    listed: dict[str, list[int]] = field(default_factory=dict, compare=False)
    warnings: list[Diagnostic] = field(default_factory=list, compare=False)
    file: str = field(default="<string>", compare=False)

    def __getitem__(self, index: int) -> Object:
        return self.objects[index]

    def __contains__(self, index: object) -> bool:
        return index in self.objects


# ---------------------------------------------------------------------------------------
# parsing

_OBJECT = re.compile(r"([0-9a-f]{4})", re.IGNORECASE)
_SUB = re.compile(r"([0-9a-f]{4})sub0*([0-9a-f]{1,2})", re.IGNORECASE)
_COMPACT = re.compile(r"([0-9a-f]{4})(name|value|denotation)", re.IGNORECASE)
#: Any section named like an object ("1000", "1000sub1", "1000Name"): what the three
#: above do not take is a misnamed object section (see _misnamed).
_OBJECT_LIKE = re.compile(r"([0-9a-f]+)(?:sub([0-9a-f]*)|name|value|denotation)?",
                          re.IGNORECASE)
#: CiA 301 objects every device has: a device without them is refused when strict.
_REQUIRED = {0x1000: "Device type", 0x1001: "Error register", 0x1018: "Identity object"}
_LISTS = {"mandatoryobjects": "mandatory", "optionalobjects": "optional",
          "manufacturerobjects": "manufacturer"}
#: A comment after a number or keyword: from the first ``;`` or ``#`` on.
_TRAILING_COMMENT = re.compile(r"[;#].*", re.DOTALL)
_VAR_KEYS = ("parametername", "objecttype", "datatype", "accesstype", "defaultvalue",
             "lowlimit", "highlimit", "pdomapping", "objflags", "parametervalue", "denotation")
_COMPOUND_KEYS = ("parametername", "objecttype", "subnumber", "objflags", "compactsubobj")


class _Builder:
    def __init__(self, file: str, node_id: int | None) -> None:
        self.file = file
        self.node_id = node_id
        self.diags: list[Diagnostic] = []

    def warn(self, msg: str, sec: Section | None = None, ent: Entry | None = None,
             key: str | None = None) -> None:
        line = ent.line if ent is not None else (sec.line if sec is not None else None)
        self.diags.append(Diagnostic(msg, self.file, line, None if sec is None else sec.name,
                                     ent.key if ent is not None else key))

    def fail(self, msg: str, sec: Section, ent: Entry | None = None) -> EdsError:
        return EdsError(msg, file=self.file, line=ent.line if ent else sec.line,
                        section=sec.name, key=None if ent is None else ent.key)

    def number(self, sec: Section, key: str) -> int | None:
        """A structural integer: unreadable is fatal."""
        ent = sec.get(key)
        if ent is None:
            return None
        try:
            value = parse_integer(self._strip_comment(sec, ent), 0)
        except NumberError as exc:
            raise self.fail(f"not a number: {exc}", sec, ent) from None
        assert value is not None
        return value

    def _strip_comment(self, sec: Section, ent: Entry) -> str:
        """A number's or keyword's text without a ``;`` or ``#`` comment after it."""
        match = _TRAILING_COMMENT.search(ent.value)
        if match is None:
            return ent.value
        self.warn(f"'{match.group(0)[0]}' comment after a value", sec, ent)
        return ent.value[:match.start()].strip()

    def evaluate(self, sec: Section, ent: Entry | None, data_type: int | None,
                 node_id: int | None) -> Value | None:
        if ent is None:
            return None
        numeric = data_type in INTEGER_TYPES or data_type in REAL_TYPES
        text = self._strip_comment(sec, ent) if numeric else ent.value
        try:
            value = parse_value(text, data_type, node_id)
        except NumberError as exc:
            self.warn(f"not a number of type {DATA_TYPES[data_type or 0].name}: {exc}", sec, ent)
            return None
        if value is None and node_id is None and data_type in INTEGER_TYPES:
            # $NODEID with the node-ID unknown: the value must fit for every node-ID
            for some_id in (1, 127):
                if not self._in_range(parse_value(text, data_type, some_id), text, data_type,
                                      sec, ent, note=f" with node-ID {some_id}"):
                    break
        if isinstance(value, int) and data_type in INTEGER_TYPES:
            value = fit_signed(value, text, data_type)
            self._in_range(value, text, data_type, sec, ent)
        return value

    def _in_range(self, value: Value | None, text: str, data_type: int, sec: Section,
                  ent: Entry, *, note: str = "") -> bool:
        """Whether an integer ``value`` fits ``data_type``; a warning when it does not."""
        if not isinstance(value, int):
            return True
        value = fit_signed(value, text, data_type)
        info = DATA_TYPES[data_type]
        if info.min <= value <= info.max:
            return True
        self.warn(f"{value}{note} is outside the range of {info.name} "
                  f"[{info.min}, {info.max}]", sec, ent)
        return False

    def variable(self, sec: Section, index: int, sub: int, base: Section | None = None,
                 name: str | None = None) -> Variable:
        """Build a Variable from ``sec`` (and, for compact arrays, keys of ``base``)."""
        src = base or sec

        def ent(key: str) -> Entry | None:
            return src.get(key)

        if name is None:
            name_ent = sec.get("parametername")
            if name_ent is None:
                self.warn("missing ParameterName", sec, key="ParameterName")
            name = "" if name_ent is None else name_ent.value
        data_type = self.number(src, "datatype")
        if data_type is None:
            self.warn("missing DataType", src, key="DataType")
        elif data_type not in DATA_TYPES:
            self.warn(f"DataType 0x{data_type:04X} is not a known basic data type", src,
                      ent("datatype"))
        access_ent = ent("accesstype")
        access = None
        if access_ent is None:
            self.warn("missing AccessType", src, key="AccessType")
        else:
            access = self._strip_comment(src, access_ent).lower()
            if access not in ACCESS_TYPES:
                self.warn(f"unknown AccessType {access_ent.value!r}", src, access_ent)
        pdo = self.number(src, "pdomapping")
        if pdo not in (None, 0, 1):
            self.warn("PDOMapping must be 0 or 1", src, ent("pdomapping"))
        var = Variable(
            index=index, subindex=sub, name=name, data_type=data_type, access_type=access,
            default_value=_text(ent("defaultvalue")), low_limit=_text(ent("lowlimit")),
            high_limit=_text(ent("highlimit")), pdo_mapping=bool(pdo),
            obj_flags=self.number(src, "objflags"),
            parameter_value=_text(sec.get("parametervalue")),
            denotation=_text(sec.get("denotation")), line=sec.line)
        if base is None:
            var.extra = {e.key: e.value for k, e in sec.entries.items() if k not in _VAR_KEYS}
        self.evaluate_all(var, sec, src)
        return var

    def evaluate_all(self, var: Variable, sec: Section, src: Section) -> None:
        dt = var.data_type if var.data_type in DATA_TYPES else None
        var.default = self.evaluate(src, src.get("defaultvalue"), dt, self.node_id)
        var.low = self.evaluate(src, src.get("lowlimit"), dt, 0)
        var.high = self.evaluate(src, src.get("highlimit"), dt, 0)
        var.value = self.evaluate(sec, sec.get("parametervalue"), dt, self.node_id)
        lo, hi = var.low, var.high
        if isinstance(lo, int | float) and isinstance(hi, int | float) and lo > hi:
            self.warn(f"LowLimit {lo} is above HighLimit {hi}", src, src.get("lowlimit"))
        for val, key in ((var.default, "defaultvalue"), (var.value, "parametervalue")):
            if not isinstance(val, int | float):
                continue
            if (isinstance(lo, int | float) and val < lo) or (
                    isinstance(hi, int | float) and val > hi):
                where = src if key == "defaultvalue" else sec
                self.warn(f"{val} is outside LowLimit/HighLimit", where, where.get(key))


def _text(ent: Entry | None) -> str | None:
    return None if ent is None else ent.value


def _hex(text: str) -> int:
    return int(text, 16)


def _source(source: str | bytes | os.PathLike[str], name: str | None) -> tuple[str, str]:
    if isinstance(source, bytes | str) and len(source) > EDS_MAX_BYTES:
        raise EdsError(f"larger than {EDS_MAX_BYTES // (1024 * 1024)} MiB, the most canola "
                       "reads", file=name or f"<{type(source).__name__}>")
    if isinstance(source, bytes):
        return decode(source), name or "<bytes>"
    if isinstance(source, str) and (not source or "\n" in source or "=" in source
                                    or "[" in source):
        return source, name or "<string>"
    path = Path(source)
    try:
        data = read_file(path, EDS_MAX_BYTES)
    except FileError as exc:
        raise EdsError(exc.why, file=str(path)) from None
    return decode(data), name or str(path)


def parse(source: str | bytes | os.PathLike[str], *, strict: bool = False,
          node_id: int | None = None, filename: str | None = None) -> ObjectDictionary:
    """Read an EDS or DCF.

    ``source`` is a path (``os.PathLike``, or a non-empty ``str`` without newline, ``=`` or
    ``[``), the file's bytes, or its text. ``filename`` names text/bytes in messages. ``node_id``
    evaluates ``$NODEID``; when None, a DCF's ``[DeviceComissioning] NodeID`` is used.
    Raises EdsError (see the module doc) and never another exception for bad input.
    """
    text, file = _source(source, filename)
    sections = read_sections(text, file)
    return _build(sections, file, strict, node_id)


def _build(sections: list[Section], file: str, strict: bool,
           node_id: int | None) -> ObjectDictionary:
    od = ObjectDictionary(file=file)
    b = _Builder(file, node_id)
    if not sections:
        b.diags.append(Diagnostic("empty file: no sections, no objects", file, 1))
    objects: dict[int, Section] = {}
    subs: dict[int, dict[int, Section]] = {}
    compact: dict[tuple[int, str], Section] = {}
    lists: dict[str, Section] = {}
    for sec in sections:
        for line, note in sec.notes:
            b.diags.append(Diagnostic(note, file, line, sec.name))
        for dup in sec.duplicates:
            b.warn(f"duplicate key (line {dup.line} overridden)", sec,
                   sec.entries[dup.key.lower()])
        if sec.more_duplicates:
            b.warn(f"{sec.more_duplicates} more duplicate keys (later values win)", sec)
        low = sec.name.lower()
        if m := _OBJECT.fullmatch(sec.name):
            if _hex(m.group(1)) in objects:
                raise b.fail("duplicate object section", sec)
            objects[_hex(m.group(1))] = sec
        elif m := _SUB.fullmatch(sec.name):
            index, sub = _hex(m.group(1)), _hex(m.group(2))
            if sub in subs.setdefault(index, {}):
                raise b.fail("duplicate sub-object section", sec)
            subs[index][sub] = sec
        elif m := _COMPACT.fullmatch(sec.name):
            compact[(_hex(m.group(1)), m.group(2).lower())] = sec
        elif low == "fileinfo":
            od.file_info = _plain(sec)
        elif low == "deviceinfo":
            od.device_info = _plain(sec)
        elif low in ("devicecomissioning", "devicecommissioning"):
            if low == "devicecommissioning":
                b.warn("CiA 306 spells this section [DeviceComissioning]", sec)
            od.device_commissioning = _plain(sec)
        elif low == "dummyusage":
            _dummy_usage(b, od, sec)
        elif low == "comments":
            od.comments = _comments(b, sec)
        elif low in _LISTS:
            lists[_LISTS[low]] = sec
        else:
            if (why := _misnamed(sec.name)) is not None:
                b.warn(f"{why}: not an object, kept as an other section", sec)
            od.other_sections[sec.name] = _plain(sec)
    if node_id is None and od.device_commissioning is not None:
        raw = next((v for k, v in od.device_commissioning.items() if k.lower() == "nodeid"), "")
        try:
            node_id = parse_integer(raw, 0) if raw else None
        except NumberError:
            b.warn(f"NodeID {raw!r} is not a number", None)
    od.node_id = node_id
    b.node_id = node_id
    for index, sub_secs in subs.items():
        if index not in objects:
            first = min(sub_secs.values(), key=lambda s: s.line)
            raise b.fail(f"sub-object section without its object section [{index:04X}]", first)
    for index in sorted(objects):
        od.objects[index] = _object(b, index, objects[index], subs.get(index, {}), compact)
    for (index, kind), sec in compact.items():
        obj = od.objects.get(index)
        if obj is None or obj.compact_sub_obj is None:
            b.warn(f"[{index:04X}{kind.capitalize()}] belongs to no CompactSubObj object", sec)
    _check_lists(b, od, lists)
    b.diags += mapping_problems(od)
    for index, what in _REQUIRED.items():
        if index not in od.objects:
            where = lists.get("mandatory")
            b.diags.append(Diagnostic(f"no object 0x{index:04X} ({what}), which every "
                                      "CANopen device has", file,
                                      None if where is None else where.line,
                                      None if where is None else where.name))
    if strict and b.diags:
        raise EdsError(problems=b.diags)
    od.warnings = b.diags
    return od


def _misnamed(name: str) -> str | None:
    """Why a section named like an object is not one (None: it is not named like one)."""
    m = _OBJECT_LIKE.fullmatch(name)
    if m is None:
        return None
    digits, sub = m.group(1), m.group(2)
    if len(digits) != 4:
        index = int(digits[:9], 16) if len(digits) > 8 else int(digits, 16)
        beyond = " is beyond 0xFFFF" if index > 0xFFFF else " has not 4 hex digits"
        return f"index 0x{digits[:8].upper()}{'...' if len(digits) > 8 else ''}{beyond}"
    if sub is not None:
        if not sub:
            return "sub-index missing after 'sub'"
        shown = sub.lstrip("0")[:8].upper()
        return f"sub-index 0x{shown}{'...' if len(sub.lstrip('0')) > 8 else ''} is beyond 0xFF"
    return None


def _plain(sec: Section) -> dict[str, str]:
    return {e.key: e.value for e in sec.entries.values()}


def _dummy_usage(b: _Builder, od: ObjectDictionary, sec: Section) -> None:
    for ent in sec.entries.values():
        m = re.fullmatch(r"dummy([0-9a-f]{4})", ent.key, re.IGNORECASE)
        if m is None or ent.value not in ("0", "1"):
            b.warn("expected DummyXXXX=0 or 1", sec, ent)
            continue
        od.dummy_usage[_hex(m.group(1))] = ent.value == "1"


def _comments(b: _Builder, sec: Section) -> list[str]:
    count = b.number(sec, "lines") or 0
    extra = [e for k, e in sec.entries.items()
             if k != "lines" and not re.fullmatch(r"line[0-9]+", k)]
    numbered = sum(1 for k in sec.entries if re.fullmatch(r"line[0-9]+", k))
    # no more lines than the section has, whatever Lines says
    lines = [sec.value(f"line{i}") or "" for i in range(1, min(count, numbered) + 1)]
    if numbered != count or extra:
        b.warn(f"Lines={count} does not match the {numbered} LineN entries", sec, sec.get("lines"))
    return lines


def _object_type(b: _Builder, sec: Section, has_subs: bool) -> ObjectType:
    code = b.number(sec, "objecttype")
    if code is None:
        b.warn("missing ObjectType", sec, key="ObjectType")
        if sec.get("compactsubobj") is not None:
            return ObjectType.ARRAY
        return ObjectType.RECORD if has_subs or sec.get("subnumber") else ObjectType.VAR
    try:
        return ObjectType(code)
    except ValueError:
        raise b.fail(f"unknown ObjectType 0x{code:X}", sec, sec.get("objecttype")) from None


def _object(b: _Builder, index: int, sec: Section, sub_secs: dict[int, Section],
            compact: dict[tuple[int, str], Section]) -> Object:
    otype = _object_type(b, sec, bool(sub_secs))
    name_ent = sec.get("parametername")
    name = "" if name_ent is None else name_ent.value
    if otype not in _COMPOUND:
        if sub_secs:
            b.warn(f"{otype.name} object has sub-object sections (ignored)", sec)
        var = b.variable(sec, index, 0)
        return Object(index, var.name, otype, {0: var}, line=sec.line)
    if name_ent is None:
        b.warn("missing ParameterName", sec, key="ParameterName")
    obj = Object(index, name, otype, obj_flags=b.number(sec, "objflags"), line=sec.line)
    n_compact = b.number(sec, "compactsubobj")
    if n_compact:
        obj.compact_sub_obj = n_compact
        _expand_compact(b, obj, sec, n_compact, compact)
        keys: tuple[str, ...] = (*_COMPOUND_KEYS, *_VAR_KEYS)
    else:
        keys = _COMPOUND_KEYS
    obj.extra = {e.key: e.value for k, e in sec.entries.items() if k not in keys}
    for sub in sorted(sub_secs):
        obj.subs[sub] = b.variable(sub_secs[sub], index, sub)
    if 0 not in obj.subs:
        highest = max((s for s in obj.subs if s), default=0)
        b.warn(f"{otype.name} without sub0: synthesised (highest sub-index {highest})", sec)
        obj.subs[0] = Variable(index, 0, "Highest sub-index supported", 0x0005, "ro",
                               str(highest), default=highest, line=sec.line)
        obj.subs = dict(sorted(obj.subs.items()))
    declared = _sub_number(b, sec)
    if declared is not None and not n_compact and declared != len(sub_secs):
        b.warn(f"SubNumber={declared} but {len(sub_secs)} sub-object sections", sec,
               sec.get("subnumber"))
    return obj


def _sub_number(b: _Builder, sec: Section) -> int | None:
    """SubNumber, an UNSIGNED8: the sub-object sections make the structure, so a value
    that is no number, or out of range, is a warning (and ignored)."""
    ent = sec.get("subnumber")
    if ent is None:
        return None
    try:
        value = parse_integer(b._strip_comment(sec, ent), 0)
    except NumberError as exc:
        b.warn(f"not a number: {exc}", sec, ent)
        return None
    if value is None or not 0 <= value <= 0xFF:
        b.warn(f"SubNumber={value} is outside 0..255 (an UNSIGNED8)", sec, ent)
        return None
    return value


def _expand_compact(b: _Builder, obj: Object, sec: Section, count: int,
                    compact: dict[tuple[int, str], Section]) -> None:
    if obj.object_type != ObjectType.ARRAY:
        b.warn("CompactSubObj is only defined for ARRAY objects", sec, sec.get("compactsubobj"))
    if not 1 <= count <= 254:
        raise b.fail("CompactSubObj must be 1..254", sec, sec.get("compactsubobj"))
    lists = {kind: _numbered(b, compact.get((obj.index, kind)), count)
             for kind in ("name", "value", "denotation")}
    obj.subs[0] = Variable(obj.index, 0, "NrOfObjects", 0x0005, "ro", str(count),
                           default=count, line=sec.line)
    for sub in range(1, count + 1):
        name = lists["name"].get(sub, f"{obj.name}{sub}")
        var = b.variable(sec, obj.index, sub, base=sec, name=name)
        var.parameter_value = lists["value"].get(sub)
        var.denotation = lists["denotation"].get(sub)
        var.value = None
        if var.parameter_value is not None:
            pv_sec = compact[(obj.index, "value")]
            pv = pv_sec.get(str(sub))
            var.value = b.evaluate(pv_sec, pv, var.data_type if var.data_type in DATA_TYPES
                                   else None, b.node_id)
        obj.subs[sub] = var


def _numbered(b: _Builder, sec: Section | None, count: int) -> dict[int, str]:
    if sec is None:
        return {}
    result: dict[int, str] = {}
    for key, ent in sec.entries.items():
        if key == "nrofentries":
            continue
        try:
            sub = parse_integer(key, 0)
        except NumberError:
            b.warn("expected N=text", sec, ent)
            continue
        if sub is None or not 1 <= sub <= count:
            b.warn(f"sub-index {sub} outside 1..{count} of CompactSubObj", sec, ent)
            continue
        result[sub] = ent.value
    declared = b.number(sec, "nrofentries")
    if declared != len(result):
        b.warn(f"NrOfEntries={declared} but {len(result)} entries", sec, sec.get("nrofentries"))
    return result


def _check_lists(b: _Builder, od: ObjectDictionary, lists: dict[str, Section]) -> None:
    listed: dict[int, str] = {}
    for kind, sec in lists.items():
        count = b.number(sec, "supportedobjects")
        if count is None:
            b.warn("missing SupportedObjects", sec, key="SupportedObjects")
        entries: list[int] = []
        for key, ent in sec.entries.items():
            if key == "supportedobjects":
                continue
            if not key.isdigit():
                b.warn("unexpected key in an object list", sec, ent)
                continue
            index = b.number(sec, key)
            assert index is not None
            entries.append(index)
            if index in listed:
                b.warn(f"0x{index:04X} is listed twice", sec, ent)
            listed[index] = kind
            if index not in od.objects:
                b.warn(f"0x{index:04X} is listed but has no section", sec, ent)
        if count is not None and count != len(entries):
            b.warn(f"SupportedObjects={count} but {len(entries)} entries", sec,
                   sec.get("supportedobjects"))
        od.listed[kind] = entries
    for index, obj in od.objects.items():
        if index >= 0x1000 and index not in listed:
            b.diags.append(Diagnostic("object is not listed in [MandatoryObjects], "
                                      "[OptionalObjects] or [ManufacturerObjects]",
                                      b.file, obj.line, f"{index:04X}"))


# ---------------------------------------------------------------------------------------
# writing


def _list_kind(index: int) -> str:
    if index in (0x1000, 0x1001, 0x1018):
        return "mandatory"
    return "manufacturer" if 0x2000 <= index <= 0x5FFF else "optional"


def _section(out: list[str], name: str, pairs: Sequence[tuple[str, str | None]]) -> None:
    out.append(f"[{name}]")
    out.extend(f"{k}={v}" for k, v in pairs if v is not None)
    out.append("")


def _num(value: int | None, width: int = 1) -> str | None:
    if value is None:
        return None
    # A file may give a negative number ("0x00-7" evaluates to -7): keep it readable back.
    sign = "-" if value < 0 else ""
    return f"{sign}0x{abs(value):0{width}X}"


def _var_pairs(var: Variable, dcf: bool) -> list[tuple[str, str | None]]:
    pairs: list[tuple[str, str | None]] = [
        ("ParameterName", var.name),
        ("ObjectType", "0x7"),
        ("DataType", _num(var.data_type, 4)),
        ("AccessType", var.access_type),
        ("DefaultValue", var.default_value),
        ("LowLimit", var.low_limit),
        ("HighLimit", var.high_limit),
        ("PDOMapping", "1" if var.pdo_mapping else "0"),
        ("ObjFlags", _num(var.obj_flags)),
    ]
    if dcf:
        pairs += [("ParameterValue", var.parameter_value), ("Denotation", var.denotation)]
    return pairs + list(var.extra.items())


def write(od: ObjectDictionary, *, dcf: bool = False) -> str:
    """CiA 306 text for ``od``: an EDS, or with ``dcf=True`` a DCF (adds ParameterValue,
    Denotation and [DeviceComissioning]). Sections come in a fixed order, objects in index
    order, keys in a fixed order; compact arrays are written expanded. Lines end in CRLF.
    """
    out: list[str] = []
    _section(out, "FileInfo", list(od.file_info.items()))
    _section(out, "DeviceInfo", list(od.device_info.items()))
    if dcf and od.device_commissioning is not None:
        _section(out, "DeviceComissioning", list(od.device_commissioning.items()))
    if od.dummy_usage:
        _section(out, "DummyUsage", [(f"Dummy{i:04X}", str(int(used)))
                                     for i, used in sorted(od.dummy_usage.items())])
    if od.comments:
        _section(out, "Comments", [("Lines", str(len(od.comments)))]
                 + [(f"Line{i}", text) for i, text in enumerate(od.comments, start=1)])
    for kind, title in (("mandatory", "MandatoryObjects"), ("optional", "OptionalObjects"),
                        ("manufacturer", "ManufacturerObjects")):
        indices = [i for i in sorted(od.objects) if i >= 0x1000 and _list_kind(i) == kind]
        _section(out, title, [("SupportedObjects", str(len(indices)))]
                 + [(str(n), f"0x{i:04X}") for n, i in enumerate(indices, start=1)])
    for index in sorted(od.objects):
        obj = od.objects[index]
        if obj.object_type not in _COMPOUND:
            pairs = _var_pairs(obj.subs[0], dcf)
            pairs[1] = ("ObjectType", f"0x{int(obj.object_type):X}")
            _section(out, f"{index:04X}", pairs)
            continue
        _section(out, f"{index:04X}", [
            ("ParameterName", obj.name), ("ObjectType", f"0x{int(obj.object_type):X}"),
            ("SubNumber", f"0x{len(obj.subs):X}"), ("ObjFlags", _num(obj.obj_flags)),
            *obj.extra.items()])
        for sub in sorted(obj.subs):
            _section(out, f"{index:04X}sub{sub:X}", _var_pairs(obj.subs[sub], dcf))
    for name, entries in od.other_sections.items():
        _section(out, name, list(entries.items()))
    return "\r\n".join(out)
