# SPDX-License-Identifier: Apache-2.0
"""canola eds check | show | dcf | diff: small EDS files written here, the repo's test EDS,
the real-world corpus beside the repo (when present), and ``diff --node`` against a
canola.Device on a python-can virtual bus."""

from __future__ import annotations

import itertools
import json
import os
import re
from collections.abc import Iterator
from pathlib import Path

import can
import canopen
import pytest
from cli_helpers import cli, one_line_error
from test_eds import VAR_1001, make, optional_list
from test_eds_pdo import mapping_file

from canola import Device
from canola.formats import eds
from canola.formats.odgen import refusals

DATA = Path(__file__).parent / "data"
EDS = DATA / "cli_device.eds"
CORPUS = Path(__file__).resolve().parents[2] / ".." / "shared" / "eds-corpus"
#: file:line: [section] key: error|warning: message (line, section and key when known)
FINDING = re.compile(r"(?P<file>[^:]+):(?:(?P<line>\d+):)? (?:\[(?P<section>[^\]]+)\] )?"
                     r"(?:(?P<key>[^:]+): )?(?P<kind>error|warning): (?P<msg>.+)")

Capsys = pytest.CaptureFixture[str]


def write(tmp_path: Path, name: str, text: str) -> str:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return str(path)


# ---- canola eds check


def test_check_a_clean_file_and_hash_comments(capsys: Capsys, tmp_path: Path) -> None:
    clean = write(tmp_path, "clean.eds", "# written by hand\n" + make()
                  .replace("[1000]\n", "[1000]\n# Category: Mandatory\n"))
    code, out, err = cli(capsys, "eds", "check", clean, str(EDS))
    assert (code, out, err) == (0, "", "")


#: (file text, the section, key and message of the one warning it gets)
DEVIATIONS = [
    (make().replace("SupportedObjects=3\n1=0x1000\n2=0x1001\n3=0x1018\n",
                    "SupportedObjects=2\n1=0x1000\n2=0x1018\n").replace(VAR_1001, ""),
     "MandatoryObjects", None,
     "no object 0x1001 (Error register), which every CANopen device has"),
    (make().replace("[1018]\nParameterName=Identity\nObjectType=0x9\nSubNumber=2",
                    "[1018]\nParameterName=Identity\nObjectType=0x9\nSubNumber=5"),
     "1018", "SubNumber", "SubNumber=5 but 2 sub-object sections"),
    (make().replace("DefaultValue=0x00020192", "DefaultValue=0x00020192\nHighLimit=0x100"),
     "1000", "DefaultValue", "131474 is outside LowLimit/HighLimit"),
    (mapping_file(0x1A00, ["0x20010008"]), "1A00sub1", "DefaultValue",
     "maps 0x2001:00 (Not mappable), whose PDOMapping is 0"),
]


@pytest.mark.parametrize("case", DEVIATIONS, ids=[c[3][:30] for c in DEVIATIONS])
def test_check_reports_each_deviation_with_its_place(
        capsys: Capsys, tmp_path: Path, case: tuple[str, str, str | None, str]) -> None:
    text, section, key, message = case
    path = write(tmp_path, "dev.eds", text)
    code, out, err = cli(capsys, "eds", "check", path)
    assert code == 0  # warnings only
    found = [FINDING.fullmatch(line) for line in out.splitlines()]
    assert all(found), out
    assert [(m["file"], m["section"], m["key"], m["kind"], m["msg"]) for m in found if m] == [
        (path, section, key, "warning", message)]
    match = found[0]
    assert match is not None and match["line"] is not None
    line = text.splitlines()[int(match["line"]) - 1]
    assert line == f"[{section}]" or (key is not None and line.startswith(f"{key}="))
    assert err == "canola eds check: 1 file, 0 errors, 1 warning\n"
    code, out, err = cli(capsys, "eds", "check", "--strict", path)
    assert code == 1 and " error: " in out and "1 error, 0 warnings" in err


#: (file text, the section, key and message of the one error it gets): files the parser
#: reads but canola odgen and canola device refuse (canola.formats.odgen.refusals)
REFUSED = [
    (make().replace("DefaultValue=0x00020192", "DefaultValue=0x1FFFFFFFF"),
     "1000", "DefaultValue",
     "'0x1FFFFFFFF' is outside the range of UNSIGNED32 [0, 4294967295]"),
    (make().replace("DefaultValue=0x00020192", "DefaultValue=many"),
     "1000", "DefaultValue", "not a number of type UNSIGNED32: 'many' is not a number"),
    (make().replace("DefaultValue=0x00020192", "DefaultValue=abc"),
     "1000", "DefaultValue", "not a number of type UNSIGNED32: 'abc' is not a number"),
    (make().replace("[1000]\nParameterName=Device type\nObjectType=0x7\nDataType=0x0007",
                    "[1000]\nParameterName=Device type\nObjectType=0x7\nDataType=0x0040"),
     "1000", "DataType", "DataType 0x0040 is not supported by the canola core"),
    ("[FileInfo]\nFileName=empty.eds\n", None, None,
     "no objects: a device needs at least its mandatory entries (0x1000, 0x1001, 0x1018)"),
]


@pytest.mark.parametrize("case", REFUSED, ids=[c[3][:30] for c in REFUSED])
def test_check_fails_on_what_odgen_and_device_refuse(
        capsys: Capsys, tmp_path: Path, case: tuple[str, str | None, str | None, str]) -> None:
    """One decision (canola.formats.odgen.refusals) for the three tools: eds check says
    error and exits 1 where canola odgen and canola device refuse the file, with the
    same words."""
    text, section, key, message = case
    path = write(tmp_path, "dev.eds", text)
    code, out, _ = cli(capsys, "eds", "check", path)
    assert code == 1
    errors = [m for m in map(FINDING.fullmatch, out.splitlines())
              if m is not None and m["kind"] == "error"]
    assert [(m["file"], m["section"], m["key"], m["msg"]) for m in errors] == [
        (path, section, key, message)]
    assert f"{section}] {key}: error" not in out.replace(errors[0].group(0), "")  # no echo
    code, _, err = cli(capsys, "odgen", path, "-o", str(tmp_path / "gen"))
    assert code == 1 and message in err
    code, _, err = cli(capsys, "device", "--eds", path, "--node-id", "5", "--bus",
                       "virtual://refused")
    assert code == 1 and message in err
    one_line_error(err)


def test_check_warns_of_sdo_server_cob_ids_that_are_not_the_defaults(
        capsys: Capsys, tmp_path: Path) -> None:
    """OreSat's battery DCF sets 0x1200's COB-IDs to 0x80000000: a device that used them
    could not be reached by the default SDO (CiA 301: its COB-IDs are fixed)."""
    body = ("[1200]\nParameterName=SDO server parameter\nObjectType=0x9\nSubNumber=3\n"
            "[1200sub0]\nParameterName=Highest\nObjectType=0x7\nDataType=0x0005\n"
            "AccessType=ro\nDefaultValue=2\n"
            "[1200sub1]\nParameterName=COB-ID client to server\nObjectType=0x7\n"
            "DataType=0x0007\nAccessType=ro\nDefaultValue=0x80000000\n"
            "[1200sub2]\nParameterName=COB-ID server to client\nObjectType=0x7\n"
            "DataType=0x0007\nAccessType=ro\nDefaultValue=$NODEID+0x580\n")
    path = write(tmp_path, "sdo.eds", make(body, optional=optional_list(0x1200)))
    code, out, _ = cli(capsys, "eds", "check", path)
    assert code == 0  # a warning: canola's device serves the default SDO all the same
    assert [(m["section"], m["key"], m["kind"], m["msg"])
            for m in map(FINDING.fullmatch, out.splitlines()) if m] == [
        ("1200sub1", "DefaultValue", "warning", "COB-ID client -> server '0x80000000' is not "
         "CiA 301's default $NODEID+0x600: the default SDO server's COB-IDs are fixed")]
    fixed = write(tmp_path, "ok.eds", Path(path).read_text().replace("=0x80000000",
                                                                     "=$NODEID+0x600"))
    assert cli(capsys, "eds", "check", fixed) == (0, "", "")


def test_check_errors_usage_and_missing_files(capsys: Capsys, tmp_path: Path) -> None:
    broken = write(tmp_path, "broken.eds", make() + "\n[1000]\nParameterName again\n")
    code, out, err = cli(capsys, "eds", "check", broken, str(tmp_path / "none.eds"), str(EDS))
    assert code == 1
    again = len(Path(broken).read_text().splitlines())
    assert out.splitlines() == [
        f"{broken}:{again}: [1000] error: line is neither [section], key=value nor comment: "
        "'ParameterName again'",
        f"{tmp_path / 'none.eds'}: error: cannot read file: No such file or directory"]
    assert err == "canola eds check: 3 files, 2 errors, 0 warnings\n"
    for args in (["eds", "check"], ["eds"], ["eds", "check", "--frob", broken]):
        code, out, err = cli(capsys, *args)
        assert (code, out) == (2, "")
        one_line_error(err)


def corpus_files() -> list[Path]:
    return sorted(p for p in CORPUS.iterdir() if p.suffix.lower() in (".eds", ".dcf"))


@pytest.mark.slow
@pytest.mark.skipif(not CORPUS.is_dir(), reason=f"no EDS corpus at {CORPUS}")
def test_check_over_the_corpus(capsys: Capsys) -> None:
    """Every corpus file loads (warnings only: trailing comments, a section given twice,
    ... read past); eds check's errors are exactly what canola's builders refuse
    (refusals), each naming file and line; every line of the output is a finding."""
    files = corpus_files()
    code, out, err = cli(capsys, "eds", "check", *map(str, files))
    findings = [FINDING.fullmatch(line) for line in out.splitlines()]
    assert all(findings), [line for line in out.splitlines() if not FINDING.fullmatch(line)]
    errors: dict[str, list[re.Match[str]]] = {}
    for m in findings:
        if m is not None and m["kind"] == "error":
            errors.setdefault(m["file"], []).append(m)
    usable = 0
    for path in files:
        refused = refusals(eds.parse(path))  # loads: no EdsError
        assert [m["msg"] for m in errors.get(str(path), [])] == [d.message for d in refused]
        assert all(m["line"] is not None for m in errors.get(str(path), []))
        usable += not refused
    print(f"\n{len(files)} of {len(files)} corpus files load; {usable} build a canola device")
    assert code == (1 if errors else 0)
    assert err.startswith(f"canola eds check: {len(files)} files, ")
# ---- canola eds show


def test_show_table_and_filters(capsys: Capsys) -> None:
    code, out, _ = cli(capsys, "eds", "show", str(EDS), "0x1018")
    assert code == 0
    lines = out.splitlines()
    assert lines[0].split() == ["INDEX", "SUB", "NAME", "TYPE", "ACCESS", "DEFAULT", "PDO"]
    assert lines[1].split() == ["0x1018", "Identity", "object", "RECORD"]
    assert lines[3].split() == ["0x1018", "0x01", "Vendor-ID", "UNSIGNED32", "ro", "0xCA0",
                                "no"]
    assert len(lines) == 1 + 1 + 5
    code, out, _ = cli(capsys, "eds", "show", str(EDS), "2000-2FFF", "--name", "PARAMETER")
    assert [line.split()[0] for line in out.splitlines()[1:]] == [
        "0x2000", "0x2001", "0x2002", "0x2003"]
    code, out, _ = cli(capsys, "eds", "show", str(EDS), "--name", "vendor", "--json")
    rows = [json.loads(line) for line in out.splitlines()]
    assert rows == [
        {"index": 0x1018, "sub": None, "name": "Identity object", "type": "RECORD",
         "access": "", "default": "", "value": None, "pdo_mappable": False},
        {"index": 0x1018, "sub": 1, "name": "Vendor-ID", "type": "UNSIGNED32",
         "access": "ro", "default": "0xCA0", "value": None, "pdo_mappable": False}]


def test_show_marks_pdo_mappable_entries_and_dcf_values(capsys: Capsys, tmp_path: Path
                                                         ) -> None:
    text = mapping_file(0x1A00, ["0x20000010"]).replace(
        "DefaultValue=0x20000010", "DefaultValue=0x20000010\nParameterValue=0x20020008")
    code, out, _ = cli(capsys, "eds", "show", write(tmp_path, "m.dcf", text), "0x1A00-0x2002")
    assert code == 0
    lines = [line.split() for line in out.splitlines()]
    assert lines[0][-2:] == ["VALUE", "PDO"]
    assert ["0x1A00", "0x01", "Mapped", "1", "UNSIGNED32", "rw", "0x20000010", "0x20020008",
            "no"] in lines
    assert lines[-1] == ["0x2002", "0x00", "Status", "UNSIGNED8", "ro", "yes"]


def test_show_errors(capsys: Capsys, tmp_path: Path) -> None:
    for args, code in ((["5000"], 1), (["0x2000-0x1000"], 2), (["0x10000"], 2),
                       (["--name", "nothing like it"], 1)):
        got, out, err = cli(capsys, "eds", "show", str(EDS), *args)
        assert (got, out) == (code, "")
        one_line_error(err)
    broken = write(tmp_path, "b.eds", "[1000]\nnot a key\n")
    got, out, err = cli(capsys, "eds", "show", broken)
    assert (got, out) == (1, "")
    one_line_error(err)
    assert f"{broken}:2: [1000]" in err


# ---- canola eds dcf


def test_dcf_from_an_eds(capsys: Capsys, tmp_path: Path) -> None:
    out_path = tmp_path / "five.dcf"
    code, out, err = cli(capsys, "eds", "dcf", str(EDS), "--node-id", "5", "--set",
                         "0x1017:0=1000", "--set", "2001=-7", "--set", "0x2002:0=hi there",
                         "--node-name", "drive", "--baudrate", "500", "-o", str(out_path))
    assert (code, out, err) == (0, "", "")
    dcf = eds.parse(out_path, strict=True)
    assert dcf.node_id == 5
    assert dcf.device_commissioning == {"NodeID": "5", "NodeName": "drive", "Baudrate": "500"}
    assert dcf[0x1017].subs[0].value == 1000
    assert dcf[0x2001].subs[0].value == -7
    assert dcf[0x2002].subs[0].parameter_value == "hi there"
    assert dcf[0x1014].subs[0].default == 0x85  # $NODEID+0x80 of node 5
    given = {(i, s) for i, o in dcf.objects.items() for s, v in o.subs.items()
             if v.parameter_value is not None}
    assert given == {(0x1017, 0), (0x2001, 0), (0x2002, 0)}  # only what was set
    code, out, _ = cli(capsys, "eds", "dcf", str(EDS), "--node-id", "5", "-o", "-")
    assert code == 0 and "[DeviceComissioning]\r\nNodeID=5\r\n" in out


@pytest.mark.parametrize(("setting", "message"), [
    ("0x1017:0=70000", "0x1017:00 (Producer heartbeat time): 70000 is outside UNSIGNED16 "
                       "(0..65535)"),
    ("0x1017:0=fast", "0x1017:00 (Producer heartbeat time): 'fast' is not a number"),
    ("0x1018:1=5", "0x1018:01 (Vendor-ID) is ro: a configuration cannot write it"),
    ("0x3000:0=1", "0x3000:00 is not in "),
    ("0x2003:0=x", "0x2003:00 (Parameter real): 'x' is not a number"),
    ("0x2001:0=-40000", "0x2001:00 (Parameter i16): -40000 is outside INTEGER16"),
    ("0x1017=", "0x1017:00 (Producer heartbeat time): empty"),
    ("1017:0", "bad setting '1017:0': INDEX:SUB=VALUE"),
    ("0x1017:300=1", "bad setting '0x1017:300=1': INDEX:SUB=VALUE"),
])
def test_dcf_refuses_a_value_that_does_not_fit(capsys: Capsys, tmp_path: Path, setting: str,
                                               message: str) -> None:
    out_path = tmp_path / "x.dcf"
    code, out, err = cli(capsys, "eds", "dcf", str(EDS), "--node-id", "5", "--set", setting,
                         "-o", str(out_path))
    assert (code, out) == (2, "")
    one_line_error(err)
    assert err.startswith("canola eds dcf: error: ") and message in err
    assert not out_path.exists()


def test_dcf_checks_limits_and_needs_its_arguments(capsys: Capsys, tmp_path: Path) -> None:
    limited = write(tmp_path, "l.eds", make().replace(
        "[1018sub1]", "[1018sub1]").replace("AccessType=ro\nDefaultValue=0x00020192",
                                            "AccessType=rw\nDefaultValue=0x10\nLowLimit=0x10"
                                            "\nHighLimit=0x20"))
    code, _, err = cli(capsys, "eds", "dcf", limited, "--node-id", "3", "--set",
                       "0x1000:0=0x21", "-o", str(tmp_path / "l.dcf"))
    assert code == 2
    assert "0x1000:00 (Device type): 0x21 is outside LowLimit..HighLimit (0x10..0x20)" in err
    code, _, _ = cli(capsys, "eds", "dcf", limited, "--node-id", "3", "--set",
                     "0x1000:0=0x20", "-o", str(tmp_path / "l.dcf"))
    assert code == 0
    for args in (["--node-id", "0", "-o", "x"], ["--node-id", "5"], ["-o", "x"],
                 ["--node-id", "5", "--baudrate", "3", "-o", "x"]):
        code, out, err = cli(capsys, "eds", "dcf", str(EDS), *args)
        assert (code, out) == (2, "")
        one_line_error(err)
    code, _, err = cli(capsys, "eds", "dcf", str(EDS), "--node-id", "5", "-o",
                       str(tmp_path / "no" / "dir.dcf"))
    assert code == 1
    one_line_error(err)


# ---- canola eds diff


def test_diff_two_files(capsys: Capsys, tmp_path: Path) -> None:
    b_text = (EDS.read_text().replace("DefaultValue=100", "DefaultValue=0x64")  # same value
              .replace("ParameterName=Parameter i16", "ParameterName=Offset")
              .replace("DefaultValue=hello", "DefaultValue=hello, world"))
    b_text = re.sub(r"\[2005\][^\[]*", "", b_text).replace("AccessType=rw\nDefaultValue=1.5",
                                                            "AccessType=ro\nDefaultValue=1.5")
    b = write(tmp_path, "b.eds", b_text)
    code, out, err = cli(capsys, "eds", "diff", str(EDS), b)
    assert (code, err) == (0, "")
    assert out.splitlines() == [
        "0x2001:00 Parameter i16: name: A Parameter i16, B Offset",
        "0x2002:00 Parameter string: default: A hello, B 'hello, world'",
        "0x2003:00 Parameter real: access: A rw, B ro",
        "0x2005 Read-only value: only in A"]
    code, out, _ = cli(capsys, "eds", "diff", b, str(EDS), "--json", "--exit-code")
    assert code == 1
    docs = [json.loads(line) for line in out.splitlines()]
    assert docs[-1] == {"index": 0x2005, "sub": None, "name": "Read-only value",
                        "what": "only in B", "a": None, "b": None}
    code, out, _ = cli(capsys, "eds", "diff", str(EDS), str(EDS), "--exit-code")
    assert (code, out) == (0, "")


def test_diff_usage_errors(capsys: Capsys) -> None:
    for args in ([str(EDS)], [str(EDS), str(EDS), "--node", "5", "--bus", "virtual://x"],
                 [str(EDS), str(EDS), "--bus", "virtual://x"],
                 [str(EDS), "--node", "200", "--bus", "virtual://x"]):
        code, out, err = cli(capsys, "eds", "diff", *args)
        assert (code, out) == (2, ""), args
        one_line_error(err)


_channels = itertools.count()


@pytest.fixture
def device_bus(tmp_path: Path) -> Iterator[tuple[list[str], Device]]:
    """A started canola.Device (cli_device.eds, node 5, storing parameters as 0x1010 says)
    on a fresh virtual channel, and the CLI's bus options for it."""
    channel = f"canola-eds-{os.getpid()}-{next(_channels)}"
    bus = can.Bus(interface="virtual", channel=channel)
    dev = Device(EDS, 5, bus, store_dir=tmp_path)
    dev.start()
    yield ["--bus", f"virtual://{channel}", "--sdo-timeout", "5000"], dev
    dev.stop()
    bus.shutdown()


@pytest.mark.realtime
def test_diff_against_a_device(capsys: Capsys, tmp_path: Path,
                               device_bus: tuple[list[str], Device]) -> None:
    opts, dev = device_bus
    code, out, err = cli(capsys, "eds", "diff", str(EDS), "--node", "5", *opts)
    assert (code, out, err) == (0, "", "")  # a fresh device has the EDS's defaults
    dev.od[0x1017, 0] = 250
    dev.od[0x2002, 0] = "bye"
    extra = ("\n[2100]\nParameterName=Not on the device\nObjectType=0x7\nDataType=0x0005\n"
             "AccessType=rw\nDefaultValue=1\nPDOMapping=0\n")
    a = write(tmp_path, "a.eds", EDS.read_text() + extra)
    code, out, err = cli(capsys, "eds", "diff", a, "--node", "5", *opts, "--exit-code")
    assert (code, err) == (1, "")
    assert out.splitlines() == [
        "0x1017:00 Producer heartbeat time: value: A 100 (0x64), B 250 (0xFA)",
        "0x2002:00 Parameter string: value: A hello, B bye",
        "0x2100 Not on the device: only in A"]
    # a DCF's ParameterValue is what the device should have; $NODEID is node 5's
    dcf = tmp_path / "five.dcf"
    assert cli(capsys, "eds", "dcf", str(EDS), "--node-id", "5", "--set", "0x1017:0=250",
               "-o", str(dcf))[0] == 0
    code, out, _ = cli(capsys, "eds", "diff", str(dcf), "--node", "5", *opts, "--json")
    assert [json.loads(line) for line in out.splitlines()] == [
        {"index": 0x2002, "sub": 0, "name": "Parameter string", "what": "value", "a": "hello",
         "b": "bye"}]


@pytest.mark.realtime
def test_diff_against_an_absent_node(capsys: Capsys, device_bus: tuple[list[str], Device]
                                     ) -> None:
    opts, _ = device_bus
    opts = [o if o != "5000" else "200" for o in opts]
    code, out, err = cli(capsys, "eds", "diff", str(EDS), "--node", "9", *opts)
    assert (code, out) == (1, "")
    one_line_error(err)
    assert err == "canola: no response from node 9 (SDO time-out 200 ms)\n"


@pytest.mark.realtime
def test_diff_against_a_python_canopen_local_node(capsys: Capsys) -> None:
    channel = f"canola-eds-pc-{os.getpid()}-{next(_channels)}"
    network = canopen.Network()
    network.connect(interface="virtual", channel=channel)
    try:
        node = canopen.LocalNode(5, str(EDS))
        network.add_node(node)
        opts = ["--node", "5", "--bus", f"virtual://{channel}", "--sdo-timeout", "5000"]
        code, out, err = cli(capsys, "eds", "diff", str(EDS), *opts)
        assert (code, out, err) == (0, "", "")
        node.sdo[0x2001].raw = 12
        code, out, err = cli(capsys, "eds", "diff", str(EDS), *opts)
        assert (code, out, err) == (0, "0x2001:00 Parameter i16: value: A -5, B 12 (0xC)\n", "")
    finally:
        network.disconnect()


@pytest.mark.realtime
def test_a_made_dcf_boots_its_device(capsys: Capsys, tmp_path: Path,
                                     device_bus: tuple[list[str], Device]) -> None:
    """canola boot downloads every value canola eds dcf put into the DCF."""
    opts, dev = device_bus
    dcf = tmp_path / "five.dcf"
    code, _, err = cli(capsys, "eds", "dcf", str(EDS), "--node-id", "5", "--set",
                       "0x2001:0=-7", "--set", "0x2003=2.25", "--set", "0x2002=configured",
                       "-o", str(dcf))
    assert (code, err) == (0, "")
    code, out, _ = cli(capsys, "boot", str(dcf), *opts)
    assert code == 0 and out.splitlines() == ["node 5 (mandatory): running", "network started"]
    assert (dev.od[0x2001, 0], dev.od[0x2003, 0], dev.od[0x2002, 0]) == (-7, 2.25, "configured")
