# SPDX-License-Identifier: Apache-2.0
"""canola.conformance against two CANopenNode devices, canopend and CANopenDemo's demoDevice,
as scripted nodes on the simulated bus in virtual time (canopennode_models.py: MODELLED on
what issue 34 observed of them, not recorded). The tester reports only their true
deviations from CiA 301, each naming its clause; every verdict it got wrong against them
before is pinned here as it is now (the frames or notes that show why)."""

from __future__ import annotations

from pathlib import Path

import pytest
from canopennode_models import NODE, CanopenNodeModel, canopend_od, demo_od

import canola.conformance as cc
from canola.conformance import Options, Status
from canola.core import SimBus
from canola.formats import eds

#: What CANopenNode does against CiA 301, as the tester finds it: (the first finding's
#: what, expected, got, the clause it names).
TRUE_DEVIATIONS = {
    # CANopenLinux loads defaults and stored parameters only at its start
    "nmt.reset_comm_values": (
        "0x1017:0 (Producer heartbeat time, rw UNSIGNED16) after NMT reset-comm", "0", "1000",
        "CiA 301 §7.3.2.2.1: NMT reset-comm sets the communication parameters to their "
        "power-on values (defaults, or stored ones)"),
    "nmt.store_restore": (
        "0x1017:0 (Producer heartbeat time, rw UNSIGNED16) after save and reset "
        "communication", "1000", "1001",
        "CiA 301 §7.5.2.13: the values saved are the power-on values of the next reset "
        "communication"),
    # a communication error sets bit 4 of the error register, not bit 0 with it
    "emcy.heartbeat_loss": (
        "EMCY error register byte", "0x1001 (now 0x10), generic bit set", "0x10",
        "CiA 301 §7.5.2.2: bit 0 (generic error) is set with any error; the EMCY carries "
        "0x1001 (§7.2.7)"),
}
DICTIONARIES = {"canopend": canopend_od, "demoDevice": demo_od}


def _run(od: eds.ObjectDictionary, *, tester_od: eds.ObjectDictionary | None = None,
         store_dir: Path | None = None, only: tuple[str, ...] = (),
         **model: bool) -> tuple[cc.Report, CanopenNodeModel]:
    bus = SimBus()
    device = CanopenNodeModel(bus, od, store_dir=store_dir, **model)
    with pytest.MonkeyPatch.context() as patch:
        device.install(patch)
        report = cc.run(bus, NODE, tester_od or od, only=only,
                        options=Options(destructive=store_dir is not None))
    return report, device


@pytest.mark.parametrize("name", list(DICTIONARIES))
def test_only_the_true_deviations_fail(tmp_path: Path, name: str) -> None:
    """Every check, destructive ones too: the three true deviations fail, each with its
    clause; everything else passes (nothing skipped)."""
    report, _ = _run(DICTIONARIES[name](), store_dir=tmp_path)
    assert report.names(Status.FAILED) == set(TRUE_DEVIATIONS), cc.markdown(report)
    assert report.count(Status.PASSED) == len(cc.CHECKS) - len(TRUE_DEVIATIONS)
    for check, (what, expected, got, clause) in TRUE_DEVIATIONS.items():
        first = report.result(check).findings[0]
        assert (first.what, first.expected, first.got, first.clause) == (
            what, expected, got, clause), check
        assert f"[{clause}]" in report.result(check).summary
    text = cc.markdown(report)
    assert "  - clause: CiA 301 §7.5.2.2: bit 0 (generic error) is set" in text
    assert "| `nmt.reset_comm_values` | CiA 301 §7.3.2.2.1 (reset communication) | FAILED |" in text


def test_an_empty_error_history_has_no_data() -> None:
    """0x1003:1..8 with 0x1003:0 = 0 aborted with 0x08000024 pass (CiA 301 §7.5.2.4; the
    tester flagged every one before); read as 0, as canola's own core did, they fail."""
    report, _ = _run(canopend_od(), only=("dictionary.entries",))
    assert report.names(Status.PASSED) == {"dictionary.entries"}, cc.markdown(report)
    report, _ = _run(canopend_od(), only=("dictionary.entries",),
                     history_reads_zero=True)
    findings = report.result("dictionary.entries").findings
    assert [f.what[:9] for f in findings] == [f"read 0x1003:{n}"[:9] for n in range(1, 9)]
    assert findings[0].what == ("read 0x1003:1 (Standard error field 1, ro UNSIGNED32) "
                                "(0x1003:0 = 0)")
    assert (findings[0].expected, findings[0].got, findings[0].clause) == (
        "abort 0x08000024 (No data available) or abort 0x08000000 (General error)",
        "the value 0x0", "CiA 301 §7.5.2.4 (no error recorded there: no data)")
    assert any("<- 585  43 03 10 01 00 00 00 00" in line for line in findings[0].frames)


def test_probes_go_where_the_eds_says_they_are_taken() -> None:
    """demoDevice's DOMAIN 0x2122 takes only its own byte sequence: the series go through
    its string 0x2121:2 (every probe into 0x2122 was refused with 0x06090030 before, six
    checks failed), and what no entry takes is not applicable, with the reason."""
    sdo = ("sdo.segmented_download", "sdo.segmented_upload", "sdo.block_download",
           "sdo.block_upload", "sdo.block_crc", "sdo.block_size")
    report, device = _run(demo_od(), only=sdo)
    assert report.names(Status.PASSED) == set(sdo), cc.markdown(report)
    string = "0x2121:2 (String long, rw VISIBLE_STRING)"
    assert report.result("sdo.segmented_download").notes == [
        f"{string}: 1, 4, 5, 7, 8, 14, 15, 21, 22 bytes"]
    block = report.result("sdo.block_download").notes
    assert block[0] == f"{string}: 1, 4, 5, 7, 8, 14, 15, 21, 22 bytes"
    assert block[1].startswith(
        f"not applicable: 889, 890 bytes, refused by the application (889 bytes to {string}: "
        "abort 0x06070012 (Data type does not match, length of service parameter too high)")
    assert device.domain.value == bytes(i % 256 for i in range(1024))  # as it was


def test_a_domain_alone_that_refuses_every_probe_is_not_applicable() -> None:
    """With only the DOMAIN in the EDS: its own value goes through instead of the probes;
    a block download with a wrong CRC carries its own value too."""
    tester = demo_od()
    del tester.objects[0x2121]
    report, _ = _run(demo_od(), tester_od=tester,
                     only=("sdo.segmented_download", "sdo.block_crc"))
    assert report.names(Status.PASSED) == {"sdo.segmented_download", "sdo.block_crc"}, (
        cc.markdown(report))
    assert report.result("sdo.segmented_download").notes[0].startswith(
        "0x2122:0 (Demo domain, rw DOMAIN): its own 1024 bytes (the probes were refused: "
        "1 bytes to 0x2122:0 (Demo domain, rw DOMAIN): abort 0x06090030")


def test_a_segmented_download_announces_what_the_string_holds() -> None:
    """sdo.toggle_download to demoDevice's 3-byte string 0x2121:1 announced 14 bytes before
    (answered 0x06070012, rightly: a false FAIL); it announces the 3 the string holds, and
    the wrong toggle bit is what the node answers."""
    tester = demo_od()
    del tester.objects[0x2122]
    del tester.objects[0x2121].subs[2]
    del tester.objects[0x2121].subs[3]
    report, device = _run(demo_od(), tester_od=tester, only=("sdo.toggle_download",))
    assert report.names(Status.PASSED) == {"sdo.toggle_download"}, cc.markdown(report)
    frames = [line.split()[-1] for line in device.bus.trace]
    at = frames.index("605#2121210103000000")  # initiate: 3 bytes
    assert frames[at + 1:at + 4] == ["585#6021210100000000", "605#1963616E00000000",
                                     "585#8021210100000305"]  # toggle 1: aborted 0x05030000


def test_it_acts_once_the_node_reports_the_state() -> None:
    """canopend enters OPERATIONAL 30 ms after the command and takes RPDOs at once: the
    tester sent its RPDO 2-9 ms after 'start' before (not applied: a false FAIL); it waits
    for the heartbeat that says OPERATIONAL."""
    report, _ = _run(canopend_od(),
                     only=("nmt.pdo_gating", "nmt.sdo_gating", "pdo.rpdo_applied",
                           "pdo.rpdo_sync", "sync.start_value", "nmt.node_guarding"))
    assert report.names(Status.FAILED) == set(), cc.markdown(report)
    assert report.result("nmt.node_guarding").notes == ["toggles 0 1 0 1 0 1 0 1 0"]
