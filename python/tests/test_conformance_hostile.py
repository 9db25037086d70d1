# SPDX-License-Identifier: Apache-2.0
"""canola.conformance against hostile nodes on the simulated bus, in virtual time (issue 35):
a segmented upload announcing 1 GiB, one without size that never ends, a block upload whose
sub-blocks never end, a block download acknowledged without progress, a flood of junk and
heartbeats, another node's SYNC. Each run ends with a verdict, in bounded memory; each
wait looks at a frame once; Ctrl-C gives the report of what ran."""

from __future__ import annotations

import signal
import tracemalloc
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest
from conformance_fakes import FAKE_EDS
from conformance_hostile import FLOOD_PER_MS, HostileNode

import canola.conformance as cc
from canola import Device, Master
from canola.conformance import Interrupted, Status
from canola.conformance.link import FRAMES_KEPT, Link
from canola.core import SimBus
from canola.formats import eds
from canola.master import Frame

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "example_od.eds"
NODE = 20
#: Peak memory of a run against a hostile node, at most (the tester's share: the frames it
#: keeps and one transfer's bytes; 47 -> 183 MB of RSS grew in 90 s before).
PEAK_BYTES = 40 << 20
#: A run that takes longer than this on the wall clock is a hang (they take 1-5 s).
WALL_LIMIT_S = 300


class WallLimit(BaseException):
    """A run that did not end (a BaseException: the tester, which reports an Exception of a
    check as its own error and goes on, cannot swallow it)."""


@contextmanager
def wall_limit(seconds: int) -> Iterator[None]:
    """Fail (WallLimit) instead of hanging when the block takes ``seconds``."""
    def expired(*_: object) -> None:
        raise WallLimit(f"still running after {seconds} s")

    previous = signal.signal(signal.SIGALRM, expired)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def _hostile_run(mode: str, only: list[str]) -> tuple[cc.Report, HostileNode, int, SimBus]:
    bus = SimBus()
    node = HostileNode(bus, NODE, mode)
    node.start()
    tracemalloc.start()
    try:
        with wall_limit(WALL_LIMIT_S):
            report = cc.run(bus, NODE, eds.parse(FAKE_EDS, node_id=NODE), only=only)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
        node.stop()
    return report, node, peak, bus


def _sent(bus: SimBus, frame: str) -> bool:
    return any(line.split()[-1] == frame for line in bus.trace)


#: mode -> (checks, the verdicts, the first finding's got (or note), the tester's abort)
HOSTILE = {
    "huge": (["dictionary.entries"], {"dictionary.entries": Status.PASSED},
             "0x2001:0 (A blob, rw DOMAIN) not read whole: upload 0x2001:0: 1073741824 bytes, "
             "more than the 16384 the tester takes", "614#8001200005000405"),
    "unsized": (["dictionary.entries"], {"dictionary.entries": Status.PASSED},
                "0x2001:0 (A blob, rw DOMAIN) not read whole: upload 0x2001:0: 16387 bytes, "
                "more than the 16384 the tester takes", "614#8001200005000405"),
    "endless_block": (["sdo.block_upload"], {"sdo.block_upload": Status.FAILED},
                      "block upload 0x2001:0: 16884 bytes, more than the 16384 the tester "
                      "takes", "614#8001200005000405"),
    "stalled_acks": (["sdo.block_download"], {"sdo.block_download": Status.FAILED},
                     "block download 0x2001:0 (1 bytes), sub-block ending at byte 1: 4 "
                     "sub-blocks in a row acknowledged with ackseq 0 (no progress)",
                     "614#8001200000000008"),
}


@pytest.mark.parametrize("mode", list(HOSTILE))
def test_every_hostile_transfer_ends_with_a_verdict(mode: str) -> None:
    """The raw SDO client stops at its bounds (bytes, segments, acknowledgements without
    progress), aborts the transfer (0x05040005: out of memory, or 0x08000000) and the
    check ends with a verdict; a DOMAIN too large to read whole is noted, not judged."""
    only, verdicts, said, abort = HOSTILE[mode]
    report, node, peak, bus = _hostile_run(mode, only)
    assert {r.check.name: r.status for r in report.results} == verdicts, cc.markdown(report)
    result = report.result(only[0])
    text = result.findings[0].got if result.findings else result.notes[0]
    assert text == said
    assert _sent(bus, abort)
    assert node.served > 0 or mode == "huge"
    assert peak < PEAK_BYTES


def test_a_flood_does_not_stop_the_run() -> None:
    """3000 frames/s of junk on the node's SDO answer COB-ID and heartbeats: every check
    ends with a verdict (junk taken for an answer is a finding), in bounded memory."""
    report, _, peak, bus = _hostile_run("flood", ["dictionary", "sdo", "nmt"])
    checks = cc.select(["dictionary", "sdo", "nmt"])
    assert [r.check.name for r in report.results] == [c.name for c in checks]
    assert report.count(Status.PASSED) >= 15, cc.markdown(report)
    assert "got [EE 01 20 00 DE AD BE EF]" in report.result("sdo.client_abort").summary
    assert bus.now_us / 1000 * FLOOD_PER_MS > 5000  # the frames the tester saw
    assert peak < PEAK_BYTES


def _port(bus: SimBus, node_id: int = 99) -> Master:
    port = Master(bus, node_id)
    port.start()
    return port


def test_the_link_keeps_bounded_memory_and_looks_at_each_frame_once() -> None:
    """A flood of 3 x FRAMES_KEPT frames of another node during one wait: at most
    2 x FRAMES_KEPT are kept (the oldest go), none in the trace, and the wait asks its
    match about each frame once (it copied every frame since its mark at each look before:
    quadratic)."""
    bus = SimBus()
    link = Link(_port(bus, 127), NODE)
    flood = _port(bus)
    engine = flood._engine
    sent = [0]
    timers: list[object] = []

    def burst() -> None:  # 1000 frames a millisecond, then the node's heartbeat
        for _ in range(1000):
            flood.send(0x123, sent[0].to_bytes(4, "little"))
            sent[0] += 1
        if sent[0] == 3 * FRAMES_KEPT:
            engine.remove_timer(timers[0])
            flood.send(0x700 + NODE, b"\x05")

    looked = [0]

    def match(frame: Frame) -> bool:
        looked[0] += 1
        return frame.can_id == 0x700 + NODE

    mark = link.mark()
    timers.append(engine.add_timer(1000, burst))
    seen = link.wait_frame(match, 1.0, mark)
    assert seen is not None and seen.frame.data == b"\x05"
    assert len(link._frames) <= 2 * FRAMES_KEPT
    assert link.mark() - mark == 3 * FRAMES_KEPT + 1
    assert looked[0] <= 3 * FRAMES_KEPT + 1
    assert link.others >= 3 * FRAMES_KEPT  # another node's: not in the trace
    assert len(link.trace()) == 1 and " <- 714  05 " in link.trace()[0]


def test_another_sync_producer_makes_the_sync_checks_inconclusive() -> None:
    """Another node produces SYNC every 10 ms on 0x080: the node under test takes those
    too, so the checks that count what it does per SYNC say they cannot judge it (they
    failed before: TPDOs counted for the tester's SYNCs); the others pass."""
    od = eds.parse(EXAMPLE, node_id=5)
    bus = SimBus()
    Device(od, 5, bus).start()
    other = Device(EXAMPLE, 9, bus)
    other.start()
    other.od.write(0x1006, 0, (10_000).to_bytes(4, "little"))
    other.od.write(0x1005, 0, (0x40000080).to_bytes(4, "little"))
    sync_checks = ["pdo.tpdo_sync_cyclic", "pdo.tpdo_sync_acyclic", "sync.start_value",
                   "sync.producer"]
    # pdo.rpdo_sync passes: no SYNC of the other came between its RPDO and the read-back
    report = cc.run(bus, 5, od, only=[*sync_checks, "pdo.rpdo_sync", "pdo.tpdo_event_timer",
                                      "nmt.states"])
    assert report.names(Status.FAILED) == set(), cc.markdown(report)
    assert report.names(Status.SKIPPED) == set(sync_checks)
    for name in sync_checks:
        assert report.result(name).reason.startswith(
            "inconclusive: another node sends SYNC on 0x080"), name


def test_ctrl_c_gives_the_report_of_what_ran() -> None:
    """Ctrl-C during the third check: Interrupted (a KeyboardInterrupt) carries the report
    of the two checks before, the interrupted check's changes put back and the node's
    state restored."""
    bus = SimBus()
    dev = Device(EXAMPLE, 5, bus)
    dev.start()
    before = {key: dev.od.read(*key) for key in dev.od}

    def progress(done: int, total: int, check: cc.Check, result: cc.Result | None) -> None:
        if check.name == "nmt.heartbeat_period" and result is None:
            bus.run_for(150_000)  # the check would have begun: 0x1017 written
            raise KeyboardInterrupt

    with pytest.raises(Interrupted) as stop:
        cc.run(bus, 5, EXAMPLE, only=["nmt.states", "nmt.sdo_gating",
                                      "nmt.heartbeat_period", "nmt.node_guarding"],
               progress=progress)
    assert isinstance(stop.value, KeyboardInterrupt)
    report = stop.value.report
    assert [r.check.name for r in report.results] == ["nmt.states", "nmt.sdo_gating"]
    assert report.interrupted == "nmt.heartbeat_period"
    assert report.notes[-1] == ("interrupted (Ctrl-C) during nmt.heartbeat_period: 2 of 4 "
                                "checks ran")
    assert cc.verdict(report) == "INTERRUPTED"
    assert "- result: **INTERRUPTED** (2 passed, 0 failed, 0 skipped)" in cc.markdown(report)
    assert {k for k in before if dev.od.read(*k) != before[k]} == set()
    assert dev.nmt_state == "PRE-OPERATIONAL"
