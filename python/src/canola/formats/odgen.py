# SPDX-License-Identifier: Apache-2.0
"""Generate a C object dictionary (``co_od_t`` of ``canola/od.h``) from an EDS or DCF.

``generate(od, name)`` returns the text of ``<name>.h`` and ``<name>.c``; ``main()`` is the
command line (``python -m canola.odgen INPUT --name NAME --out-dir DIR``). The output is
reproducible: no timestamps, no absolute paths, entries in (index, sub-index) order, so the
same input gives the same bytes.

Layout of the generated code (chosen for firmware: the table lives in flash):

- ``<name>_values_t``: one member per entry, named after its ParameterName (lower case,
  ``[a-z0-9_]``, made unique; the index/sub-index is in a comment). ARRAY and RECORD objects
  become a nested struct whose members are their sub-indices, sub-index 0 included (a plain
  UNSIGNED8 entry as the EDS describes it). Members come the most aligned first (in index
  order among equals), in the struct and in each nested one, so that no padding lies
  between them (a nested struct keeps its tail padding up to its own alignment).
- ``<name>_values``: the one static instance that holds the RAM values, zero-initialised;
  ``<name>_od``: a const ``co_od_t`` whose const entry table points into it. Call
  ``co_od_reset(&<name>_od, 0x0000, 0xFFFF, node_id)`` once before use. One node per
  generated dictionary: generate again under another name for a second node in the same
  program.
- The ``.c`` file holds the tables in both forms of ``canola/od.h``, chosen by the core's
  ``CO_CONFIG_OD_COMPACT`` (the dictionary and the library must agree, as for every
  configuration value). The compact form (1), the smaller: 6-byte entries (index, the
  value's offset in ``<name>_values``, sub-index, a row of ``k_rows``: type, attributes, a
  side table position, the limits of a number or the capacity of a string or domain; each
  distinct row once), the power-on values as one
  byte image ``k_defaults`` (a record per entry whose value is not all zeros: a head byte of
  the entries skipped since the previous record and the length, then the bytes: a number's
  storage little-endian, an INTEGER24 sign-extended to its int32_t, the others' wire bytes; see
  ``co_od_tables_t.defaults``), the distinct limits once each in
  ``k_limits``, the distinct capacities once each in ``k_sizes``, all four in ``k_tables``
  (``co_od_tables_t``). The general form (0): 28-byte entries with pointers to
  the value, its power-on value in a const ``<name>_values_t``, its limits and hooks
  (NULL), and the dense key array ``k_keys``. Both share the look-up hash ``k_hash``, left
  out where the core does not read it (``CO_CONFIG_OD_HASH`` 0: by default the compact
  form).
- Power-on values come from ``ParameterValue`` when present (DCF), else ``DefaultValue``,
  else zero / empty. A value using ``$NODEID`` is stored without the node-ID and the entry
  gets ``CO_OD_NODEID``: ``co_od_reset`` adds the node-ID (``$NODEID+0x180`` -> 0x180).
- Storage widths follow ``od.h``: 24-bit integers in 32-bit, 40..56-bit in 64-bit, BOOLEAN
  in a ``uint8_t``, TIME_OF_DAY/TIME_DIFFERENCE in 6 raw bytes (the value as a 48-bit
  little-endian number).
- VISIBLE_STRING capacity is the default's length in UTF-8 plus one (at least
  ``min_string_size``): the EDS gives no capacity, so a longer string needs
  ``--min-string-size`` (or a hand edit of the EDS default);
  OCTET_STRING the default's bytes (hex digits, optionally space-separated; at least 1 and
  ``min_string_size``); UNICODE_STRING the default in UTF-16LE plus a terminating code unit.
- DOMAIN entries need storage the EDS does not size: with ``domain_size`` 0 (the default)
  they are left out of the table and listed in a comment (the application serves them, e.g.
  with a dictionary of its own or by generating with a size); with ``domain_size`` N they get
  a static N-byte buffer and a ``co_od_domain_t`` (empty at power-on; DefaultValue ignored).
- Limits: LowLimit/HighLimit of numeric entries (a missing side is the type's bound) in a
  ``co_od_limits_t`` using ``.i`` (signed), ``.u`` (unsigned, BOOLEAN) or ``.f`` (REAL).
- Attributes: AccessType ro/wo/rw/rwr/rww/const -> CO_OD_RO/WO/RW/RWR/RWW/CO; PDOMapping=1
  adds CO_OD_TPDO when readable (ro, const, rwr, rw) and CO_OD_RPDO when writable (wo, rww,
  rw).
- DEFTYPE/DEFSTRUCT/NULL objects (data type definitions) are not part of the table.
- The ``.c`` file refuses with ``#error`` a configuration whose node would refuse the
  dictionary at start (``co_node_init``: CO_ERR_CONFIG): more heartbeat consumer entries
  (0x1016) than ``CO_HB_CONSUMERS_MAX``, where the consumer is built.
- For a core that does not validate its dictionary (``CO_CONFIG_OD_VALIDATE`` 0), the
  ``.c`` file refuses with ``#error`` the features it uses that the core leaves out
  (limits, REAL limits, DOMAIN values in RAM, UNICODE_STRING, types wider than 32 bits),
  which co_od_validate would otherwise refuse at run time.

Anything the core cannot hold (a DataType it lacks, a value that is not a number of its
type or does not fit, a missing AccessType) raises :class:`~canola.errors.EdsError` naming
file, line and section.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import struct
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from canola.errors import Diagnostic, EdsError
from canola.files import write_file
from canola.formats import eds
from canola.formats.datatypes import DATA_TYPES, NumberError, fit_signed, parse_value

# The co_od_entry_t layout this generator writes (canola/od.h: CO_OD_FORMAT).
OD_FORMAT = 7  # 2: co_od_t.keys; 3: co_od_t.hash; 4: the compact form (CO_CONFIG_OD_COMPACT);
# 5: its 8-byte entries (value offsets, co_od_tables_t); 6: numbers in its image as their
# storage's bytes; 7: its 6-byte entries (co_od_t.rows)

__all__ = ["GenerateOptions", "build_parser", "check_usable", "generate", "generate_files", "main",
           "refusals"]

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_NODEID = re.compile(r"\$nodeid", re.IGNORECASE)
_C_KEYWORDS = frozenset({
    "auto", "break", "case", "char", "const", "continue", "default", "do", "double", "else",
    "enum", "extern", "float", "for", "goto", "if", "inline", "int", "long", "register",
    "restrict", "return", "short", "signed", "sizeof", "static", "struct", "switch", "typedef",
    "union", "unsigned", "void", "volatile", "while", "bool", "true", "false"})

# type code -> (C enum name, wire size (0: variable), C storage type, kind)
_BOOL, _SIGNED, _UNSIGNED, _REAL, _VSTRING, _OSTRING, _USTRING, _RAW, _DOMAIN = range(9)
_TYPES: dict[int, tuple[str, int, str, int]] = {
    0x01: ("BOOLEAN", 1, "uint8_t", _BOOL),
    0x02: ("INTEGER8", 1, "int8_t", _SIGNED),
    0x03: ("INTEGER16", 2, "int16_t", _SIGNED),
    0x04: ("INTEGER32", 4, "int32_t", _SIGNED),
    0x05: ("UNSIGNED8", 1, "uint8_t", _UNSIGNED),
    0x06: ("UNSIGNED16", 2, "uint16_t", _UNSIGNED),
    0x07: ("UNSIGNED32", 4, "uint32_t", _UNSIGNED),
    0x08: ("REAL32", 4, "float", _REAL),
    0x09: ("VISIBLE_STRING", 0, "char", _VSTRING),
    0x0A: ("OCTET_STRING", 0, "uint8_t", _OSTRING),
    0x0B: ("UNICODE_STRING", 0, "uint8_t", _USTRING),
    0x0C: ("TIME_OF_DAY", 6, "uint8_t", _RAW),
    0x0D: ("TIME_DIFFERENCE", 6, "uint8_t", _RAW),
    0x0F: ("DOMAIN", 0, "co_od_domain_t", _DOMAIN),
    0x10: ("INTEGER24", 3, "int32_t", _SIGNED),
    0x11: ("REAL64", 8, "double", _REAL),
    0x12: ("INTEGER40", 5, "int64_t", _SIGNED),
    0x13: ("INTEGER48", 6, "int64_t", _SIGNED),
    0x14: ("INTEGER56", 7, "int64_t", _SIGNED),
    0x15: ("INTEGER64", 8, "int64_t", _SIGNED),
    0x16: ("UNSIGNED24", 3, "uint32_t", _UNSIGNED),
    0x18: ("UNSIGNED40", 5, "uint64_t", _UNSIGNED),
    0x19: ("UNSIGNED48", 6, "uint64_t", _UNSIGNED),
    0x1A: ("UNSIGNED56", 7, "uint64_t", _UNSIGNED),
    0x1B: ("UNSIGNED64", 8, "uint64_t", _UNSIGNED),
}
# bytes of a number's native storage (canola/od.h)
_STORAGE_BYTES = {"uint8_t": 1, "int8_t": 1, "int16_t": 2, "uint16_t": 2, "int32_t": 4,
                  "uint32_t": 4, "int64_t": 8, "uint64_t": 8}
_ATTR = {"ro": "CO_OD_RO", "wo": "CO_OD_WO", "rw": "CO_OD_RW", "rwr": "CO_OD_RWR",
         "rww": "CO_OD_RWW", "const": "CO_OD_CO"}
_READABLE = frozenset({"ro", "const", "rwr", "rw"})
_WRITABLE = frozenset({"wo", "rww", "rw"})
_TABLE_OBJECTS = (eds.ObjectType.VAR, eds.ObjectType.DOMAIN, eds.ObjectType.ARRAY,
                  eds.ObjectType.RECORD)


@dataclass(frozen=True)
class GenerateOptions:
    """Choices the EDS does not make (see the module doc)."""

    domain_size: int = 0
    min_string_size: int = 0
    node_id: int | None = None


@dataclass
class _Entry:
    var: eds.Variable
    member: str  # C path below <name>_values, e.g. "identity.vendor_id"
    ctype: str
    array: int  # array length of the storage, 0 for a scalar
    size: int
    attr: str
    init: str | None  # C initializer of the default, None for none
    limits: str | None
    kind: int
    # the power-on value's bytes in the compact form's image (a number's storage, little-endian;
    # the wire bytes of the others), trailing zeros left out
    default: bytes = b""


# ---------------------------------------------------------------------------------------
# names and literals


def _ident(text: str, fallback: str) -> str:
    name = re.sub(r"[^a-z0-9]+", "_", text.lower()).strip("_")[:48].rstrip("_")
    if not name:
        name = fallback
    if name[0].isdigit():
        name = "n" + name
    if name in _C_KEYWORDS:
        name += "_"
    return name


def _unique(name: str, used: set[str], suffix: str) -> str:
    candidate = name
    n = 1
    while candidate in used:
        candidate = f"{name}_{suffix}" if n == 1 else f"{name}_{suffix}_{n}"
        n += 1
    used.add(candidate)
    return candidate


def _comment(text: str) -> str:
    """Text safe inside a /* */ comment: printable ASCII, no comment end, no trigraphs."""
    out = "".join(c if " " <= c <= "~" else "?" for c in text)
    return out.replace("*/", "*_/").replace("/*", "/_*").replace("??", "?_?")


def _c_string(data: bytes) -> str:
    out = []
    for b in data:
        c = chr(b)
        if c in "\"\\?":
            out.append("\\" + c)
        elif " " <= c <= "~":
            out.append(c)
        else:
            out.append(f"\\{b:03o}")
    return '"' + "".join(out) + '"'


def _bytes_init(data: bytes) -> str:
    return "{" + ", ".join(f"0x{b:02X}u" for b in data) + "}"


def _int_literal(value: int, kind: int) -> str:
    if kind == _SIGNED:
        if value == -(1 << 63):
            return "INT64_MIN"
        if value == -(1 << 31):
            return "(-2147483647 - 1)"
        return str(value)
    return f"0x{value:X}u" if value > 9 else f"{value}u"


def _real_literal(value: float, wire: int) -> str:
    text = repr(float(value))
    return text + ("f" if wire == 4 else "")


# ---------------------------------------------------------------------------------------
# values


class _Gen:
    def __init__(self, od: eds.ObjectDictionary, opts: GenerateOptions) -> None:
        self.od = od
        self.opts = opts

    def fail(self, var: eds.Variable, msg: str, key: str | None = None) -> EdsError:
        section = f"{var.index:04X}"
        obj = self.od.objects.get(var.index)
        compound = obj is not None and obj.object_type not in (eds.ObjectType.VAR,
                                                               eds.ObjectType.DOMAIN)
        if compound and obj is not None and obj.compact_sub_obj is None:
            section += f"sub{var.subindex:X}"
        return EdsError(msg, file=self.od.file, line=var.line, section=section, key=key)

    def value_text(self, var: eds.Variable) -> tuple[str, str]:
        if var.parameter_value is not None and var.parameter_value.strip():
            return var.parameter_value, "ParameterValue"
        return var.default_value or "", "DefaultValue"

    def number(self, var: eds.Variable, text: str, key: str, kind: int,
               node_ok: bool) -> tuple[int | float, bool]:
        """Evaluate a numeric text (without the node-ID); returns (value, uses $NODEID)."""
        assert var.data_type is not None
        text = text.partition(";")[0].strip()
        uses_node = bool(_NODEID.search(text))
        if uses_node and not node_ok:
            raise self.fail(var, f"$NODEID is not supported in {key} of this type", key)
        info = DATA_TYPES[var.data_type]
        try:
            value = parse_value(text, var.data_type, 0)
        except NumberError as exc:
            raise self.fail(var, f"not a number of type {info.name}: {exc}", key) from None
        if value is None:
            return 0, False
        assert not isinstance(value, str)
        if kind == _REAL:
            value = float(value)
            limit = 3.4028234663852886e38 if var.data_type == 0x08 else sys.float_info.max
            if not math.isfinite(value) or abs(value) > limit:
                raise self.fail(var, f"{text!r} is not a finite {info.name}", key)
            return value, uses_node
        assert isinstance(value, int)
        value = fit_signed(value, text, var.data_type)
        if not info.min <= value <= info.max:
            raise self.fail(var, f"{text!r} is outside the range of {info.name} "
                            f"[{info.min}, {info.max}]", key)
        return value, uses_node

    def entry(self, var: eds.Variable, member: str) -> _Entry | None:
        if var.data_type is None:
            raise self.fail(var, "missing DataType", "DataType")
        if var.data_type not in _TYPES:
            raise self.fail(var, f"DataType 0x{var.data_type:04X} is not supported by the "
                            "canola core", "DataType")
        if var.access_type not in _ATTR:
            what = "missing" if var.access_type is None else f"unknown ({var.access_type!r})"
            raise self.fail(var, f"AccessType {what}", "AccessType")
        _, wire, ctype, kind = _TYPES[var.data_type]
        access = var.access_type
        attr = [_ATTR[access]]
        if var.pdo_mapping and access in _READABLE:
            attr.append("CO_OD_TPDO")
        if var.pdo_mapping and access in _WRITABLE:
            attr.append("CO_OD_RPDO")
        text, key = self.value_text(var)
        init: str | None
        limits = None
        array = 0
        size = wire
        data = b""  # the power-on value's bytes in the image (Entry.default)
        if kind in (_BOOL, _SIGNED, _UNSIGNED, _REAL):
            value, uses_node = self.number(var, text, key, kind, kind != _REAL)
            if uses_node:
                attr.append("CO_OD_NODEID")
            if kind == _REAL:
                init = _real_literal(value, wire)
                data = struct.pack("<f" if wire == 4 else "<d", float(value))
            else:
                assert isinstance(value, int)
                init = _int_literal(value, kind)
                # the storage's little-endian bytes (an INTEGER24 as its int32_t: sign-extended)
                width = _STORAGE_BYTES[ctype]
                data = (value & ((1 << (8 * width)) - 1)).to_bytes(width, "little")
            limits = self.limits(var, kind, wire)
        elif kind == _RAW:
            value, _ = self.number_raw(var, text, key)
            array = size = 6
            data = value.to_bytes(6, "little")
            init = _bytes_init(data)
        elif kind == _VSTRING:
            data = self.encode(var, text, key)
            array = size = max(len(data) + 1, 1, self.opts.min_string_size)
            init = _c_string(data)
        elif kind == _OSTRING:
            data = self.octets(var, text, key)
            array = size = max(len(data), 1, self.opts.min_string_size)
            init = _bytes_init(data) if data else None
        elif kind == _USTRING:
            data = text.encode("utf-16-le")
            need = len(data) + 2
            need = max(need, self.opts.min_string_size)
            array = size = need + need % 2
            init = _bytes_init(data) if data else None
        else:  # DOMAIN
            if self.opts.domain_size <= 0:
                return None
            size = self.opts.domain_size
            init = None
        if kind in (_OSTRING, _USTRING) and init is None:
            init = "{0}"
        return _Entry(var, member, ctype, array, size, " | ".join(attr), init, limits, kind,
                      data.rstrip(b"\0"))

    def number_raw(self, var: eds.Variable, text: str, key: str) -> tuple[int, bool]:
        text = text.partition(";")[0].strip()
        if not text:
            return 0, False
        try:
            value = parse_value(text, 0x1B, 0)  # as a plain unsigned number
        except NumberError as exc:
            raise self.fail(var, f"not a number: {exc}", key) from None
        if not isinstance(value, int) or not 0 <= value < 1 << 48 or _NODEID.search(text):
            raise self.fail(var, f"{text!r} does not fit 6 bytes", key)
        return value, False

    def encode(self, var: eds.Variable, text: str, key: str) -> bytes:
        del var, key  # every text has a UTF-8 form
        return text.encode("utf-8")

    def octets(self, var: eds.Variable, text: str, key: str) -> bytes:
        digits = re.sub(r"\s+", "", text)
        if digits.lower().startswith("0x"):
            digits = digits[2:]
        if len(digits) % 2 or not re.fullmatch(r"[0-9A-Fa-f]*", digits):
            raise self.fail(var, f"OCTET_STRING {text!r} is not pairs of hex digits", key)
        return bytes.fromhex(digits)

    def limits(self, var: eds.Variable, kind: int, wire: int) -> str | None:
        if not (var.low_limit or "").strip() and not (var.high_limit or "").strip():
            return None
        assert var.data_type is not None
        info = DATA_TYPES[var.data_type]
        sides = []
        for text, key, bound in ((var.low_limit, "LowLimit", 0), (var.high_limit, "HighLimit",
                                                                   1)):
            if text is not None and text.strip():
                value, _ = self.number(var, text, key, kind, True)
            elif kind == _REAL:
                value = 0.0
            else:
                value = (info.min, info.max)[bound]
            if kind == _REAL:
                if text is None or not text.strip():
                    lit = ("-FLT_MAX", "FLT_MAX") if wire == 4 else ("-DBL_MAX", "DBL_MAX")
                    sides.append(f".f = {lit[bound]}")
                else:
                    sides.append(f".f = {_real_literal(value, 8)}")
            elif kind == _SIGNED:
                assert isinstance(value, int)
                sides.append(f".i = {_int_literal(value, _SIGNED)}")
            else:
                assert isinstance(value, int)
                sides.append(f".u = {_int_literal(value, _UNSIGNED)}")
        return f"{{.low = {{{sides[0]}}}, .high = {{{sides[1]}}}}}"


# ---------------------------------------------------------------------------------------
# what is refused


def refusals(od: eds.ObjectDictionary,
             options: GenerateOptions | None = None) -> list[Diagnostic]:
    """Every reason why canola cannot build a dictionary of ``od``: the one decision behind
    :func:`generate` (odgen), :meth:`canola.core.Od.from_eds` (``canola.Device``,
    ``canola device``) and the errors of ``canola eds check``. Empty: it can."""
    gen = _Gen(od, options or GenerateOptions())
    found: list[Diagnostic] = []
    entries = 0
    for index in sorted(od.objects):
        obj = od.objects[index]
        if obj.object_type not in _TABLE_OBJECTS:
            continue
        for var in obj.subs.values():
            entries += 1
            try:
                gen.entry(var, "member")
            except EdsError as exc:
                found.extend(exc.problems)
    if not entries:
        found.append(Diagnostic("no objects: a device needs at least its mandatory entries "
                                "(0x1000, 0x1001, 0x1018)", od.file))
    return found


def check_usable(od: eds.ObjectDictionary, options: GenerateOptions | None = None) -> None:
    """Raise :class:`~canola.errors.EdsError` listing :func:`refusals`, if there are any."""
    found = refusals(od, options)
    if found:
        raise EdsError(problems=found)


# ---------------------------------------------------------------------------------------
# output


def generate(od: eds.ObjectDictionary, name: str,
             options: GenerateOptions | None = None) -> tuple[str, str]:
    """Return the text of ``<name>.h`` and ``<name>.c`` for ``od``. Raises EdsError."""
    if not _NAME.fullmatch(name):
        raise ValueError(f"{name!r} is not a C identifier")
    opts = options or GenerateOptions()
    check_usable(od, opts)
    gen = _Gen(od, opts)
    source = Path(od.file).name
    entries: list[_Entry] = []
    skipped: list[eds.Variable] = []
    members: list[tuple[int, list[str]]] = []  # (alignment, lines) of each top-level member
    used: set[str] = set()
    for index in sorted(od.objects):
        obj = od.objects[index]
        if obj.object_type not in _TABLE_OBJECTS or not obj.subs:
            continue
        obj_name = _unique(_ident(obj.name, f"obj_{index:04x}"), used, f"{index:04x}")
        compound = obj.object_type in (eds.ObjectType.ARRAY, eds.ObjectType.RECORD)
        if not compound:
            var = next(iter(obj.subs.values()))
            e = gen.entry(var, obj_name)
            if e is None:
                skipped.append(var)
                used.discard(obj_name)
                continue
            entries.append(e)
            members.append((_ALIGN[e.ctype],
                            [_member(e, obj_name, "    ", f"0x{index:04X}", obj.name)]))
            continue
        inner: list[tuple[int, list[str]]] = []
        sub_used: set[str] = set()
        for sub in sorted(obj.subs):
            var = obj.subs[sub]
            member = _unique(_ident(var.name, f"sub{sub}"), sub_used, str(sub))
            e = gen.entry(var, f"{obj_name}.{member}")
            if e is None:
                skipped.append(var)
                continue
            entries.append(e)
            inner.append((_ALIGN[e.ctype], [_member(e, member, "        ",
                                                    f"0x{index:04X} sub {sub}", var.name)]))
        if not inner:
            used.discard(obj_name)
            continue
        members.append((max(align for align, _ in inner),
                        ["    struct {", *_by_alignment(inner),
                         f"    }} {obj_name}; /* 0x{index:04X} {_comment(obj.name)} */"]))
    struct = _by_alignment(members)
    node_id = opts.node_id if opts.node_id is not None else od.node_id
    return (_header(name, source, struct, skipped, node_id),
            _source_text(name, source, entries, skipped))


# Alignment of each storage type (at most: a co_od_domain_t holds a pointer), which orders
# the values struct's members so that the compiler pads none of them.
_ALIGN = {"uint8_t": 1, "int8_t": 1, "char": 1, "uint16_t": 2, "int16_t": 2, "uint32_t": 4,
          "int32_t": 4, "float": 4, "int64_t": 8, "uint64_t": 8, "double": 8,
          "co_od_domain_t": 8}


def _by_alignment(members: list[tuple[int, list[str]]]) -> list[str]:
    """The members' lines, the most aligned first (in EDS order among equals): no padding
    between them (a struct keeps only the tail padding up to its own alignment)."""
    ordered = sorted(members, key=lambda m: -m[0])
    return [line for _, lines in ordered for line in lines]


def _member(e: _Entry, member: str, indent: str, where: str, title: str) -> str:
    decl = f"{e.ctype} {member}" + (f"[{e.array}]" if e.array else "")
    tname = _TYPES[e.var.data_type or 0][0]
    return f"{indent}{decl}; /* {where} {tname}: {_comment(title)} */"


def _skipped_note(skipped: Sequence[eds.Variable]) -> list[str]:
    if not skipped:
        return []
    lines = [" * DOMAIN entries left out (generated with --domain-size 0); the application",
             " * must serve them itself:"]
    lines += [f" *   0x{v.index:04X} sub {v.subindex}: {_comment(v.name)}" for v in skipped]
    return lines


def _header(name: str, source: str, struct: list[str], skipped: Sequence[eds.Variable],
            node_id: int | None) -> str:
    guard = name.upper() + "_H"
    if not struct:
        struct = ["    uint8_t unused; /* the dictionary has no entries */"]
    node_line = (f"#define {name.upper()}_NODE_ID {node_id}u /* node-ID of the DCF or "
                 "--node-id: pass it to co_od_reset() */" if node_id is not None else
                 f"/* No node-ID given: pass yours to co_od_reset(&{name}_od, ...). */")
    out = [
        f"/* {name}.h -- object dictionary generated by canola.odgen from {_comment(source)}.",
        " * Do not edit: regenerate from the EDS instead.",
        " *",
        f" * {name}_values holds every value in RAM (one static instance: one node per",
        f" * generated dictionary); {name}_od is a const table (it can live in flash) whose",
        f" * entries point into {name}_values, in either form of canola/od.h (the core's",
        " * CO_CONFIG_OD_COMPACT chooses; the compact one is the smaller). The values start",
        f" * at zero: call co_od_reset(&{name}_od, 0x0000, 0xFFFF, node_id) once before use;",
        " * entries whose EDS default uses $NODEID (CO_OD_NODEID) get the node-ID added then.",
        *_skipped_note(skipped),
        " */",
        f"#ifndef {guard}",
        f"#define {guard}",
        "",
        '#include "canola/od.h"',
        "",
        f"#if !defined(CO_OD_FORMAT) || CO_OD_FORMAT != {OD_FORMAT}",
        f'#error "{name}.h was generated for object dictionary format {OD_FORMAT}: '
        'regenerate it with the odgen of this canola"',
        "#endif",
        "",
        "#ifdef __cplusplus",
        'extern "C" {',
        "#endif",
        "",
        node_line,
        "",
        "/** Every value of the dictionary, in native form (see canola/od.h). */",
        f"typedef struct {name}_values {{",
        *struct,
        f"}} {name}_values_t;",
        "",
        "/** The values of the node, in RAM. */",
        f"extern {name}_values_t {name}_values;",
        "",
        "/** The dictionary: a const table of entries sorted by index and sub-index. */",
        f"extern const co_od_t {name}_od;",
        "",
        "#ifdef __cplusplus",
        "}",
        "#endif",
        f"#endif /* {guard} */",
        "",
    ]
    return "\n".join(out)


def _source_text(name: str, source: str, entries: list[_Entry],
                 skipped: Sequence[eds.Variable]) -> str:
    out = [
        f"/* {name}.c -- object dictionary generated by canola.odgen from {_comment(source)}.",
        f" * Do not edit: regenerate from the EDS instead. See {name}.h.",
        *_skipped_note(skipped),
        " */",
        f'#include "{name}.h"',
        "",
        "#include <stddef.h>",
    ]
    if any(e.limits and "_MAX}" in e.limits for e in entries):
        out.append("")
        out.append("#include <float.h>")
    out.append("")
    domains = [e for e in entries if e.kind == _DOMAIN]
    for e in domains:
        out.append(f"static uint8_t k_domain_{e.var.index:04x}_{e.var.subindex:02x}[{e.size}];")
    if domains:
        out.append("")
    if domains:
        out.append(f"{name}_values_t {name}_values = {{")
        out += [f"    .{e.member} = {{.data = k_domain_{e.var.index:04x}_{e.var.subindex:02x}, "
                ".len = 0},"
                for e in domains]
        out.append("};")
    else:
        out.append(f"{name}_values_t {name}_values;")
    out.append("")
    if not entries:
        out.append(f"const co_od_t {name}_od = {{.entries = NULL, .count = 0, .hook_ctx = NULL}};")
        out.append("")
        return "\n".join(out)
    out += _feature_guards(entries)
    out += _start_guards(entries)
    out.append("#if CO_CONFIG_OD_COMPACT /* canola/config.h: the compact form (canola/od.h) */")
    out += _compact_tables(name, entries)
    out.append("#else /* the general form */")
    out += _general_tables(name, entries)
    out.append("#endif")
    out.append("")
    # The look-up's hash, left out where the core does not read it (CO_CONFIG_OD_HASH 0: by
    # default the compact form): entry position + 1 per slot, 0 = empty; the same in both
    # forms.
    slots = _hash_table([(e.var.index << 8) | e.var.subindex for e in entries])
    if slots:
        out.append("#if CO_CONFIG_OD_HASH /* canola/config.h: 0 where the core does not read it */")
        out.append(f"static const uint16_t k_hash[{len(slots)}] = {{")
        for i in range(0, len(slots), 16):
            out.append("    " + ", ".join(str(v) for v in slots[i:i + 16]) + ",")
        out.append("};")
        out.append("#endif")
        out.append("")
    out.append(f"const co_od_t {name}_od = {{.entries = k_entries, .count = {len(entries)}u, "
               ".hook_ctx = NULL,")
    out.append("#if CO_CONFIG_OD_COMPACT")
    rows = len(_rows(entries)[0])
    out.append(f"    .values = &{name}_values, .rows = k_rows, .rows_count = {rows}u, "
               ".tables = &k_tables,")
    out.append("#endif")
    out.append("#if !CO_CONFIG_OD_COMPACT")
    out.append("    .keys = k_keys,")
    out.append("#endif")
    out.append("#if CO_CONFIG_OD_HASH")
    if slots:
        out.append(f"    .hash = k_hash, .hash_mask = {len(slots) - 1}u")
    out.append("#endif")
    out.append("};")
    out.append("")
    return "\n".join(out)


def _feature_guards(entries: list[_Entry]) -> list[str]:
    """Compile-time refusal of the features the dictionary uses and the core may leave out,
    for a core that does not validate its dictionary (CO_CONFIG_OD_VALIDATE 0), where
    co_od_validate would not refuse it at run time."""
    kinds = {_TYPES[e.var.data_type or 0][3] for e in entries}
    wide = any(_TYPES[e.var.data_type or 0][2] in ("int64_t", "uint64_t", "double")
               for e in entries)
    real_limits = any(e.limits and _TYPES[e.var.data_type or 0][3] == _REAL for e in entries)
    used = [(any(e.limits for e in entries), "CO_CONFIG_OD_LIMITS", "limits"),
            (real_limits, "CO_CONFIG_REAL_LIMITS", "limits on REAL entries"),
            (_DOMAIN in kinds, "CO_CONFIG_OD_DOMAIN", "DOMAIN values in RAM"),
            (_USTRING in kinds, "CO_CONFIG_OD_UNICODE", "UNICODE_STRING entries"),
            (wide, "CO_CONFIG_OD_64BIT", "types wider than 32 bits")]
    out = ["#if !CO_CONFIG_OD_VALIDATE /* canola/config.h: co_od_validate would not refuse "
           "it */"]
    for uses, switch, what in used:
        if uses:
            out += [f"#if !{switch}",
                    f'#error "this dictionary has {what}: the core leaves them out ({switch} 0)"',
                    "#endif"]
    return [*out, "#endif", ""] if len(out) > 1 else []


def _start_guards(entries: list[_Entry]) -> list[str]:
    """Compile-time refusal of a configuration that co_node_init would refuse with this
    dictionary (CO_ERR_CONFIG): more heartbeat consumer entries (0x1016 sub 1, 2, ... in a
    row, as the node binds them) than CO_HB_CONSUMERS_MAX holds, where the consumer is built
    (CO_HB_CONSUMERS_MAX > 0; without it 0x1016 is a plain entry)."""
    subs = {e.var.subindex for e in entries if e.var.index == 0x1016}
    consumers = 0
    while consumers + 1 in subs:
        consumers += 1
    if consumers == 0:
        return []
    return [f"#if CO_HB_CONSUMERS_MAX > 0 && CO_HB_CONSUMERS_MAX < {consumers}",
            f'#error "0x1016 has {consumers} heartbeat consumer entries: CO_HB_CONSUMERS_MAX '
            f'is smaller, so co_node_init would refuse this dictionary (CO_ERR_CONFIG)"',
            "#endif", ""]


def _distinct_limits(entries: list[_Entry]) -> list[str]:
    """The different limits of the entries, in the order of their first entry."""
    return list(dict.fromkeys(e.limits for e in entries if e.limits))


def _distinct_sizes(entries: list[_Entry]) -> list[int]:
    """The different capacities of the strings and domains, in the order of their first
    entry."""
    return list(dict.fromkeys(e.size for e in entries if _TYPES[e.var.data_type or 0][1] == 0))


def _record(skip: int, pos: int, value: bytes) -> list[int]:
    """One record of the power-on values' image (canola/od.h, co_od_tables_t.defaults): the
    head (bits 0-4 the entries skipped since the previous record, 31: the position follows;
    bits 5-7 the length, 7: the length follows), the position and length if they follow,
    the value."""
    n = len(value)
    head = (skip if skip < 31 else 31) | (n if n < 7 else 7) << 5
    out = [head]
    if skip >= 31:
        out += [pos & 0xFF, pos >> 8]
    if n >= 7:
        out += [n & 0xFF, n >> 8]
    return out + list(value)


def _side_table(what: str, declaration: str, items: list[str]) -> list[str]:
    """One side table of the compact form (co_od_tables_t), whose positions the entries' one
    byte can name: 255 of them at most."""
    out = []
    if len(items) > 255:
        out.append(f'#error "more than 255 different {what}: the compact form refers to at '
                   'most 255 (use the general form, CO_CONFIG_OD_COMPACT 0)"')
    if items:
        out.append(f"static const {declaration}[] = {{")
        out += [f"    {text}," for text in items]
        out.append("};")
        out.append("")
    return out


def _rows(entries: list[_Entry]) -> tuple[list[str], list[int]]:
    """The compact form's rows (co_od_row_t: type, attributes, side table position), each
    once, in the order of their first entry, and the row of each entry."""
    limit_pos = {text: i + 1 for i, text in enumerate(_distinct_limits(entries))}
    size_pos = {n: i + 1 for i, n in enumerate(_distinct_sizes(entries))}
    rows: dict[str, int] = {}
    placed = []
    for e in entries:
        v = e.var
        if _TYPES[v.data_type or 0][1] == 0:
            side = size_pos[e.size]
        else:
            side = limit_pos[e.limits] if e.limits else 0
        row = f"{{.type = CO_TYPE_{_TYPES[v.data_type or 0][0]}, .attr = {e.attr}, .side = {side}}}"
        placed.append(rows.setdefault(row, len(rows)))
    return list(rows), placed


def _compact_tables(name: str, entries: list[_Entry]) -> list[str]:
    """The compact form's tables: power-on values as one image without zeros, the distinct
    limits and capacities (co_od_tables_t), the distinct rows (co_od_row_t), 6-byte entries
    that give their value's offset in the values struct and their row."""
    out = ["/* Power-on values (without the node-ID where CO_OD_NODEID is set), one record per",
           " * entry whose value is not all zeros: a head (entries skipped, length), the bytes",
           " * (co_od_tables_t.defaults). */",
           "static const uint8_t k_defaults[] = {"]
    next_pos = 0
    for pos, e in enumerate(entries):
        if e.default and e.kind != _DOMAIN:
            v = e.var
            out.append(f"    /* 0x{v.index:04X} sub {v.subindex} */ "
                       + ", ".join(f"0x{b:02X}" for b in _record(pos - next_pos, pos, e.default))
                       + ",")
            next_pos = pos + 1
    out.append("    0x00, /* end */")
    out.append("};")
    out.append("")
    limits = _distinct_limits(entries)
    sizes = _distinct_sizes(entries)
    out += _side_table("limits", "co_od_limits_t k_limits", limits)
    out += _side_table("string and domain sizes", "uint32_t k_sizes", [f"{n}u" for n in sizes])
    lim = f"k_limits, .limits_count = {len(limits)}u" if limits else "NULL, .limits_count = 0"
    siz = f"k_sizes, .sizes_count = {len(sizes)}u" if sizes else "NULL, .sizes_count = 0"
    out.append(f"static const co_od_tables_t k_tables = {{.defaults = k_defaults, .limits = {lim},")
    out.append(f"                                         .sizes = {siz}}};")
    out.append("")
    out.append(f"_Static_assert(sizeof({name}_values_t) <= 0x10000u, \"the compact form addresses "
               "values by 16-bit offsets (use the general form, CO_CONFIG_OD_COMPACT 0)\");")
    out.append("")
    rows, placed = _rows(entries)
    if len(rows) > 256:
        out.append('#error "more than 256 different (type, attributes, side) rows: the compact '
                   'form names at most 256 (use the general form, CO_CONFIG_OD_COMPACT 0)"')
    out.append("/* What entries share (co_od_row_t): type, attributes, side table position. */")
    out.append("static const co_od_row_t k_rows[] = {")
    out += [f"    {row}," for row in rows]
    out.append("};")
    out.append("")
    out.append("static const co_od_entry_t k_entries[] = {")
    for e, row in zip(entries, placed, strict=True):
        v = e.var
        out.append(
            f"    {{.index = 0x{v.index:04X}, .sub = {v.subindex}, .row = {row}, "
            f".offset = offsetof({name}_values_t, {e.member})}},")
    out.append("};")
    return out


def _general_tables(name: str, entries: list[_Entry]) -> list[str]:
    """The general form's tables: power-on values as a copy of the values, limits and a
    28-byte entry (32-bit targets) of pointers each, the dense key array."""
    out = []
    with_init = [e for e in entries if e.init is not None]
    out.append("/* Power-on values (without the node-ID where CO_OD_NODEID is set). */")
    if with_init:
        out.append(f"static const {name}_values_t k_defaults = {{")
        out += [f"    .{e.member} = {e.init}," for e in with_init]
        out.append("};")
    else:
        out.append(f"static const {name}_values_t k_defaults;")
    out.append("")
    limited = [e for e in entries if e.limits]
    for e in limited:
        out.append(f"static const co_od_limits_t {_limits_name(e)} = {e.limits};")
    if limited:
        out.append("")
    out.append("static const co_od_entry_t k_entries[] = {")
    for e in entries:
        v = e.var
        amp = "" if e.array else "&"
        dflt = "NULL" if e.init is None else f"{amp}k_defaults.{e.member}"
        lim = f"&{_limits_name(e)}" if e.limits else "NULL"
        out.append(
            f"    {{.index = 0x{v.index:04X}, .sub = {v.subindex}, "
            f".type = CO_TYPE_{_TYPES[v.data_type or 0][0]}, .attr = {e.attr}, "
            f".size = {e.size}, .value = {amp}{name}_values.{e.member}, .dflt = {dflt}, "
            f".limits = {lim}, .hooks = NULL}},")
    out.append("};")
    out.append("")
    # The dense key array the look-up searches (co_od_t.keys), 4 bytes per entry.
    out.append("static const uint32_t k_keys[] = {")
    keys = [f"0x{(e.var.index << 8) | e.var.subindex:06X}u" for e in entries]
    for i in range(0, len(keys), 8):
        out.append("    " + ", ".join(keys[i:i + 8]) + ",")
    out.append("};")
    return out


def _hash_table(keys: list[int]) -> list[int]:
    """The hash of co_od_t (canola/od.h, as co_od_hash_build makes it): 2^bits slots with
    2^bits >= 2 * len(keys), each key at the first free slot from its home
    (CO_OD_HASH_HOME) on; a slot holds 1 + the key's position, 0 when empty. No hash ([])
    for more than 32767 keys."""
    if len(keys) > 32767:
        return []
    bits = 1
    while (1 << bits) < 2 * len(keys):
        bits += 1
    mask = (1 << bits) - 1
    slots = [0] * (1 << bits)
    for pos, key in enumerate(keys):
        slot = (((key * 0x9E3779B1) & 0xFFFFFFFF) >> 16) & mask
        while slots[slot]:
            slot = (slot + 1) & mask
        slots[slot] = pos + 1
    return slots


def _limits_name(e: _Entry) -> str:
    return f"k_limits_{e.var.index:04x}_{e.var.subindex:02x}"


# ---------------------------------------------------------------------------------------
# files and command line


def generate_files(source: str | Path, name: str, out_dir: str | Path,
                   options: GenerateOptions | None = None) -> tuple[Path, Path]:
    """Parse ``source`` and write ``<out_dir>/<name>.h`` and ``.c``; returns their paths."""
    od = eds.parse(Path(source))
    header, code = generate(od, name, options)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = (out / f"{name}.h", out / f"{name}.c")
    for path, text in zip(paths, (header, code), strict=True):
        write_file(path, text.encode("ascii"))
    return paths


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message}\n")


def _c_name(text: str) -> str:
    if not _NAME.fullmatch(text):
        raise argparse.ArgumentTypeError(f"{text!r} is not a C identifier")
    return text


def _int_range(low: int, high: int) -> Callable[[str], int]:
    def conv(text: str) -> int:
        try:
            value = int(text, 0)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{value} is outside {low}..{high}")
        return value
    return conv


def _name_from_path(path: str) -> str:
    """A C identifier from a file name: its stem, lower case, other characters as '_'."""
    stem = os.path.splitext(os.path.basename(path))[0].lower()
    name = re.sub(r"[^a-z0-9_]", "_", stem)
    return name if name and not name[0].isdigit() else "od_" + name


def build_parser(prog: str = "canola-odgen") -> argparse.ArgumentParser:
    """The command line's parser (docs/cli.md lists its options from it)."""
    p = _Parser(prog=prog,
                description="Generate a canola object dictionary (C) from an EDS/DCF.")
    p.add_argument("input", help="EDS or DCF file")
    p.add_argument("--name", type=_c_name,
                   help="C name: files NAME.h/NAME.c, symbols NAME_od, NAME_values "
                        "(default: from the input's file name)")
    p.add_argument("-o", "--out-dir", required=True, help="folder for the generated files")
    p.add_argument("--node-id", type=_int_range(1, 127),
                   help="node-ID to define as NAME_NODE_ID (default: the DCF's NodeID)")
    p.add_argument("--domain-size", type=_int_range(0, 0xFFFFFFFF), default=0,
                   help="RAM buffer per DOMAIN entry in bytes (0: leave DOMAINs out)")
    p.add_argument("--min-string-size", type=_int_range(0, 0xFFFF), default=0,
                   help="minimum capacity of string entries in bytes")
    return p


def main(argv: Sequence[str] | None = None, prog: str = "canola-odgen") -> int:
    """Command line: ``canola odgen INPUT -o DIR [--name NAME] [--node-id N]``."""
    p = build_parser(prog)
    args = p.parse_args(argv)
    name: str = args.name if args.name is not None else _name_from_path(args.input)
    if _NAME.fullmatch(name) is None:
        p.error(f"cannot make a C name of {args.input!r}: give --name")
    opts = GenerateOptions(domain_size=args.domain_size, min_string_size=args.min_string_size,
                           node_id=args.node_id)
    try:
        header, code = generate_files(args.input, name, args.out_dir, opts)
    except EdsError as exc:
        print(exc, file=sys.stderr)
        return 1
    except OSError as exc:
        print(f"{p.prog}: {exc}", file=sys.stderr)
        return 1
    print(f"{p.prog}: wrote {header} and {code} from {args.input}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
