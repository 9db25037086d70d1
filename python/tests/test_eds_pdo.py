# SPDX-License-Identifier: Apache-2.0
"""PDO mapping objects in an EDS/DCF are checked against CiA 301 (canola.formats._eds_pdo): every
rule has a file that breaks it, and a file that keeps them all has no warning."""

from __future__ import annotations

import pytest
from test_eds import make, optional_list

from canola import EdsError
from canola.formats import eds

APP = """[2000]
ParameterName=Speed
ObjectType=0x7
DataType=0x0006
AccessType=rw
PDOMapping=1

[2001]
ParameterName=Not mappable
ObjectType=0x7
DataType=0x0005
AccessType=rw
PDOMapping=0

[2002]
ParameterName=Status
ObjectType=0x7
DataType=0x0005
AccessType=ro
PDOMapping=1

[2003]
ParameterName=Command
ObjectType=0x7
DataType=0x0007
AccessType=wo
PDOMapping=1
"""


def mapping_file(index: int, entries: list[str], count: str | None = None) -> str:
    """An EDS with APP's objects and one mapping object at ``index`` with ``entries``
    (DefaultValue texts of sub1..) and sub0 ``count`` (default: their number)."""
    subs = "".join(f"\n[{index:04X}sub{n}]\nParameterName=Mapped {n}\nObjectType=0x7\n"
                   f"DataType=0x0007\nAccessType=rw\nDefaultValue={text}\nPDOMapping=0\n"
                   for n, text in enumerate(entries, start=1))
    body = (f"[{index:04X}]\nParameterName=Mapping\nObjectType=0x9\n"
            f"SubNumber={len(entries) + 1}\n\n[{index:04X}sub0]\nParameterName=Count\n"
            f"ObjectType=0x7\nDataType=0x0005\nAccessType=rw\n"
            f"DefaultValue={len(entries) if count is None else count}\nPDOMapping=0\n"
            + subs + "\n" + APP)
    return make(body, optional=optional_list(index, 0x2000, 0x2001, 0x2002, 0x2003))


def problems(text: str) -> list[str]:
    return [f"[{w.section}] {w.key}: {w.message}" for w in eds.parse(text).warnings]


def test_a_mapping_that_keeps_the_rules_has_no_warning() -> None:
    text = mapping_file(0x1A00, ["0x20000010", "0x20020008", "0x00050008", "0"], count="3")
    assert problems(text) == []
    eds.parse(text, strict=True)
    rpdo = mapping_file(0x1600, ["0x20000010", "0x20030020", "0x00060010"])
    assert problems(rpdo) == []


@pytest.mark.parametrize(("index", "entry", "message"), [
    (0x1A00, "0x30000008", "maps 0x3000:00, which is not in the dictionary"),
    (0x1A00, "0x20000108", "maps 0x2000:01, which is not in the dictionary"),
    (0x1A00, "0x20010008", "maps 0x2001:00 (Not mappable), whose PDOMapping is 0"),
    (0x1A00, "0x20000008", "maps 0x2000:00 (Speed) with 8 bits, but UNSIGNED16 has 16"),
    (0x1A00, "0x20000000", "maps 0x2000:00 with length 0"),
    (0x1A00, "0x20030020", "a TPDO maps 0x2003:00 (Command), which cannot be read "
                           "(AccessType=wo)"),
    (0x1600, "0x20020008", "an RPDO maps 0x2002:00 (Status), which cannot be written "
                           "(AccessType=ro)"),
    (0x1600, "0x00050010", "maps dummy 0x0005:00 (UNSIGNED8) with 16 bits, not 8"),
])
def test_a_broken_mapping_entry_is_named_with_its_place(index: int, entry: str,
                                                        message: str) -> None:
    text = mapping_file(index, [entry])
    assert problems(text) == [f"[{index:04X}sub1] DefaultValue: {message}"]
    line = text.splitlines().index(f"[{index:04X}sub1]") + 1
    assert [(w.file, w.line) for w in eds.parse(text, filename="m.eds").warnings] == [
        ("m.eds", line)]
    with pytest.raises(EdsError, match="maps"):
        eds.parse(text, strict=True)


def test_count_beyond_the_entries_or_64_and_more_than_64_bits() -> None:
    assert problems(mapping_file(0x1A00, ["0x20000010"], count="2")) == [
        "[1A00sub0] DefaultValue: 2 mapped entries, but only 1 mapping sub-objects"]
    assert problems(mapping_file(0x1A00, ["0x20000010"], count="65")) == [
        "[1A00sub0] DefaultValue: 65 mapped entries: a PDO maps 0..64"]
    assert problems(mapping_file(0x1A00, ["0x20000010", "0"])) == [
        "[1A00sub2] DefaultValue: mapped entry 2 of 2 is empty (0)"]
    assert problems(mapping_file(0x1600, ["0x20030020"] * 3)) == [
        "[1600sub0] DefaultValue: the 3 mapped entries have 96 bits: a PDO carries at most 64"]


def test_a_dcf_value_is_checked_in_place_of_the_default() -> None:
    text = mapping_file(0x1A00, ["0x20000010"]).replace(
        "DefaultValue=0x20000010", "DefaultValue=0x20000010\nParameterValue=0x20010008")
    assert problems(text) == [
        "[1A00sub1] ParameterValue: maps 0x2001:00 (Not mappable), whose PDOMapping is 0"]
