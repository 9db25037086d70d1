# SPDX-License-Identifier: Apache-2.0
"""canola.conformance in virtual time on the simulated bus: canola.Device passes every
check (with canola-node's dictionary too), leaves its values as it found them, each check
runs alone with the same outcome; a device that deviates from its EDS and a hand-written
responder with protocol gaps fail exactly the checks they should, with the frames that
prove it; SKIPPED says why; the reports."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path

import pytest
from conformance_fakes import FAKE_EDS, FakeNode

import canola.conformance as cc
from canola import Device, Error
from canola.conformance import Options, Status
from canola.conformance.entries import VARIABLE_TYPES
from canola.core import SimBus
from canola.formats import eds

ROOT = Path(__file__).resolve().parents[2]
INTEROP = Path(__file__).parent / "data" / "interop.eds"
EXAMPLE = ROOT / "examples" / "example_od.eds"
NODE = 5
#: Entries a run may leave changed: the error state its EMCY checks cause on purpose.
ERROR_STATE = {0x1001, 0x1003}


def device_run(eds_file: Path | eds.ObjectDictionary, device_eds: Path = INTEROP,
               **kw: object) -> cc.Report:
    bus = SimBus()
    Device(device_eds, NODE, bus).start()
    return cc.run(bus, NODE, eds_file, **kw)  # type: ignore[arg-type]


@pytest.mark.parametrize(("path", "skipped"), [
    (INTEROP, {"nmt.node_guarding", "nmt.store_restore"}),  # interop.eds: no 0x100C/0x100D
    (EXAMPLE, {"nmt.store_restore"}),
], ids=["interop.eds", "example_od.eds"])
def test_canola_device_passes(path: Path, skipped: set[str]) -> None:
    report = device_run(path, path)
    assert report.names(Status.FAILED) == set(), cc.markdown(report)
    assert report.names(Status.SKIPPED) == skipped
    assert report.count(Status.PASSED) == len(cc.CHECKS) - len(skipped)
    assert report.result("nmt.store_restore").reason == (
        "saves or restores stored parameters: run with --destructive")
    assert "1, 4, 5, 7, 8, 14, 15, 21, 22" in report.result("sdo.segmented_download").summary


def test_without_strings_or_domains_fixed_size_entries_serve() -> None:
    """The SDO checks fall back on entries of fixed size (TIME_OF_DAY's 6 bytes) and
    announce their size: a segmented download of 14 bytes to them would be refused."""
    od = eds.parse(INTEROP, node_id=NODE)
    for index in [i for i, obj in od.objects.items()
                  if any(v.data_type in VARIABLE_TYPES for v in obj.subs.values())]:
        del od.objects[index]
    report = device_run(od, only=["sdo"])
    assert report.names(Status.FAILED) == set(), cc.markdown(report)
    assert report.result("sdo.toggle_download").status is Status.PASSED
    assert report.result("sdo.block_download").summary.startswith("0x200C:0 (TIME_OF_DAY")


def _set(od: eds.ObjectDictionary, index: int, sub: int, **fields: object) -> None:
    """Change an entry of ``od``: its default (``default=``, the value and its text) or any
    other field."""
    var = od.objects[index].subs[sub]
    if "default" in fields:
        fields["default_value"] = str(fields["default"])
    for name, value in fields.items():
        setattr(var, name, value)


def _sync_producer(od: eds.ObjectDictionary) -> None:
    _set(od, 0x1005, 0, default=0x40000080)
    _set(od, 0x1006, 0, default=50000)


def _unmappable(od: eds.ObjectDictionary) -> None:
    entry = od.objects[0x1A00].subs[1].default
    assert isinstance(entry, int)
    _set(od, entry >> 16, (entry >> 8) & 0xFF, pdo_mapping=False)


#: Dictionaries (example_od.eds changed) whose settings the tester works around, or whose
#: deviation from CiA 301 fails exactly one check, with the first finding or skip reason.
Change = Callable[[eds.ObjectDictionary], object]
VARIANTS: dict[str, tuple[Change, dict[str, str]]] = {
    "SYNC counter (0x1019 = 4)": (lambda od: _set(od, 0x1019, 0, default=4), {}),
    "the node a SYNC producer": (_sync_producer, {}),
    "a synchronous window": (lambda od: _set(od, 0x1007, 0, default=1000), {}),
    "0x1006 up to 50 ms": (lambda od: _set(od, 0x1006, 0, high=50000, high_limit="50000"), {}),
    "RPDO1 type read-only": (lambda od: _set(od, 0x1400, 2, access_type="ro"), {
        "pdo.rpdo_sync": "the EDS has RPDO1 type (0x1400:2) read-only (255); the check "
                         "needs 1"}),
    "TPDO1 COB-ID read-only": (lambda od: _set(od, 0x1800, 1, access_type="ro"), {}),
    "no 0x1000": (lambda od: od.objects.pop(0x1000), {
        "dictionary.mandatory": "EDS entry 0x1000:0: expected present (mandatory), got missing",
        "dictionary.device_type": "the EDS has no 0x1000:0 (device type)"}),
    "a value outside its limits": (lambda od: _set(od, 0x2001, 0, default=150), {
        "dictionary.limits": "value of 0x2001:0 (Application i16, rw INTEGER16): expected "
                             "within LowLimit -100 .. HighLimit 100, got 150"}),
    "0x1003:0 read-only": (lambda od: _set(od, 0x1003, 0, access_type="ro"), {
        "emcy.error_history": "0x1003:0 in the EDS: expected rw (writing 0 clears the "
                              "history), got ro"}),
    "a mapping its EDS does not allow": (_unmappable, {
        "pdo.own_mappings": "TPDO1's mapping (0x1A00): expected one the EDS allows for a "
                            "TPDO, got count 1, [20000020]"}),
}


@pytest.mark.parametrize("name", list(VARIANTS))
def test_dictionaries_unlike_the_usual(name: str) -> None:
    """The tester sends SYNC with the counter, as the only producer, outside no window,
    within 0x1006's limits; leaves read-only PDO parameters as they are; and fails (or
    skips) exactly the one check a deviation concerns, leaving every value as it was."""
    change, outcomes = VARIANTS[name]
    od = eds.parse(EXAMPLE, node_id=NODE)
    change(od)
    bus = SimBus()
    dev = Device(od, NODE, bus)
    dev.start()
    before = {key: dev.od.read(*key) for key in dev.od}
    report = cc.run(bus, NODE, od)
    got = {r.check.name: r.findings[0].what + ": expected " + r.findings[0].expected
           + ", got " + r.findings[0].got if r.findings else r.reason
           for r in report.results if r.status is not Status.PASSED}
    assert got == {"nmt.store_restore": "saves or restores stored parameters: run with "
                                         "--destructive", **outcomes}, cc.markdown(report)
    after = {key: dev.od.read(*key) for key in dev.od}
    assert {i for i, _ in (k for k in before if before[k] != after[k])} <= ERROR_STATE


def test_canola_device_passes_every_check_destructive_too(tmp_path: Path) -> None:
    """All 54 checks, store and restore included, against canola.Device with storage."""
    bus = SimBus()
    Device(EXAMPLE, NODE, bus, store_dir=tmp_path).start()
    report = cc.run(bus, NODE, EXAMPLE, options=Options(destructive=True))
    assert report.names(Status.PASSED) == {c.name for c in cc.CHECKS}, cc.markdown(report)


def test_store_restore_with_destructive(tmp_path: Path) -> None:
    bus = SimBus()
    Device(EXAMPLE, NODE, bus, store_dir=tmp_path).start()
    report = cc.run(bus, NODE, EXAMPLE, only=["nmt.store_restore"],
                    options=Options(destructive=True))
    assert report.names(Status.PASSED) == {"nmt.store_restore"}, cc.markdown(report)
    # without storage the node says it does not save on command (0x1010): skipped, not passed
    report = device_run(EXAMPLE, EXAMPLE, only=["nmt.store_restore"],
                        options=Options(destructive=True))
    assert report.result("nmt.store_restore").status is Status.SKIPPED
    assert "does not save on command" in report.result("nmt.store_restore").reason


def test_a_run_leaves_the_values_as_it_found_them() -> None:
    bus = SimBus()
    dev = Device(INTEROP, NODE, bus)
    dev.start()
    before = {key: dev.od.read(*key) for key in dev.od}
    report = cc.run(bus, NODE, INTEROP)
    assert report.passed
    after = {key: dev.od.read(*key) for key in dev.od}
    changed = {key for key in before if before[key] != after[key]}
    assert {index for index, _ in changed} <= ERROR_STATE, changed
    assert dev.nmt_state == "PRE-OPERATIONAL"


def test_the_node_is_left_in_its_state() -> None:
    bus = SimBus()
    dev = Device(EXAMPLE, NODE, bus)
    dev.start()
    dev.nmt_apply("start")
    report = cc.run(bus, NODE, EXAMPLE, only=["nmt.states", "pdo.rpdo_applied"])
    assert report.passed
    assert "NMT state before the run: OPERATIONAL" in report.notes
    assert dev.nmt_state == "OPERATIONAL"


@pytest.mark.slow  # a run per check
def test_each_check_alone_ends_as_in_a_full_run() -> None:
    full = {r.check.name: r.status for r in device_run(EXAMPLE, EXAMPLE).results}
    alone = {}
    for chk in cc.select():
        alone[chk.name] = device_run(EXAMPLE, EXAMPLE, only=[chk.name]).results[0].status
    assert alone == full


def _deviating_eds() -> eds.ObjectDictionary:
    """interop.eds, but the device it describes is not what runs: 0x200D read-only, another
    vendor-ID, an object 0x2103 more."""
    od = eds.parse(INTEROP, node_id=NODE)
    od.objects[0x200D].subs[0].access_type = "ro"
    od.device_info["VendorNumber"] = "0xBAD"
    od.objects[0x2103] = eds.Object(0x2103, "Not there", eds.ObjectType.VAR, {0: eds.Variable(
        0x2103, 0, "Not there", 0x0005, "rw", "0", default=0)})
    return od


def test_a_device_unlike_its_eds_fails_exactly_those_checks() -> None:
    report = device_run(_deviating_eds())
    assert report.names(Status.FAILED) == {"dictionary.entries", "dictionary.write_read_only",
                                           "dictionary.identity"}, cc.markdown(report)
    ro = report.result("dictionary.write_read_only").findings
    assert len(ro) == 1
    assert ro[0].what.startswith("write its own value to 0x200D:0")
    assert (ro[0].expected, ro[0].got) == (
        "abort 0x06010002 (Attempt to write a read only object)", "success")
    # the frames prove it: the (segmented) download of 0x200D and the server's confirmations
    assert "-> 605  21 0D 20 00 06 00 00 00" in ro[0].frames[-4]
    assert "<- 585  60 0D 20 00 00 00 00 00" in ro[0].frames[-3]
    assert "<- 585  20 00 00 00 00 00 00 00" in ro[0].frames[-1]
    missing = report.result("dictionary.entries").findings
    assert [(f.what[:12], f.got) for f in missing] == [
        ("read 0x2103:", "abort 0x06020000 (Object does not exist in the object dictionary)")]
    vendor = report.result("dictionary.identity").findings
    assert [(f.expected, f.got) for f in vendor] == [
        ("0xBAD ([DeviceInfo] VendorNumber)", "0xCA0")]


@pytest.mark.parametrize("checks_toggle", [True, False], ids=["toggle checked", "toggle ignored"])
def test_a_responder_with_gaps_fails_exactly_those_checks(checks_toggle: bool) -> None:
    bus = SimBus()
    FakeNode(bus, 20, checks_toggle=checks_toggle).start()
    report = cc.run(bus, 20, eds.parse(FAKE_EDS, node_id=20), only=["dictionary", "sdo", "nmt"])
    gaps = {"sdo.block_download", "sdo.block_upload", "sdo.block_crc", "sdo.block_size",
            "sdo.server_timeout"}
    assert report.names(Status.FAILED) == gaps | (set() if checks_toggle
                                                  else {"sdo.toggle_download"})
    assert report.result("sdo.block_upload").findings[0].got == (
        "abort 0x05040001 (Client/server command specifier not valid or unknown)")
    if not checks_toggle:
        toggle = report.result("sdo.toggle_download").findings[0]
        assert (toggle.expected, toggle.got) == (
            "abort 0x05030000 (Toggle bit not alternated)", "[30 00 00 00 00 00 00 00]")
        assert "-> 614  17 63 61 6E 6F 00 00 00" in toggle.frames[-2]  # the 4 bytes it holds
        assert "<- 594  30 00 00 00 00 00 00 00" in toggle.frames[-1]


def _fake_run(**switches: object) -> cc.Report:
    """The whole suite against a FakeNode (node 20) with ``switches``."""
    bus = SimBus()
    FakeNode(bus, 20, **switches).start()  # type: ignore[arg-type]
    return cc.run(bus, 20, eds.parse(FAKE_EDS, node_id=20))


@pytest.mark.parametrize(("switches", "check", "finding"), [
    ({"accepts_read_only": True}, "dictionary.write_read_only", (
        "write its own value to 0x1000:0",
        "abort 0x06010002 (Attempt to write a read only object)", "success",
        ["-> 614  23 00 10 00 91 01 00 00", "<- 594  60 00 10 00 00 00 00 00"])),
    ({"missing_object_code": 0x06090011}, "dictionary.missing_object", (
        "read 0x5FFF:0", "abort 0x06020000 (Object does not exist in the object dictionary)",
        "abort 0x06090011 (Sub-index does not exist)",
        ["-> 614  40 FF 5F 00 00 00 00 00", "<- 594  80 FF 5F 00 11 00 09 06"])),
], ids=["read-only write succeeds", "wrong abort code"])
def test_a_broken_node_fails_exactly_the_checks_it_should(
        switches: dict[str, object], check: str,
        finding: tuple[str, str, str, list[str]]) -> None:
    baseline = _fake_run()  # what the responder lacks anyway (block transfer, ...)
    report = _fake_run(**switches)
    assert report.names(Status.FAILED) == baseline.names(Status.FAILED) | {check}
    assert check not in baseline.names(Status.FAILED)
    assert report.names(Status.SKIPPED) == baseline.names(Status.SKIPPED)
    what, expected, got, frames = finding
    first = report.result(check).findings[0]
    assert first.what.startswith(what)
    assert (first.expected, first.got) == (expected, got)
    for line, frame in zip(first.frames[-2:], frames, strict=True):
        assert frame in line


def test_a_node_that_does_not_answer_is_an_error() -> None:
    bus = SimBus()
    began = bus.now_us
    with pytest.raises(Error, match=r"node 20 does not answer SDO \(no answer to upload "
                                    r"0x1000:0 within 2 s\), not even after 'enter "
                                    "pre-operational'"):
        cc.run(bus, 20, eds.parse(FAKE_EDS, node_id=20))
    assert bus.now_us - began < 10_000_000  # at once, not a time-out per check


def test_a_stopped_node_without_heartbeat_is_found_and_left_stopped() -> None:
    bus = SimBus()
    fake = FakeNode(bus, 20)
    fake.start()
    fake.state = 0x04
    report = cc.run(bus, 20, eds.parse(FAKE_EDS, node_id=20), only=["dictionary.mandatory"])
    assert report.passed, cc.markdown(report)
    assert report.notes[0] == ("NMT state before the run: STOPPED (no heartbeat; SDO answered "
                               "only after 'enter pre-operational')")
    assert fake.state == 0x04


def test_a_late_answer_of_an_earlier_exchange_is_passed_over() -> None:
    # a stale abort before every answer, initiate or segment: each check still reads the
    # answers of its own transfer, and fails exactly what the responder lacks anyway
    report = _fake_run(late_abort=True)
    assert report.names(Status.FAILED) == _fake_run().names(Status.FAILED)
    assert report.names(Status.PASSED) >= {"sdo.segmented_upload", "sdo.toggle_upload",
                                           "sdo.toggle_download", "sdo.client_abort"}
    # an answer that names another entry, and nothing else: wrong
    bus = SimBus()
    fake = FakeNode(bus, 20)
    fake.start()
    fake._send = lambda data: fake.port.send(0x594, data[:1] + b"\0\0\0" + data[4:])  # type: ignore[method-assign]
    report = cc.run(bus, 20, eds.parse(FAKE_EDS, node_id=20), only=["dictionary.mandatory"])
    assert report.result("dictionary.mandatory").findings[0].got == (
        "upload 0x1000:0: answer names 0x0000:0 instead of 0x1000:0")


def test_skipped_says_why_and_is_never_passed() -> None:
    bus = SimBus()
    FakeNode(bus, 20).start()
    report = cc.run(bus, 20, eds.parse(FAKE_EDS, node_id=20), only=["nmt", "pdo", "sync",
                                                                      "emcy", "time"])
    reasons = {r.check.name: r.reason for r in report.results if r.status is Status.SKIPPED}
    assert reasons["nmt.states"] == "the EDS has no 0x1017:0 (no heartbeat producer)"
    assert reasons["pdo.remap"] == "no PDO has a writable mapping and a mappable entry"
    assert reasons["emcy.heartbeat_loss"] == (
        "the EDS has no 0x1016:1 (no heartbeat consumer to cause an EMCY with)")
    assert reasons["time.consumer"] == "the EDS has no 0x1012:0 (no TIME object)"
    assert report.names(Status.PASSED) == {"nmt.bootup_reset_node", "nmt.bootup_reset_comm",
                                           "nmt.sdo_gating"}
    assert all(not r.findings for r in report.results if r.status is Status.SKIPPED)


def test_reports() -> None:
    bus = SimBus()
    FakeNode(bus, 20, checks_toggle=False).start()
    report = cc.run(bus, 20, eds.parse(FAKE_EDS, node_id=20), only=["sdo"])
    text = cc.markdown(report)
    assert "- result: **FAILED** (7 passed, 6 failed, 0 skipped)" in text
    assert "## sdo: SDO protocol" in text
    assert "| `sdo.unknown_command` | CiA 301 §7.2.4.3.17 | PASSED |" in text
    assert "### `sdo.toggle_download` (CiA 301 §7.2.4.3.4, §7.2.4.3.17)" in text
    assert "  - expected: abort 0x05030000 (Toggle bit not alternated)" in text
    root = ET.fromstring(cc.junit(report))
    assert (root.get("tests"), root.get("failures"), root.get("skipped")) == ("13", "6", "0")
    cases = {c.get("name"): c for c in root.iter("testcase")}
    assert cases["sdo.toggle_download"].find("failure") is not None
    assert "got: [30 00 00 00 00 00 00 00]" in (cases["sdo.toggle_download"].find(
        "failure").text or "")  # type: ignore[union-attr]
    assert cases["sdo.unknown_command"].find("failure") is None
    prop = cases["sdo.unknown_command"].find("properties/property")
    assert prop is not None and prop.get("value") == "CiA 301 §7.2.4.3.17"


def test_check_list_and_selection() -> None:
    text = cc.check_list(cc.select())
    for chk in cc.CHECKS:
        assert f"  {chk.name} " in text and chk.clause in text
        assert chk.clause.startswith(("CiA 301 §", "CiA 306 §")), chk
    assert "nmt.store_restore" in text and "[--destructive]" in text
    assert [c.name for c in cc.select(["time", "sdo.toggle_upload"])] == [
        "sdo.toggle_upload", "time.consumer"]
    with pytest.raises(Error, match="unknown group or check 'nope'"):
        cc.select(["nope"])
    with pytest.raises(Error, match=r"node-ID 0 is outside 1\.\.127"):
        cc.run(SimBus(), 0, INTEROP)
    with pytest.raises(Error, match="node-ID 5 is the node's"):
        cc.run(SimBus(), 5, INTEROP, master_id=5)


def test_the_docs_list_every_check() -> None:
    text = (ROOT / "docs" / "conformance.md").read_text()
    listed = {line.split("`")[1] for line in text.splitlines() if line.startswith("| `")}
    assert listed == {c.name for c in cc.CHECKS}
    assert f"{len(cc.CHECKS)} checks in {len(cc.GROUPS)} groups" in text


CORPUS = ROOT / ".." / "shared" / "eds-corpus"
#: What the corpus's files get wrong about themselves (their EDS against the dictionary a
#: device made from it has): the vendor-ID or product code of [DeviceInfo] not 0x1018's,
#: a default outside its limits, a missing mandatory object, 0x1003:0 read-only, a default
#: PDO mapping of entries not PDO-mappable.
EDS_SELF_CONTRADICTIONS = {"dictionary.identity", "dictionary.limits",
                           "dictionary.mandatory", "emcy.error_history",
                           "pdo.own_mappings"}


def _commissioned_id(od: eds.ObjectDictionary) -> int | None:
    text = {k.lower(): v for k, v in (od.device_commissioning or {}).items()}.get("nodeid")
    return int(text, 0) if text else None


@pytest.mark.slow  # a full run per file (virtual time)
def test_devices_of_real_eds_files() -> None:
    """The suite against a canola.Device made from each real EDS of ../shared/eds-corpus
    that canola loads as that device: it finishes, with no error of its own, and what
    fails is what the file contradicts itself in."""
    if not CORPUS.is_dir():
        pytest.skip(f"no corpus at {CORPUS}")
    ran = 0
    for path in sorted(CORPUS.glob("*.[de][dc][sf]")):
        try:
            od = eds.parse(path, node_id=NODE)
            if _commissioned_id(od) not in (None, NODE):
                continue  # a DCF of another node: its SDO COB-IDs are fixed
            bus = SimBus()
            Device(od, NODE, bus).start()
        except Error:
            continue  # canola refuses the file (test_eds pins why)
        report = cc.run(bus, NODE, od)
        ran += 1
        assert report.names(Status.FAILED) <= EDS_SELF_CONTRADICTIONS, (path.name,
                                                                        cc.markdown(report))
        assert not any("error of the tester" in f.got for r in report.results
                       for f in r.findings), (path.name, cc.markdown(report))
    assert ran >= 30
