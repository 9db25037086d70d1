# SPDX-License-Identifier: Apache-2.0
"""The values mapped to one of the gateway's own PDOs, read from its dictionary."""

from __future__ import annotations

from collections.abc import Callable

__all__ = ["mapped_entries", "mapped_values"]

Read = Callable[[int, int], bytes]


def _uint(read: Read, index: int, sub: int) -> int:
    return int.from_bytes(read(index, sub), "little")


def mapped_entries(read: Read, mapping: int) -> list[tuple[int, int, int]]:
    """(index, sub, bits) of each object mapped by mapping record ``mapping`` (0x1600..,
    0x1A00..). Raises SdoAbort when the record does not exist."""
    count = _uint(read, mapping, 0)
    out = []
    for i in range(1, count + 1):
        entry = _uint(read, mapping, i)
        out.append((entry >> 16, (entry >> 8) & 0xFF, entry & 0xFF))
    return out


def mapped_values(read: Read, mapping: int) -> list[int]:
    """The mapped objects' values as unsigned numbers (dummy entries read as 0)."""
    values = []
    for index, sub, _bits in mapped_entries(read, mapping):
        if index < 0x20 and sub == 0:  # dummy mapping of a data type
            values.append(0)
        else:
            values.append(_uint(read, index, sub))
    return values
