# SPDX-License-Identifier: Apache-2.0
"""The dictionary of an EDS/DCF as rows of a table (``canola eds show``): one row per
object, then one per sub-object of an ARRAY/RECORD; filtered by index range and name.

    >>> print(format_rows(rows(eds.parse("drive.eds"), first=0x1018, last=0x1018)))
"""

from __future__ import annotations

from dataclasses import dataclass

from canola.formats import eds
from canola.formats.datatypes import DATA_TYPES

__all__ = ["Row", "format_rows", "rows", "type_name"]


@dataclass(frozen=True)
class Row:
    """One line of the table. ``sub`` is None for the object line of an ARRAY/RECORD;
    ``default`` and ``value`` are the texts of the file (DefaultValue, ParameterValue)."""

    index: int
    sub: int | None
    name: str
    type: str
    access: str
    default: str
    value: str | None
    pdo_mappable: bool

    def as_dict(self) -> dict[str, object]:
        return {"index": self.index, "sub": self.sub, "name": self.name, "type": self.type,
                "access": self.access, "default": self.default, "value": self.value,
                "pdo_mappable": self.pdo_mappable}


def type_name(code: int | None) -> str:
    """The CiA 301 name of a data type code ("" for none, the code for an unknown one)."""
    if code is None:
        return ""
    info = DATA_TYPES.get(code)
    return info.name if info is not None else f"0x{code:04X}"


def _row(var: eds.Variable, sub: int | None, name: str) -> Row:
    return Row(var.index, sub, name, type_name(var.data_type), var.access_type or "",
               var.default_value or "", var.parameter_value, var.pdo_mapping)


def rows(od: eds.ObjectDictionary, *, first: int = 0, last: int = 0xFFFF,
         name: str | None = None) -> list[Row]:
    """The rows of the objects ``first..last`` in index order. With ``name``, only entries
    whose name (or whose object's name) contains it, in any case."""
    wanted = None if name is None else name.casefold()
    out: list[Row] = []
    for index in sorted(od.objects):
        if not first <= index <= last:
            continue
        obj = od.objects[index]
        object_hit = wanted is None or wanted in obj.name.casefold()
        if obj.object_type not in (eds.ObjectType.ARRAY, eds.ObjectType.RECORD,
                                   eds.ObjectType.DEFSTRUCT):
            if object_hit:
                out.append(_row(obj.subs[0], 0, obj.name))
            continue
        subs = [_row(var, sub, var.name) for sub, var in sorted(obj.subs.items())
                if object_hit or (wanted is not None and wanted in var.name.casefold())]
        if subs:
            out.append(Row(index, None, obj.name, obj.object_type.name, "", "", None, False))
            out += subs
    return out


_HEADINGS = ("INDEX", "SUB", "NAME", "TYPE", "ACCESS", "DEFAULT", "VALUE", "PDO")


def format_rows(table: list[Row]) -> str:
    """The rows as aligned text columns under a heading line; the VALUE column only when a
    row has a value (a DCF). Sub-object names are indented under their object's."""
    with_value = any(r.value is not None for r in table)
    compound = {r.index for r in table if r.sub is None}
    lines = [[h for h in _HEADINGS if with_value or h != "VALUE"]]
    for r in table:
        cells = [f"0x{r.index:04X}", "" if r.sub is None else f"0x{r.sub:02X}",
                 ("  " if r.sub is not None and r.index in compound else "") + r.name,
                 r.type, r.access, r.default]
        if with_value:
            cells.append(r.value or "")
        cells.append("" if r.sub is None else ("yes" if r.pdo_mappable else "no"))
        lines.append(cells)
    widths = [max(len(line[i]) for line in lines) for i in range(len(lines[0]))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(line, widths, strict=True)).rstrip()
                     for line in lines)

