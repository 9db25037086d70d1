# SPDX-License-Identifier: Apache-2.0
"""canola._linkbase.LinkBase: the two kinds of link (python-can's, the C link) implement
every method the base leaves to them, and a kind that leaves one out fails when it is
made, not when the first frame or call reaches the missing method; a node's stop runs
the callbacks queued before it."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import can
import pytest

from canola import Device
from canola._linkbase import LinkBase
from canola._native import NativeLink
from canola._pylink import Link

INTEROP = Path(__file__).parent / "data" / "interop.eds"


def test_both_kinds_implement_every_abstract_method() -> None:
    assert LinkBase.__abstractmethods__ >= {"now_us", "in_thread", "enter_app", "leave_app",
                                            "wait", "_start_thread", "_stop_thread"}
    assert Link.__abstractmethods__ == frozenset()
    assert NativeLink.__abstractmethods__ == frozenset()


def test_a_kind_missing_a_method_fails_when_made() -> None:
    class Incomplete(LinkBase):
        def now_us(self) -> int:
            return 0

    with pytest.raises(TypeError, match="abstract"):
        Incomplete(None, None)  # type: ignore[arg-type]


def test_callbacks_queued_before_stop_run_before_it_returns() -> None:
    """A callback the link's thread queued but had not run when the node stopped (a loaded
    machine: ``canola device`` stopped by SIGTERM right after its EMCY) still runs."""
    bus = can.Bus(interface="virtual", channel=f"linkbase-{time.monotonic_ns()}")
    try:
        device = Device(INTEROP, 5, bus)
        device.start()
        link = device._engine.link
        assert link is not None
        link.dispatch = lambda: None  # type: ignore[method-assign]  # its thread runs none
        told: list[str] = []
        link.later(lambda: told.append("EMCY"))
        stop_thread = link._stop_thread

        def stopped_then_dispatching(engine: Any, timeout: float) -> None:
            stop_thread(engine, timeout)  # the thread is gone, the callback still queued
            del link.dispatch  # type: ignore[method-assign]
        link._stop_thread = stopped_then_dispatching  # type: ignore[method-assign]
        device.stop()
        assert told == ["EMCY"]
    finally:
        bus.shutdown()
