# SPDX-License-Identifier: Apache-2.0
"""Tests of canola.eds: one behaviour per test, plus the shared corpus of real files."""

from __future__ import annotations

from pathlib import Path

import pytest

from canola import EdsError, Error
from canola.formats import eds
from canola.formats.eds import ObjectType

HEADER = """[FileInfo]
FileName=t.eds
EDSVersion=4.0

[DeviceInfo]
VendorNumber=0x1234
ProductNumber=1

[MandatoryObjects]
SupportedObjects=2
1=0x1000
2=0x1001
"""

VAR_1000 = """[1000]
ParameterName=Device type
ObjectType=0x7
DataType=0x0007
AccessType=ro
DefaultValue=0x00020192
PDOMapping=0
"""


VAR_1001 = """[1001]
ParameterName=Error register
ObjectType=0x7
DataType=0x0005
AccessType=ro
PDOMapping=1
"""


def make(body: str = "", mandatory: str = VAR_1000, optional: str = "") -> str:
    """An EDS with [1000] plus ``optional`` objects (listed in [OptionalObjects]), the
    identity object [1018] (RECORD_1018, below) unless the test brings its own, and [1001]
    last (lines before it keep their numbers)."""
    if "[1018]" in body + optional + mandatory:
        return HEADER + optional + mandatory + "\n" + body + "\n" + VAR_1001
    # the listing's extra line takes a blank line's place: lines after the listing
    # keep the numbers they have in HEADER
    header = HEADER.replace("EDSVersion=4.0\n\n", "EDSVersion=4.0\n").replace(
        "SupportedObjects=2\n1=0x1000\n2=0x1001\n",
        "SupportedObjects=3\n1=0x1000\n2=0x1001\n3=0x1018\n")
    return (header + optional + mandatory + "\n" + RECORD_1018 + "\n" + body + "\n"
            + VAR_1001)


def optional_list(*indices: int) -> str:
    lines = [f"{n}=0x{i:04X}" for n, i in enumerate(indices, start=1)]
    listing = "\n".join(lines)
    return f"[OptionalObjects]\nSupportedObjects={len(indices)}\n{listing}\n\n"


RECORD_1018 = """[1018]
ParameterName=Identity
ObjectType=0x9
SubNumber=2

[1018sub0]
ParameterName=Highest sub-index
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=1

[1018sub1]
ParameterName=Vendor-ID
ObjectType=0x7
DataType=0x0007
AccessType=ro
DefaultValue=0x1234
"""


def test_clean_file_parses_without_warnings() -> None:
    od = eds.parse(make(), strict=True)
    assert od.warnings == []
    assert od[0x1000].object_type is ObjectType.VAR
    assert od[0x1000].subs[0].default == 0x20192
    assert od.device_info["VendorNumber"] == "0x1234"


def test_section_and_key_names_in_any_case() -> None:
    text = make(mandatory=VAR_1000.replace("[1000]", "[1000]").replace(
        "ParameterName", "parametername").replace("DataType", "DATATYPE"))
    text = text.replace("[DeviceInfo]", "[deviceinfo]")
    od = eds.parse(text, strict=True)
    assert od[0x1000].name == "Device type"
    assert od[0x1000].subs[0].data_type == 7
    assert "VendorNumber" in od.device_info


def test_lower_case_hex_and_sub_spelling_in_section_names() -> None:
    body = RECORD_1018.replace("[1018sub1]", "[1018SUB1]").replace("[1018]", "[1018]")
    od = eds.parse(make(body, optional=optional_list(0x1018)), strict=True)
    assert od[0x1018].subs[1].name == "Vendor-ID"


def test_whitespace_around_equals_and_trailing_spaces_are_ignored() -> None:
    text = make(mandatory=VAR_1000.replace("DefaultValue=0x00020192",
                                           "DefaultValue  =  0x10   \t"))
    assert eds.parse(text, strict=True)[0x1000].subs[0].default_value == "0x10"


def test_crlf_and_cr_line_endings() -> None:
    text = make().replace("\n", "\r\n")
    od = eds.parse(text, strict=True)
    assert od[0x1000].subs[0].default == 0x20192
    assert eds.parse(make().replace("\n", "\r"), strict=True)[0x1000].name == "Device type"


def test_whole_line_comments_are_skipped() -> None:
    text = "; leading comment\n" + make(mandatory=VAR_1000 + "  ;DefaultValue=5\n")
    assert eds.parse(text, strict=True)[0x1000].subs[0].default == 0x20192


def test_hash_comment_lines_are_skipped() -> None:
    # seen in real files (kacanopen's 301.eds): "# Category: Mandatory" inside a section
    text = "# leading\n" + make(mandatory=VAR_1000 + "  # DefaultValue=5\n#\n")
    od = eds.parse(text, strict=True)
    assert od[0x1000].subs[0].default == 0x20192
    assert "#" not in od[0x1000].subs[0].extra


def test_semicolon_after_a_number_is_dropped_with_a_warning() -> None:
    text = make(mandatory=VAR_1000.replace("0x00020192", "0x10 ; note"))
    od = eds.parse(text)
    assert od[0x1000].subs[0].default == 0x10
    assert od[0x1000].subs[0].default_value == "0x10 ; note"
    assert [w.message for w in od.warnings] == ["';' comment after a value"]


def test_semicolon_inside_a_string_value_is_kept() -> None:
    body = optional_list(0x1008) + "[1008]\nParameterName=Name\nObjectType=0x7\n" \
        "DataType=0x0009\nAccessType=const\nDefaultValue=a;b\n"
    od = eds.parse(make(body), strict=True)
    assert od[0x1008].subs[0].default == "a;b"


def test_utf8_text_is_decoded_as_utf8() -> None:
    data = make(mandatory=VAR_1000.replace("Device type", "Gerät")).encode("utf-8")
    assert eds.parse(data)[0x1000].name == "Gerät"


def test_non_utf8_bytes_are_decoded_as_latin1() -> None:
    data = make(mandatory=VAR_1000.replace("Device type", "Ger\xe4t")).encode("latin-1")
    assert eds.parse(data)[0x1000].name == "Gerät"


@pytest.mark.parametrize(("text", "value"), [
    ("10", 10), ("0x1F", 31), ("0X1f", 31), ("017", 15), ("0", 0), ("-5", -5),
    ("-0x10", -16),
])
def test_number_forms(text: str, value: int) -> None:
    body = make(mandatory=VAR_1000.replace("0x0007", "0x0004").replace("0x00020192", text))
    assert eds.parse(body, strict=True)[0x1000].subs[0].default == value


@pytest.mark.parametrize("text", ["$NODEID+0x180", "0x180+$NODEID", "$NodeID + 0x180",
                                  "$nodeid+384"])
def test_nodeid_expressions_are_evaluated_for_the_node_id(text: str) -> None:
    body = make(mandatory=VAR_1000.replace("0x00020192", text))
    var = eds.parse(body, node_id=5, strict=True)[0x1000].subs[0]
    assert var.default == 0x185
    assert var.default_value == text


def test_nodeid_expression_without_node_id_stays_unevaluated() -> None:
    body = make(mandatory=VAR_1000.replace("0x00020192", "$NODEID+0x180"))
    var = eds.parse(body, strict=True)[0x1000].subs[0]
    assert var.default is None
    assert var.default_value == "$NODEID+0x180"


def test_missing_sub0_is_synthesised() -> None:
    body = RECORD_1018.replace("""[1018sub0]
ParameterName=Highest sub-index
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=1
""", "").replace("SubNumber=2", "SubNumber=1")
    od = eds.parse(make(body, optional=optional_list(0x1018)))
    sub0 = od[0x1018].subs[0]
    assert (sub0.data_type, sub0.access_type, sub0.default) == (5, "ro", 1)
    assert [w.message for w in od.warnings] == [
        "RECORD without sub0: synthesised (highest sub-index 1)"]


def test_missing_sub0_is_an_error_in_strict_mode() -> None:
    body = RECORD_1018.split("[1018sub0]", maxsplit=1)[0].replace("SubNumber=2", "SubNumber=0")
    with pytest.raises(EdsError, match="without sub0"):
        eds.parse(make(body, optional=optional_list(0x1018)), strict=True)


COMPACT = """[1003]
ParameterName=Errors
ObjectType=0x8
DataType=0x0007
AccessType=ro
DefaultValue=0
CompactSubObj=3
"""


def test_compact_sub_obj_expands_to_n_sub_objects() -> None:
    od = eds.parse(make(COMPACT, optional=optional_list(0x1003)), strict=True)
    obj = od[0x1003]
    assert sorted(obj.subs) == [0, 1, 2, 3]
    assert obj.subs[0].default == 3
    assert [(s.name, s.data_type, s.default) for s in list(obj.subs.values())[1:]] == [
        ("Errors1", 7, 0), ("Errors2", 7, 0), ("Errors3", 7, 0)]


def test_compact_sub_obj_takes_names_and_values_from_name_and_value_sections() -> None:
    body = COMPACT + "\n[1003Name]\nNrOfEntries=2\n1=first\n3=third\n" \
        "\n[1003Value]\nNrOfEntries=1\n2=0x42\n"
    od = eds.parse(make(body, optional=optional_list(0x1003)), strict=True)
    subs = od[0x1003].subs
    assert [subs[i].name for i in (1, 2, 3)] == ["first", "Errors2", "third"]
    assert subs[2].parameter_value == "0x42"
    assert subs[2].value == 0x42


def test_dummy_usage_is_read() -> None:
    body = "[DummyUsage]\nDummy0001=0\nDummy0002=1\n"
    assert eds.parse(make(body), strict=True).dummy_usage == {1: False, 2: True}


def test_obj_flags_are_read() -> None:
    body = make(mandatory=VAR_1000 + "ObjFlags=0x3\n")
    assert eds.parse(body, strict=True)[0x1000].subs[0].obj_flags == 3


DCF_HEAD = "[DeviceComissioning]\nNodeID=0x10\nNodeName=drive\nBaudrate=500\n\n"


def test_dcf_parameter_value_denotation_and_device_comissioning() -> None:
    text = DCF_HEAD + make(mandatory=VAR_1000 + "ParameterValue=$NODEID+1\nDenotation=dt\n")
    od = eds.parse(text, strict=True)
    var = od[0x1000].subs[0]
    assert od.device_commissioning == {"NodeID": "0x10", "NodeName": "drive", "Baudrate": "500"}
    assert od.node_id == 0x10
    assert (var.parameter_value, var.value, var.denotation) == ("$NODEID+1", 0x11, "dt")


def test_node_id_argument_wins_over_device_comissioning() -> None:
    text = DCF_HEAD + make(mandatory=VAR_1000 + "ParameterValue=$NODEID+1\n")
    assert eds.parse(text, node_id=3)[0x1000].subs[0].value == 4


def test_double_m_commissioning_is_accepted_with_a_warning() -> None:
    text = DCF_HEAD.replace("Comissioning", "Commissioning") + make()
    od = eds.parse(text)
    assert od.node_id == 0x10
    assert "[DeviceComissioning]" in od.warnings[0].message


# --- strict-mode deviations ------------------------------------------------------------

def strict_problems(text: str) -> list[str]:
    with pytest.raises(EdsError) as info:
        eds.parse(text, strict=True, filename="t.eds")
    return str(info.value).splitlines()


@pytest.mark.parametrize("key", ["ParameterName", "DataType", "AccessType", "ObjectType"])
def test_missing_mandatory_key_of_a_var_is_reported(key: str) -> None:
    lines = [ln for ln in VAR_1000.splitlines() if not ln.startswith(key)]
    problems = strict_problems(make(mandatory="\n".join(lines) + "\n"))
    assert problems == [f"t.eds:13: [1000] {key}: missing {key}"]


def test_supported_objects_count_mismatch_is_reported() -> None:
    text = make().replace("SupportedObjects=3", "SupportedObjects=4")
    assert strict_problems(text) == [
        "t.eds:9: [MandatoryObjects] SupportedObjects: SupportedObjects=4 but 3 entries"]


def test_listed_object_without_section_is_reported() -> None:
    text = make(optional=optional_list(0x1017))
    assert strict_problems(text) == [
        "t.eds:15: [OptionalObjects] 1: 0x1017 is listed but has no section"]


def test_section_without_listing_is_reported() -> None:
    body = RECORD_1018
    assert strict_problems(make(body)) == [
        "t.eds:21: [1018] object is not listed in [MandatoryObjects], [OptionalObjects] "
        "or [ManufacturerObjects]"]


def test_unknown_access_type_is_reported() -> None:
    text = make(mandatory=VAR_1000.replace("AccessType=ro", "AccessType=read"))
    assert strict_problems(text) == ["t.eds:17: [1000] AccessType: unknown AccessType 'read'"]


def test_unknown_data_type_is_reported() -> None:
    text = make(mandatory=VAR_1000.replace("DataType=0x0007", "DataType=0x0E"))
    assert strict_problems(text)[0] == (
        "t.eds:16: [1000] DataType: DataType 0x000E is not a known basic data type")


def test_value_that_is_not_a_number_is_reported() -> None:
    text = make(mandatory=VAR_1000.replace("0x00020192", "twelve"))
    assert strict_problems(text) == [
        "t.eds:18: [1000] DefaultValue: not a number of type UNSIGNED32: 'twelve' is not a number"]


def test_value_that_is_not_a_number_is_a_warning_in_lenient_mode() -> None:
    text = make(mandatory=VAR_1000.replace("0x00020192", "twelve"))
    od = eds.parse(text)
    assert od[0x1000].subs[0].default is None
    assert len(od.warnings) == 1


def test_limit_outside_the_type_range_is_reported() -> None:
    text = make(mandatory=VAR_1000.replace("DataType=0x0007", "DataType=0x0005")
                .replace("0x00020192", "1") + "HighLimit=256\n")
    assert strict_problems(text) == [
        "t.eds:20: [1000] HighLimit: 256 is outside the range of UNSIGNED8 [0, 255]"]


@pytest.mark.parametrize(("default", "problem"), [
    ("$NODEID+0xFF", "256 with node-ID 1 is outside the range of UNSIGNED8 [0, 255]"),
    ("$NODEID+0x81", "256 with node-ID 127 is outside the range of UNSIGNED8 [0, 255]"),
    ("$NODEID-2", "-1 with node-ID 1 is outside the range of UNSIGNED8 [0, 255]"),
])
def test_a_nodeid_default_must_fit_for_every_node_id(default: str, problem: str) -> None:
    text = make(mandatory=VAR_1000.replace("DataType=0x0007", "DataType=0x0005")
                .replace("0x00020192", default))
    assert strict_problems(text) == [f"t.eds:18: [1000] DefaultValue: {problem}"]
    fits = text.replace(default, "$NODEID+0x80")
    assert eds.parse(fits, strict=True)[0x1000].subs[0].default is None  # no node-ID known
    assert eds.parse(fits, node_id=127)[0x1000].subs[0].default == 255


def test_hex_bit_pattern_of_a_signed_limit_is_its_twos_complement() -> None:
    text = make(mandatory=VAR_1000.replace("DataType=0x0007", "DataType=0x0003")
                .replace("0x00020192", "0") + "LowLimit=0x8000\n")
    assert eds.parse(text, strict=True)[0x1000].subs[0].low == -0x8000


def test_default_outside_limits_is_reported() -> None:
    text = make(mandatory=VAR_1000.replace("0x00020192", "9") + "HighLimit=8\n")
    assert strict_problems(text) == ["t.eds:18: [1000] DefaultValue: 9 is outside "
                                     "LowLimit/HighLimit"]


def test_strict_mode_lists_every_problem() -> None:
    text = make(mandatory=VAR_1000.replace("AccessType=ro", "AccessType=x")
                .replace("0x00020192", "y"))
    problems = strict_problems(text)
    assert len(problems) == 2
    assert all(p.startswith("t.eds:1") for p in problems)


def test_sub_number_mismatch_is_reported() -> None:
    body = RECORD_1018.replace("SubNumber=2", "SubNumber=3")
    assert strict_problems(make(body, optional=optional_list(0x1018))) == [
        "t.eds:28: [1018] SubNumber: SubNumber=3 but 2 sub-object sections"]


# --- broken files ------------------------------------------------------------------------

def broken(text: str) -> EdsError:
    with pytest.raises(EdsError) as info:
        eds.parse(text, filename="bad.eds")
    return info.value


def test_error_tree() -> None:
    assert issubclass(EdsError, Error)
    assert issubclass(Error, Exception)


def test_line_that_is_neither_section_key_nor_comment_is_an_error() -> None:
    err = broken(make(mandatory=VAR_1000 + "garbage here\n"))
    assert str(err) == ("bad.eds:20: [1000] line is neither [section], key=value nor "
                        "comment: 'garbage here'")
    assert (err.file, err.line, err.section, err.key) == ("bad.eds", 20, "1000", None)


def test_a_section_again_is_merged_with_a_warning_and_refused_when_strict() -> None:
    # kacanopen's NEMA23 EDS has [1008], [1009], [100A] and [1017] twice
    text = make(mandatory=VAR_1000 + "\n[1000]\nDefaultValue=0x99\n")
    od = eds.parse(text, filename="bad.eds")
    assert od[0x1000].subs[0].default == 0x99 and od[0x1000].name == "Device type"
    merged = ("bad.eds:21: [1000] section [1000] again (first at line 13): its keys are "
              "added, later values win")
    assert merged in [str(w) for w in od.warnings]
    with pytest.raises(EdsError) as info:
        eds.parse(text, filename="bad.eds", strict=True)
    assert merged in str(info.value).splitlines()


def test_sub_object_without_object_is_an_error() -> None:
    body = "[2000sub1]\nParameterName=x\nDataType=0x0005\nAccessType=ro\n"
    text = make(body)
    line = text.splitlines().index("[2000sub1]") + 1
    assert str(broken(text)) == (f"bad.eds:{line}: [2000sub1] sub-object section without its "
                                 "object section [2000]")


def test_unreadable_structural_number_is_an_error() -> None:
    err = broken(make(mandatory=VAR_1000.replace("DataType=0x0007", "DataType=int")))
    assert str(err) == "bad.eds:16: [1000] DataType: not a number: 'int' is not a number"


def test_key_before_any_section_is_an_error() -> None:
    assert str(broken("A=1\n" + make())) == "bad.eds:1: A: key=value before the first section"


def test_unreadable_file_is_an_error_naming_the_file(tmp_path: Path) -> None:
    missing = tmp_path / "none.eds"
    with pytest.raises(EdsError) as info:
        eds.parse(missing)
    assert str(info.value).startswith(f"{missing}: cannot read file")


def test_file_path_and_line_in_messages(tmp_path: Path) -> None:
    path = tmp_path / "dev.eds"
    path.write_bytes(make(mandatory=VAR_1000 + "oops\n").encode())
    with pytest.raises(EdsError) as info:
        eds.parse(path)
    assert str(info.value).startswith(f"{path}:20: ")


# --- writing ---------------------------------------------------------------------------

def test_write_then_parse_gives_the_same_model() -> None:
    body = RECORD_1018 + "\n" + COMPACT + "\n[1003Name]\nNrOfEntries=1\n2=two\n"
    od = eds.parse(make(body, optional=optional_list(0x1003, 0x1018)), node_id=2)
    again = eds.parse(eds.write(od), node_id=2, strict=True)
    assert again == od


def test_dcf_round_trip_keeps_parameter_values_and_commissioning() -> None:
    text = DCF_HEAD + make(mandatory=VAR_1000 + "ParameterValue=7\nDenotation=d\n")
    od = eds.parse(text)
    out = eds.write(od, dcf=True)
    assert "[DeviceComissioning]" in out
    assert eds.parse(out) == od


def test_eds_output_drops_dcf_only_content() -> None:
    text = DCF_HEAD + make(mandatory=VAR_1000 + "ParameterValue=7\n")
    out = eds.write(eds.parse(text))
    assert "ParameterValue" not in out
    assert "DeviceComissioning" not in out


def test_write_orders_objects_by_index_and_is_stable() -> None:
    body = RECORD_1018 + "\n" + COMPACT
    od = eds.parse(make(body, optional=optional_list(0x1018, 0x1003)))
    out = eds.write(od)
    assert out.index("[1000]") < out.index("[1003]") < out.index("[1018]")
    assert eds.write(eds.parse(out)) == out


def test_written_file_passes_strict_mode() -> None:
    od = eds.parse(make(RECORD_1018))  # unlisted object: the writer lists it
    eds.parse(eds.write(od), strict=True)


# --- corpus of real files ---------------------------------------------------------------

CORPUS = Path(__file__).resolve().parents[2] / ".." / "shared" / "eds-corpus"


def corpus_files() -> list[Path]:
    if not CORPUS.is_dir():
        return []
    return sorted(p for p in CORPUS.iterdir() if p.suffix.lower() in (".eds", ".dcf"))


@pytest.mark.slow
def test_corpus_files_parse_or_fail_with_file_and_line() -> None:
    files = corpus_files()
    if not files:
        pytest.skip(f"no corpus at {CORPUS}")
    for path in files:
        try:
            od = eds.parse(path)
        except EdsError as exc:
            assert str(exc).startswith(f"{path}:"), str(exc)
            assert exc.line is not None, str(exc)
            continue
        again = eds.parse(eds.write(od, dcf=True), filename=f"{path.name} (rewritten)")
        assert again.objects == od.objects, path.name
        assert again == od, path.name
