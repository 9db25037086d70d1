# SPDX-License-Identifier: Apache-2.0
"""The EDS from the checks' side: which entries are readable, writable, of fixed size,
PDO-mappable, and the values the EDS fixes."""

from __future__ import annotations

from collections.abc import Iterator

from canola.formats import eds, values
from canola.formats.datatypes import DATA_TYPES, INTEGER_TYPES

__all__ = ["ACTING", "VARIABLE_TYPES", "another_number", "another_value", "describe",
           "fixed_size", "integer_range", "mappable", "plain_rw", "readable", "value_text",
           "variables", "writable"]

#: Entries whose writes act (store, restore, program download): no probe value goes there.
ACTING = frozenset({0x1010, 0x1011, *range(0x1F50, 0x1F60)})
#: Data types whose length is the value's (strings, DOMAIN).
VARIABLE_TYPES = frozenset({0x0009, 0x000A, 0x000B, 0x000F})

_TPDO_ACCESS = ("ro", "const", "rw", "rwr")
_RPDO_ACCESS = ("wo", "rw", "rww")
_SIZES = {0x0001: 1, 0x0008: 4, 0x0011: 8, 0x000C: 6, 0x000D: 6}


def variables(od: eds.ObjectDictionary) -> Iterator[eds.Variable]:
    """Every entry of the EDS (VARs and sub-indices), in index order."""
    for index in sorted(od.objects):
        obj = od.objects[index]
        for sub in sorted(obj.subs):
            yield obj.subs[sub]


def readable(var: eds.Variable) -> bool:
    return var.access_type in ("ro", "rw", "rwr", "rww", "const")


def writable(var: eds.Variable) -> bool:
    return var.access_type in ("wo", "rw", "rwr", "rww")


def plain_rw(var: eds.Variable) -> bool:
    """Readable and writable, and a write only stores the value (not in :data:`ACTING`)."""
    return readable(var) and writable(var) and var.index not in ACTING


def fixed_size(var: eds.Variable) -> int | None:
    """The wire size of the entry's type in bytes; None for strings, DOMAIN and unknown
    types."""
    code = var.data_type
    if code is None or code in VARIABLE_TYPES:
        return None
    if code in _SIZES:
        return _SIZES[code]
    info = DATA_TYPES.get(code)
    return info.bits // 8 if info is not None and info.bits else None


def integer_range(var: eds.Variable) -> tuple[int, int] | None:
    """The range of an integer entry's type; None for other types."""
    if var.data_type not in INTEGER_TYPES or var.data_type == 0x0001:
        return None
    info = DATA_TYPES[var.data_type]
    return info.min, info.max


def mappable(var: eds.Variable, *, tpdo: bool) -> bool:
    """PDO-mappable per the EDS, in the direction its access type allows (CiA 306: rww is
    an output, RPDOs only; rwr an input, TPDOs only), and of a size a mapping entry can
    give (1..64 bits, whole bytes)."""
    size = fixed_size(var)
    if not var.pdo_mapping or size is None or not 1 <= size <= 8:
        return False
    return var.access_type in (_TPDO_ACCESS if tpdo else _RPDO_ACCESS)


def describe(var: eds.Variable) -> str:
    """``0x1018:1 (Vendor-ID, ro UNSIGNED32)``."""
    kind = DATA_TYPES[var.data_type].name if var.data_type in DATA_TYPES else "?"
    name = f"{var.name}, " if var.name else ""
    return f"0x{var.index:04X}:{var.subindex} ({name}{var.access_type} {kind})"


def value_text(var: eds.Variable, data: bytes) -> str:
    """``data`` as a value of the entry's type (hex for integers), or hex bytes."""
    if var.data_type in DATA_TYPES:
        try:
            value = values.decode(var.data_type, data)
        except values.ValueFormatError:
            return f"[{data.hex(' ').upper()}]"
        if isinstance(value, int) and not isinstance(value, bool):
            return f"0x{value:X}" if value >= 0 else str(value)
        return repr(value)
    return f"[{data.hex(' ').upper()}]"


def another_number(var: eds.Variable, value: int) -> int:
    """Another value of an integer entry, within its type and limits (+1, else -1; 1000 for
    a time in ms that is 0, 0x1017 and 0x100C, so that no 1 ms heartbeat floods the bus)."""
    low, high = integer_range(var) or (0, 0)
    if isinstance(var.low, int):
        low = max(low, var.low)
    if isinstance(var.high, int):
        high = min(high, var.high)
    if value == 0 and var.index in (0x1017, 0x100C) and high >= 1000:
        return 1000
    return value + 1 if value + 1 <= high else max(low, value - 1)


def another_value(var: eds.Variable, data: bytes) -> bytes:
    """Wire bytes of another value of the entry than ``data`` (its type's and limits')."""
    code = var.data_type
    if code is None or not data:
        return data
    if code == 0x0001:
        return bytes([int(not data[0])])
    if code in (0x0008, 0x0011):
        return values.encode(code, 2.5 if values.decode(code, data) == 1.5 else 1.5)
    if integer_range(var) is not None:
        number = values.decode(code, data)
        assert isinstance(number, int)
        return values.encode(code, another_number(var, number))
    return bytes([data[0] ^ 1]) + data[1:]
