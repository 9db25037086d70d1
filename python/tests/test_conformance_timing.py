"""canola.conformance's verdicts on a late node, in virtual time: a frame the node sends
late (as a node starved of CPU does on a busy host) still counts for the SYNC or reset it
answers, and a frame too many is still found however late it comes.

The tester's link sees chosen frames of canola.Device late (they are held back on their
way to the tester and delivered after a delay, after frames the node sent later): the
tester's view of a starved node."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

import canola.conformance as cc
from canola import Device
from canola.conformance import Status
from canola.conformance.link import Link
from canola.core import SimBus
from canola.master import Frame

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "example_od.eds"
NODE = 5
TPDO1 = 0x180 + NODE
#: Later than the tester's ``quiet`` window (0.5 s), sooner than its answer time-out (2 s).
LATE_US = 700_000


def _late_link(monkeypatch: pytest.MonkeyPatch, match: Callable[[Frame], bool],
               plan: Iterator[tuple[bool, bool]]) -> None:
    """For each frame that ``match``es, the next item of ``plan`` (``late``, ``twice``):
    deliver it to the tester :data:`LATE_US` later; ``twice``: at once and again later (a
    frame too many that comes late)."""
    received = Link._received

    def delivered(self: Link, frame: Frame) -> None:
        late, twice = next(plan, (False, False)) if match(frame) else (False, False)
        if not late:
            received(self, frame)
            if not twice:
                return
        engine = self.master._engine
        timers = []

        def later() -> None:
            engine.remove_timer(timers[0])
            received(self, frame)

        timers.append(engine.add_timer(LATE_US, later))

    monkeypatch.setattr(Link, "_received", delivered)


def _run(only: list[str]) -> cc.Report:
    bus = SimBus()
    Device(EXAMPLE, NODE, bus).start()
    return cc.run(bus, NODE, EXAMPLE, only=only)


SYNC_CHECKS = ["pdo.tpdo_sync_cyclic", "sync.start_value"]


def test_a_late_tpdo_counts_for_its_sync(monkeypatch: pytest.MonkeyPatch) -> None:
    """The first TPDO of each check comes 0.7 s after its SYNC, the others at once: the
    tester waits for it before the next SYNC (sampling after a fixed window counted it for
    the next SYNC: 0 1 1 0 1 0)."""
    plan = iter([(True, False), *[(False, False)] * 3] * 2)
    _late_link(monkeypatch, lambda f: f.can_id == TPDO1, plan)
    report = _run(SYNC_CHECKS)
    assert report.names(Status.FAILED) == set(), cc.markdown(report)
    assert report.result("pdo.tpdo_sync_cyclic").notes == ["TPDO1 on 0x185: 0 1 0 1 0 1"]
    assert report.result("sync.start_value").notes == ["TPDO1: 0 0 1 1 1 1"]


def test_a_late_tpdo_too_many_is_found(monkeypatch: pytest.MonkeyPatch) -> None:
    """The node sends a TPDO twice, the copy late: the copy counts for the SYNC after."""
    plan = iter([(False, False), (False, True), (False, False),  # tpdo_sync_cyclic
                 (False, True), *[(False, False)] * 3])  # start_value
    _late_link(monkeypatch, lambda f: f.can_id == TPDO1, plan)
    report = _run(SYNC_CHECKS)
    assert report.names(Status.FAILED) == set(SYNC_CHECKS), cc.markdown(report)
    got = {name: report.result(name).findings[0].got for name in SYNC_CHECKS}
    assert got == {"pdo.tpdo_sync_cyclic": "0 1 0 1 1 1", "sync.start_value": "0 0 1 2 1 1"}
