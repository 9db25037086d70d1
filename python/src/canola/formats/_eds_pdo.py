# SPDX-License-Identifier: Apache-2.0
"""The CiA 301 rules of the PDO mapping objects of a parsed EDS/DCF (0x1600-0x17FF RPDOs,
0x1A00-0x1BFF TPDOs), checked on the values the file gives (ParameterValue, else
DefaultValue):

- every mapping entry ``0xIIIISSLL`` (index, sub-index, length in bits) names an entry of
  the dictionary whose PDOMapping is 1, or a dummy (a basic data type index, 0x0001-0x0007);
- the length is the size of the entry's data type (strings and domains: any whole bytes);
- an RPDO maps entries that may be written, a TPDO entries that may be read;
- sub0 (the number of mapped entries) is at most 64 and has that many entries, which carry
  at most 64 bits together.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from canola.errors import Diagnostic
from canola.formats.datatypes import DATA_TYPES, type_bits

if TYPE_CHECKING:
    from canola.formats.eds import Object, ObjectDictionary, Variable

__all__ = ["mapping_problems"]

def _given(var: Variable) -> int | None:
    value = var.value if var.value is not None else var.default
    return value if isinstance(value, int) else None


def mapping_problems(od: ObjectDictionary) -> list[Diagnostic]:
    """Every deviation from the rules above, one Diagnostic each (file, line, section)."""
    problems: list[Diagnostic] = []
    for index, obj in od.objects.items():
        compound = int(obj.object_type) != 0x7  # a VAR mapping object is reported already
        if compound and (0x1600 <= index <= 0x17FF or 0x1A00 <= index <= 0x1BFF):
            problems += _check_mapping(od, obj, rpdo=index < 0x1800)
    return problems


def _check_mapping(od: ObjectDictionary, obj: Object, *, rpdo: bool) -> list[Diagnostic]:
    problems: list[Diagnostic] = []

    def problem(var: Variable, text: str) -> None:
        key = "ParameterValue" if var.value is not None else "DefaultValue"
        problems.append(Diagnostic(text, od.file, var.line,
                                   f"{obj.index:04X}sub{var.subindex:X}", key))

    sub0 = obj.subs.get(0)
    count = None if sub0 is None else _given(sub0)
    if sub0 is not None and count is not None:
        present = sum(1 for s in obj.subs if 1 <= s <= 64)
        if not 0 <= count <= 64:
            problem(sub0, f"{count} mapped entries: a PDO maps 0..64")
        elif count > present:
            problem(sub0, f"{count} mapped entries, but only {present} mapping sub-objects")
    total = 0
    for sub in sorted(obj.subs):
        var = obj.subs[sub]
        value = _given(var)
        if sub == 0 or value is None:
            continue
        mapped = count is not None and sub <= count
        if value == 0:
            if mapped:
                problem(var, f"mapped entry {sub} of {count} is empty (0)")
            continue
        why = _entry_problem(od, value, rpdo=rpdo)
        if why is not None:
            problem(var, why)
        if mapped:
            total += value & 0xFF
    if total > 64:
        problem(sub0 or next(iter(obj.subs.values())),
                f"the {count} mapped entries have {total} bits: a PDO carries at most 64")
    return problems


def _entry_problem(od: ObjectDictionary, value: int, *, rpdo: bool) -> str | None:
    """What is wrong with mapping entry ``value`` (None: nothing)."""
    index, sub, bits = value >> 16, (value >> 8) & 0xFF, value & 0xFF
    where = f"0x{index:04X}:{sub:02X}"
    if bits == 0:
        return f"maps {where} with length 0"
    if 0x0001 <= index <= 0x0007 and sub == 0:  # a dummy: the data type says its size
        want = type_bits(index)
        if want is not None and bits != want:
            return f"maps dummy {where} ({DATA_TYPES[index].name}) with {bits} bits, not {want}"
        return None
    obj = od.objects.get(index)
    var = None if obj is None else obj.subs.get(sub)
    if var is None:
        return f"maps {where}, which is not in the dictionary"
    named = f"{where} ({var.name})" if var.name else where
    if not var.pdo_mapping:
        return f"maps {named}, whose PDOMapping is 0"
    if rpdo and var.access_type in ("ro", "const"):
        return f"an RPDO maps {named}, which cannot be written (AccessType={var.access_type})"
    if not rpdo and var.access_type == "wo":
        return f"a TPDO maps {named}, which cannot be read (AccessType=wo)"
    want = type_bits(var.data_type)
    if want is not None and bits != want:
        name = DATA_TYPES[var.data_type or 0].name
        return f"maps {named} with {bits} bits, but {name} has {want}"
    if want is None and bits % 8:
        return f"maps {named} with {bits} bits, not whole bytes"
    return None
