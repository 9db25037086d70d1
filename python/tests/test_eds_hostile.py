# SPDX-License-Identifier: Apache-2.0
"""canola.eds against hostile and careless files: every input ends as an ObjectDictionary
(with warnings) or an EdsError, whatever its size, and every warning says where (file,
line, section, key) so that a tool can print it."""

from __future__ import annotations

import random
from pathlib import Path

import pytest
from test_eds import HEADER, RECORD_1018, VAR_1000, VAR_1001, make, optional_list

from canola import EdsError
from canola.errors import Diagnostic
from canola.formats import eds


def _warnings(text: str | bytes, **kw: object) -> list[Diagnostic]:
    return eds.parse(text, filename="h.eds", **kw).warnings  # type: ignore[arg-type]


def _line_of(text: str, line: str) -> int:
    return text.splitlines().index(line) + 1


@pytest.mark.parametrize("key", ["DefaultValue", "LowLimit", "HighLimit"])
@pytest.mark.parametrize("digits", ["9" * 4301, "0x" + "F" * 5000, "0" + "7" * 5000,
                                    "1" * 1_000_000])
def test_a_number_of_any_size_is_a_warning(key: str, digits: str) -> None:
    text = make(mandatory=VAR_1000 + f"{key}={digits}\n" if key != "DefaultValue"
                else VAR_1000.replace("0x00020192", digits))
    warnings = _warnings(text)
    assert len(warnings) == 1
    w = warnings[0]
    assert (w.file, w.section, w.key) == ("h.eds", "1000", key)
    assert w.line == _line_of(text, f"{key}={digits}")
    assert f"a number of {len(digits)} digits (at most 64)" in w.message
    assert len(str(w)) < 200  # the message does not carry the number
    with pytest.raises(EdsError):
        eds.parse(text, strict=True)


def test_a_structural_number_of_any_size_is_an_error() -> None:
    text = make(mandatory=VAR_1000.replace("DataType=0x0007", "DataType=" + "9" * 5000))
    with pytest.raises(EdsError, match=r"h.eds:\d+: \[1000\] DataType: not a number"):
        eds.parse(text, filename="h.eds")


def test_counts_from_the_file_do_not_drive_loops() -> None:
    text = make("[Comments]\nLines=0xFFFFFFFFFFFF\nLine1=one\n")
    od = eds.parse(text)  # at once, not after 2**48 iterations
    assert od.comments == ["one"]


@pytest.mark.parametrize("source", [b"", "", "  \n\n; only a comment\n"])
def test_an_empty_file_is_a_warning_and_no_device(source: str | bytes) -> None:
    warnings = _warnings(source)
    assert [(w.line, w.message) for w in warnings] == [
        (1, "empty file: no sections, no objects"),
        (None, "no object 0x1000 (Device type), which every CANopen device has"),
        (None, "no object 0x1001 (Error register), which every CANopen device has"),
        (None, "no object 0x1018 (Identity object), which every CANopen device has")]
    with pytest.raises(EdsError, match="empty file"):
        eds.parse(source, strict=True)


def test_an_empty_file_on_disk(tmp_path: Path) -> None:
    path = tmp_path / "empty.eds"
    path.write_bytes(b"")
    with pytest.raises(EdsError, match=f"{path}:1: empty file"):
        eds.parse(path, strict=True)


@pytest.mark.parametrize(("section", "why"), [
    ("10000", "index 0x10000 is beyond 0xFFFF"),
    ("FFFFFFFF", "index 0xFFFFFFFF is beyond 0xFFFF"),
    ("FFFFFFFFFFFFFFFFFFFF", "index 0xFFFFFFFF... is beyond 0xFFFF"),
    ("100", "index 0x100 has not 4 hex digits"),
    ("2000sub12C", "sub-index 0x12C is beyond 0xFF"),
    ("2000sub", "sub-index missing after 'sub'"),
])
def test_sections_named_like_impossible_objects_are_warnings(section: str, why: str) -> None:
    body = (f"[2000]\nParameterName=r\nObjectType=0x9\nSubNumber=1\n[2000sub0]\n"
            f"ParameterName=n\nDataType=0x0005\nAccessType=ro\nDefaultValue=0\n\n"
            f"[{section}]\nParameterName=x\nObjectType=0x7\nDataType=0x0005\nAccessType=rw\n")
    text = make(body, optional="[OptionalObjects]\nSupportedObjects=1\n1=0x2000\n\n")
    od = eds.parse(text, filename="h.eds")
    assert [(w.line, w.section, w.message) for w in od.warnings] == [
        (_line_of(text, f"[{section}]"), section,
         f"{why}: not an object, kept as an other section")]
    assert sorted(od.objects) == [0x1000, 0x1001, 0x1018, 0x2000]
    assert section in od.other_sections
    with pytest.raises(EdsError):
        eds.parse(text, strict=True)


def test_a_sub_index_with_leading_zeros_is_still_the_sub_index() -> None:
    text = make(RECORD_1018.replace("[1018sub1]", "[1018sub001]"),
                optional=optional_list(0x1018))
    assert eds.parse(text, strict=True)[0x1018].subs[1].name == "Vendor-ID"


@pytest.mark.parametrize(("value", "message"), [
    ("0xFFFF", "SubNumber=65535 is outside 0..255 (an UNSIGNED8)"),
    ("-1", "SubNumber=-1 is outside 0..255 (an UNSIGNED8)"),
    ("1e24", "not a number: '1e24' is not a number"),
    ("9" * 5000, "not a number: a number of 5000 digits (at most 64)"),
])
def test_sub_number_out_of_range_is_a_warning(value: str, message: str) -> None:
    text = make(RECORD_1018.replace("SubNumber=2", f"SubNumber={value}"),
                optional=optional_list(0x1018))
    warnings = _warnings(text)
    assert [(w.line, w.section, w.key, w.message) for w in warnings] == [
        (_line_of(text, f"SubNumber={value}"), "1018", "SubNumber", message)]
    assert sorted(eds.parse(text)[0x1018].subs) == [0, 1]  # the sections make the structure


@pytest.mark.parametrize("missing", [0x1000, 0x1001, 0x1018])
def test_a_device_without_a_mandatory_object_is_refused_when_strict(missing: int) -> None:
    text = {0x1000: make(mandatory=""),
            0x1001: make().replace(VAR_1001, ""),
            0x1018: HEADER + VAR_1000 + VAR_1001}[missing]  # HEADER lists no 0x1018
    with pytest.raises(EdsError, match=f"no object 0x{missing:04X}"):
        eds.parse(text, strict=True)
    warnings = [w for w in _warnings(text) if f"0x{missing:04X} (" in w.message]
    assert len(warnings) == 1
    assert (warnings[0].file, warnings[0].section) == ("h.eds", "MandatoryObjects")


def test_random_files_of_every_size_end_in_a_model_or_an_eds_error() -> None:
    """Any other exception escapes and fails the test: that is the contract checked."""
    rng = random.Random(18)
    alphabet = b"[]=;\n\r 0123456789abcdefxX$NODEIDsubSUB-+" + bytes(range(256))
    outcomes: dict[str, int] = {"model": 0, "EdsError": 0}
    for size in (0, 1, 7, 100, 10_000, 300_000):
        for _ in range(3):
            data = bytes(rng.choice(alphabet) for _ in range(size))
            for strict in (False, True):
                try:
                    eds.parse(data, strict=strict)
                    outcomes["model"] += 1
                except EdsError:
                    outcomes["EdsError"] += 1
        # and the same sizes spent on one huge value of a valid file: a warning
        text = make(mandatory=VAR_1000.replace("0x00020192", "7" * size))
        assert len(eds.parse(text).warnings) == (size > 64)
    assert outcomes["model"] >= 3 and outcomes["EdsError"] >= 3, outcomes  # size 0: a model
