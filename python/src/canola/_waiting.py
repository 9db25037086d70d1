# SPDX-License-Identifier: Apache-2.0
"""Waiting for work the C node does on its own (an LSS request, a network boot, a program
download): on a SimBus by running the bus in virtual time, on python-can by receiving in
the waiting thread (:meth:`canola._engine.Link.wait`): the answers that arrived count
before a time-out is judged. Shared by canola.lss, canola.manager and canola.flash."""

from __future__ import annotations

import time
from collections.abc import Callable

from canola._engine import Engine
from canola.core import SimBus
from canola.errors import Error

__all__ = ["Waiter"]

#: Virtual time the simulated bus advances between two checks (us).
SIM_STEP_US = 1000


class Waiter:
    """``wait(done, limit_s)`` until ``done()`` (set by a C callback) or the limit."""

    def __init__(self, engine: Engine) -> None:
        self.engine = engine

    def check(self) -> None:
        """Raise when a blocking wait cannot work: not started, or called from a callback
        that the bus thread runs (it would wait for itself)."""
        self.engine.check_may_block()
        if not self.engine.running:
            raise Error("the master is not started: call start() first")

    def wait(self, done: Callable[[], bool], limit_s: float | None) -> bool:
        """True once ``done()``; False when ``limit_s`` (virtual seconds on a SimBus) passed
        first. Raises Error when the master is stopped meanwhile."""
        bus = self.engine.bus
        if isinstance(bus, SimBus):
            end = None if limit_s is None else bus.now_us + round(limit_s * 1e6)
            while not done():
                if end is not None and bus.now_us >= end:
                    return False
                step = bus.now_us + SIM_STEP_US
                bus.run_until(step if end is None else min(step, end))
            return True
        link = self.engine.link
        assert link is not None
        deadline = None if limit_s is None else time.monotonic() + limit_s
        try:
            return link.wait(self.engine, done, deadline)  # this thread receives meanwhile
        except Error:
            raise Error("the master was stopped") from None
