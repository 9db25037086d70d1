"""Shared fixtures: python-can buses for the tests that talk over a real(istic) bus.

``can_bus`` makes python-can buses that see each other: the ``virtual`` interface on a
channel of the test's own by default; SocketCAN on the interface named by the environment
variable ``CANOLA_VCAN`` (e.g. ``vcan0``) when it is set, as the SocketCAN tier does
(``CANOLA_VCAN=vcan0 pytest -m vcan``). Every bus made is shut down after the test.
``wait_until`` polls a condition of such a test for a while.
"""

from __future__ import annotations

import itertools
import os
import time
from collections.abc import Callable, Iterator

import can
import pytest

_channels = itertools.count()

#: The SocketCAN interface of the SocketCAN tier, or None (virtual buses).
VCAN = os.environ.get("CANOLA_VCAN") or None

#: SDO time-outs (ms) of the nodes in tests over python-can. The SocketCAN tier runs in an
#: emulated VM (canvm, no KVM) where python-canopen takes more than a second to work
#: through a block of 127 segments before it acknowledges it.
SDO_TIMEOUT_MS = 5000 if VCAN else 1000


@pytest.fixture
def can_bus() -> Iterator[Callable[[], can.BusABC]]:
    """A factory of python-can buses on one shared channel."""
    channel = f"canola-test-{os.getpid()}-{next(_channels)}"
    made: list[can.BusABC] = []

    def make() -> can.BusABC:
        if VCAN:
            bus = can.Bus(interface="socketcan", channel=VCAN)
        else:
            bus = can.Bus(interface="virtual", channel=channel)
        made.append(bus)
        return bus

    yield make
    for bus in made:
        bus.shutdown()


def wait_until(check: Callable[[], bool], timeout: float = 3.0) -> bool:
    """Poll ``check`` every 5 ms until it is true or ``timeout`` seconds have passed; its
    last answer."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if check():
            return True
        time.sleep(0.005)
    return check()
