# SPDX-License-Identifier: Apache-2.0
"""canola.conformance against RECORDED frames of real CANopenNode devices (data/traces/*.log,
canopennode_traces.py), not against models: every verdict of issue 34, right and wrong,
pinned on what the real device sent.

- the SDO-only checks are replayed: :class:`ReplayNode` answers the tester's requests with
  the device's recorded answers and the tester judges them (a check that relied on a wrong
  expectation would fail here on the device's own frames);
- the NMT, heartbeat, EMCY and PDO checks depend on the tester's timing, so their verdicts
  are pinned by asserting from the trace what the device did (the answer, the state in its
  heartbeat after NMT start and when, 0x1017 after reset communication, the EMCY's
  register byte), with the verdict the recorded run gave.

The traces: canopend's full run, demoDevice's full run, and demoDevice with only its 3-byte
string or only its DOMAIN in the EDS (where issue 34's false SDO verdicts came from). Live
interaction (the tester's waits, RPDOs before the state change) stays with the scripted
models of test_conformance_canopennode.py.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from pathlib import Path

import pytest
from canopennode_dictionaries import EDS
from canopennode_traces import NODE, ReplayNode, answers, header, load

import canola.conformance as cc
from canola.conformance import Status
from canola.core import SimBus
from canola.formats import eds

#: The checks of the recorded run whose requests and answers are SDO frames only, in the
#: order the tester runs them (the replay follows the recorded run from its start).
SDO_ONLY = ("dictionary.mandatory", "dictionary.entries", "dictionary.read_write_only",
            "dictionary.write_read_only", "dictionary.length_too_long",
            "dictionary.length_too_short", "dictionary.limits", "dictionary.missing_object",
            "dictionary.missing_sub", "dictionary.device_type", "dictionary.identity",
            "dictionary.constants", "sdo.expedited_upload", "sdo.expedited_download",
            "sdo.segmented_download", "sdo.segmented_upload", "sdo.toggle_download",
            "sdo.toggle_upload", "sdo.unknown_command", "sdo.client_abort",
            "sdo.server_timeout", "sdo.block_download", "sdo.block_upload",
            "sdo.block_crc", "sdo.block_size")


TRACES = ("canopend", "demodevice")
CORPUS = Path(__file__).resolve().parents[2] / ".." / "shared" / "eds-corpus"


def _abort(frame: bytes) -> int | None:
    return int.from_bytes(frame[4:8], "little") if frame[0] == 0x80 else None


Table = dict[bytes, deque[list[bytes]]]


def _replayed(name: str, *, od: eds.ObjectDictionary | None = None,
              only: tuple[str, ...] = SDO_ONLY,
              edit: Callable[[Table], None] | None = None) -> tuple[cc.Report, ReplayNode]:
    """The checks ``only`` run against the device of trace ``name`` (its EDS, or ``od``),
    replayed; ``edit`` changes recorded answers first."""
    bus = SimBus()
    node = ReplayNode(bus, load(name))
    if edit is not None:
        edit(node.table)
    node.start()
    if od is None:
        od = eds.parse(EDS[name](), node_id=NODE)
    return cc.run(bus, NODE, od, only=only), node


def _answered(request: str, reply: str) -> Callable[[Table], None]:
    """An edit: the first time ``request`` comes, ``reply`` answers it (hex)."""
    def edit(table: Table) -> None:
        table[bytes.fromhex(request)][0][:] = [bytes.fromhex(reply)]
    return edit


@pytest.mark.parametrize("name", TRACES)
def test_the_trace_says_where_it_comes_from(name: str) -> None:
    """The header names the device, the upstream commits and how the run was made."""
    text = header(name)
    for fact in ("candump -L", "CANopenLinux", "CANopenNode", "canola conformance",
                 "--destructive", "Run 1 of 2", "Run 2"):
        assert fact in text


def _entries(od: eds.ObjectDictionary) -> dict[tuple[int, int], tuple[object, ...]]:
    return {(i, s): (v.name, v.data_type, v.access_type, v.default, v.pdo_mapping,
                     v.low_limit, v.high_limit)
            for i, obj in od.objects.items() for s, v in obj.subs.items()}


def test_the_replayed_dictionary_is_demodevice_eds() -> None:
    """The dictionary the demoDevice replay gives the tester is demoDevice.eds's, entry by
    entry (names, types, access, defaults, PDO mapping, limits), and so are the
    [DeviceInfo] keys it gives, where ../shared has the file."""
    path = CORPUS / "CANopenNode__CANopenDemo__demoDevice.eds"
    if not path.is_file():
        pytest.skip("../shared/eds-corpus is not here")
    real = eds.parse(path.read_text(encoding="utf-8"), node_id=NODE)
    replayed = eds.parse(EDS["demodevice"](), node_id=NODE)
    assert _entries(replayed) == _entries(real)
    for key, value in replayed.device_info.items():
        assert real.device_info[key] == value


@pytest.mark.parametrize("name", TRACES)
def test_an_empty_error_history_is_answered_no_data(name: str) -> None:
    """Both devices answer 0x1003:0 with 0 and 0x1003:1..16 with abort 0x08000024, as CiA
    301 §7.5.2.4 prescribes (the tester flagged these 16 answers before issue 34's fix)."""
    table = answers(load(name))
    count = table[bytes.fromhex("4003100000000000")][0]
    assert count == [bytes.fromhex("4F03100000000000")]
    for sub in range(1, 17):
        request = bytes([0x40, 0x03, 0x10, sub, 0, 0, 0, 0])
        (reply,) = table[request][0]
        assert reply[:4] == bytes([0x80, 0x03, 0x10, sub]) and _abort(reply) == 0x08000024


def test_the_sdo_checks_judge_the_recorded_answers() -> None:
    """The SDO-only checks replayed on canopend's own answers: all pass or are skipped for
    the reason the EDS gives (no string, no entry longer than 4 bytes), none fails; every
    request of the tester found its recorded answer."""
    report, node = _replayed("canopend")
    assert report.names(Status.FAILED) == set(), cc.markdown(report)
    assert node.missed == []
    assert "dictionary.entries" in report.names(Status.PASSED)
    assert report.result("sdo.segmented_download").summary.endswith(
        "the EDS has no readable and writable entry longer than 4 bytes")


def test_demodevice_fails_only_on_its_empty_software_version() -> None:
    """demoDevice's SDO checks replayed on its own answers: every request found its recorded
    answer (so no probe went to the DOMAIN 0x2122, which takes only its own byte sequence:
    the segmented and block checks wrote the 1000-byte string 0x2121:2, every length taken);
    the one failure is a TRUE deviation: 0x100A (VISIBLE_STRING, empty in this build) read
    is aborted with 0x06040047, where CiA 301 lets an upload carry 0 bytes."""
    report, node = _replayed("demodevice")
    assert node.missed == []
    assert report.names(Status.FAILED) == {"dictionary.entries"}, cc.markdown(report)
    (finding,) = report.result("dictionary.entries").findings
    assert "0x100A:0" in finding.what and "0x06040047" in finding.got
    assert "CiA 306 §4.5.2" in report.result("dictionary.entries").check.clause
    for name in ("sdo.segmented_download", "sdo.block_download", "sdo.block_upload"):
        assert report.result(name).status is Status.PASSED
        assert report.result(name).summary.startswith("0x2121:2 (String long")
    assert "sdo.toggle_download" in report.names(Status.PASSED)
    downloads = [f.data for f in load("demodevice") if f.cob == 0x600 + NODE
                 and f.data[0] >> 5 in (1, 6) and f.data[1:4] == b"\x22\x21\x00"]
    assert downloads == []  # 0x2122 only read


def test_the_toggle_download_announces_what_the_string_holds() -> None:
    """Issue 34's false verdict, pinned on demoDevice's frames: sdo.toggle_download once
    announced 14 bytes to the 3-byte string 0x2121:1 (rightly refused with 0x06070012);
    now it announces the 110 bytes 0x2121:2 read as, the device takes the transfer (60) and
    answers the first segment's wrong toggle bit with 0x05030000."""
    frames = _texts("demodevice")
    initiate = next(i for i, (_, t) in enumerate(frames) if t == "605#212121026E000000"
                    and frames[i + 2][1].startswith("605#10"))  # toggle 1 on segment 1
    assert _answer(frames, initiate) == "585#6021210200000000"
    assert _answer(frames, initiate + 2) == "585#8021210200000305"
    upload = _after(frames, 0, "605#4021210200000000")
    assert _answer(frames, upload) == "585#41212102" + (110).to_bytes(4, "little").hex().upper()
    assert not [t for _, t in frames if t.startswith("605#21212101")]


@pytest.mark.parametrize("name, check", [("canopend", "dictionary.entries"),
                                         ("canopend", "sdo.block_download"),
                                         ("demodevice", "sdo.toggle_download")])
def test_a_replayed_check_fails_when_the_device_answers_otherwise(name: str, check: str) -> None:
    """The replay is a real test: the same run with one recorded answer changed (0x1003:1
    read as the value 0, as canola's core once answered; the block download's end not
    confirmed; the segment with the wrong toggle bit taken) makes the tester fail that
    check."""
    def edit(table: Table) -> None:
        if check == "dictionary.entries":
            _answered("4003100100000000", "4303100100000000")(table)
        elif check == "sdo.block_download":
            end = next(k for k in table if k[0] & 0xE3 == 0xC1)
            table[end][0][:] = []
        else:
            wrong = next(k for k, v in table.items() if v and v[0] == [
                bytes.fromhex("8021210200000305")])
            _answered(wrong.hex(), "2021210200000000")(table)

    report, _ = _replayed(name, edit=edit)
    assert check in report.names(Status.FAILED), cc.markdown(report)


@pytest.mark.parametrize("answer", ["430A100076342E30", "800A100024000008"])
def test_demodevice_passes_with_a_software_version_or_no_data(answer: str) -> None:
    """The other way round: with 0x100A answered as a 4-byte string, as a tagged build of
    CANopenDemo would, or aborted with 0x08000024 (no data: the abort CiA 301 has for an
    empty value), demoDevice's dictionary.entries passes."""
    report, _ = _replayed("demodevice", only=("dictionary.mandatory", "dictionary.entries"),
                          edit=_answered("400A100000000000", answer))
    assert report.names(Status.PASSED) == {"dictionary.mandatory", "dictionary.entries"}


# ---- demoDevice's strings and DOMAIN alone in the EDS (data/traces/demodevice_*.log): where
# issue 34's false verdicts came from, on the real device's frames

PROBES = ("sdo.segmented_download", "sdo.toggle_download", "sdo.block_download",
          "sdo.block_crc")


def _demo_without(*entries: tuple[int, int | None]) -> eds.ObjectDictionary:
    """demoDevice's dictionary less the objects (sub None) and sub-indices given."""
    od = eds.parse(EDS["demodevice"](), node_id=NODE)
    for index, sub in entries:
        if sub is None:
            del od.objects[index]
        else:
            del od.objects[index].subs[sub]
    return od


def test_the_3_byte_string_is_announced_3_bytes() -> None:
    """Issue 34: sdo.toggle_download announced 14 bytes to demoDevice's 3-byte string
    0x2121:1 (rightly refused, 0x06070012: a false FAIL). With that string alone in the EDS
    the real device takes the 3 bytes announced, answers the wrong toggle bit with
    0x05030000, and refuses the longer probes with 0x06070012: not applicable, with the
    reason; every check passes on its recorded answers."""
    report, node = _replayed("demodevice_short_string", only=PROBES,
                             od=_demo_without((0x2121, 2), (0x2121, 3), (0x2122, None)))
    assert node.missed == []
    assert report.names(Status.PASSED) == set(PROBES), cc.markdown(report)
    assert "not applicable: 4, 5, 7, 8, 14, 15, 21, 22 bytes" in report.result(
        "sdo.segmented_download").summary
    assert "0x06070012" in report.result("sdo.segmented_download").summary
    frames = [t for _, t in _texts("demodevice_short_string")]
    at = frames.index("605#2121210103000000")  # initiate: 3 bytes
    assert frames[at + 1:at + 4] == ["585#6021210100000000", "605#1963616E00000000",
                                     "585#8021210100000305"]  # toggle 1: aborted 0x05030000


def test_the_domain_refuses_probes_and_takes_its_own_value() -> None:
    """Issue 34: the segmented and block checks wrote probe text into the DOMAIN 0x2122,
    whose application takes only its own byte sequence and refuses the rest with
    0x06090030 (six false FAILs). With the DOMAIN alone in the EDS the real device refuses
    every probe so, and takes its own 1024 bytes: the checks pass on that, the refusal
    named."""
    report, node = _replayed("demodevice_domain", only=PROBES,
                             od=_demo_without((0x2121, None)))
    assert node.missed == []
    assert report.names(Status.PASSED) == set(PROBES), cc.markdown(report)
    for name in ("sdo.segmented_download", "sdo.block_download"):
        assert report.result(name).summary.startswith(
            "0x2122:0 (Demo domain, rw DOMAIN): its own 1024 bytes (the probes were refused: "
            "1 bytes to 0x2122:0 (Demo domain, rw DOMAIN): abort 0x06090030")
    refusals = [t for _, t in _texts("demodevice_domain") if t == "585#8022210030000906"]
    assert len(refusals) == 2


def test_a_refusal_that_is_no_application_s_fails() -> None:
    """The replay can fail: the DOMAIN's first refusal answered with 0x05040001 (command
    specifier not valid: the SDO protocol, not the application) fails the check."""
    frames = _texts("demodevice_domain")
    refusal = frames.index(next(f for f in frames if f[1] == "585#8022210030000906"))
    request = next(t for _, t in reversed(frames[:refusal]) if t.startswith("605#"))[4:]
    report, _ = _replayed("demodevice_domain", only=PROBES, od=_demo_without((0x2121, None)),
                          edit=_answered(request, "8022210001000405"))
    assert "sdo.segmented_download" in report.names(Status.FAILED), cc.markdown(report)


# ---- the verdicts that rest on the tester's timing: asserted from the recorded frames

def _texts(name: str) -> list[tuple[float, str]]:
    return [(f.t, f.text) for f in load(name)]


def _after(frames: list[tuple[float, str]], start: int, text: str) -> int:
    """The position of the first frame ``text`` at or after ``start``."""
    return next(i for i in range(start, len(frames)) if frames[i][1] == text)


def _answer(frames: list[tuple[float, str]], request: int) -> str:
    """The device's SDO frame that answered the request at position ``request``."""
    return next(t for _, t in frames[request + 1:] if t.startswith("585#"))


def _read_after(frames: list[tuple[float, str]], start: int, index: int) -> bytes:
    """The first expedited answer to a read of ``index``:0 after ``start``."""
    request = f"605#40{index & 0xFF:02X}{index >> 8:02X}0000000000"
    return bytes.fromhex(_answer(frames, _after(frames, start, request))[4:])


@pytest.mark.parametrize("name", TRACES)
def test_reset_communication_keeps_a_written_heartbeat_time(name: str) -> None:
    """A TRUE deviation (nmt.reset_comm_values, CiA 301 §7.3.2.2.1), on both devices: the
    device takes 0x1017 = 1000, is reset (NMT reset communication, its boot-up follows) and
    still reads 1000, where its power-on value is its EDS default 0 (nothing stored)."""
    frames = _texts(name)
    write = _after(frames, 0, "605#2B171000E8030000")
    assert _answer(frames, write) == "585#6017100000000000"
    reset = _after(frames, write, "000#8205")
    boot = _after(frames, reset, "705#00")
    assert _read_after(frames, boot, 0x1017)[:6] == bytes.fromhex("4B171000E803")
    default = eds.parse(EDS[name](), node_id=NODE).objects[0x1017].subs[0].default
    assert default == 0


@pytest.mark.parametrize("name", TRACES)
def test_a_saved_value_is_not_what_reset_communication_restores(name: str) -> None:
    """A TRUE deviation (nmt.store_restore, CiA 301 §7.5.2.13), on both devices: the device
    confirms 'save' of 1000, takes 1001 after it, and after reset communication reads 1001,
    not the saved 1000 (CANopenLinux loads stored values only at its start)."""
    frames = _texts(name)
    save = next(i for i, (_, t) in enumerate(frames)
                if t.startswith("605#231010") and t.endswith("73617665"))
    assert _answer(frames, save).startswith("585#601010")
    saved = _after(frames, 0, "605#2B171000E8030000")
    assert saved < save
    newer = _after(frames, save, "605#2B171000E9030000")
    reset = _after(frames, newer, "000#8205")
    boot = _after(frames, reset, "705#00")
    assert _read_after(frames, boot, 0x1017)[:6] == bytes.fromhex("4B171000E903")


@pytest.mark.parametrize("name, read, before, applied", [
    ("canopend", "605#4080120100000000", "585#4380120100000080", "585#4380120101000080"),
    ("demodevice", "605#4000620100000000", "585#4F00620100000000", "585#4F00620101000000")])
def test_the_rpdo_counts_once_the_heartbeat_says_operational(
        name: str, read: str, before: str, applied: str) -> None:
    """The tester's timing, pinned on both devices (nmt.pdo_gating PASSED): the RPDO (mapped
    to canopend's 0x1280:1, to demoDevice's outputs 0x6200:1..2) sent in PRE-OPERATIONAL and
    in STOPPED is not applied, the one sent after NMT start went out only after the
    heartbeat reported OPERATIONAL (issue 34: the tester sent it 2-9 ms after 'start',
    before the node's state changed) and is applied."""
    frames = _texts(name)
    applied_at = next(i for i, (_, t) in enumerate(frames) if t == applied)
    rpdo = max(i for i in range(applied_at) if frames[i][1].startswith("205#"))
    start = max(i for i in range(rpdo) if frames[i][1] == "000#0105")
    beat = _after(frames, start, "705#05")
    assert start < beat < rpdo
    assert 0 < frames[beat][0] - frames[start][0] < 0.1
    earlier = [i for i in range(start) if frames[i][1].startswith("205#")][-2:]
    assert len(earlier) == 2
    for at in earlier:
        assert _answer(frames, _after(frames, at, read)) == before  # not applied


@pytest.mark.parametrize("name", TRACES)
def test_the_heartbeat_loss_emcy_lacks_the_generic_bit(name: str) -> None:
    """A TRUE deviation (emcy.heartbeat_loss, CiA 301 §7.5.2.2), on both devices: the EMCY
    0x8130 for the heartbeat consumer time-out carries the error register 0x10, bit 0
    (generic error) clear; its reset EMCY follows with 0x00."""
    frames = _texts(name)
    emcys = [t for _, t in frames if t[:4] in ("085#", "086#")]
    losses = [bytes.fromhex(t[4:]) for t in emcys if t[4:8] == "3081"]
    assert losses and all(d[2] == 0x10 for d in losses)
    assert any(t[4:].startswith("000000") for t in emcys)
