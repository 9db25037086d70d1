# SPDX-License-Identifier: Apache-2.0
"""Shared fixtures: python-can buses for the tests that talk over a real(istic) bus.

``can_bus`` makes python-can buses that see each other: the ``virtual`` interface on a
channel of the test's own by default; SocketCAN on the interface named by the environment
variable ``CANOLA_VCAN`` (e.g. ``vcan0``) when it is set, as the SocketCAN tier does
(``CANOLA_VCAN=vcan0 pytest -m vcan``). Every bus made is shut down after the test.
``wait_until`` polls a condition of such a test for a while.

Every test is checked for processes it left running (``leftovers``): such a test errors,
naming them, and they are killed.
"""

from __future__ import annotations

import itertools
import os
import signal
import time
from collections.abc import Callable, Iterator

import can
import pytest
from leftovers import SESSION_VAR, TEST_VAR, describe, left_running

_channels = itertools.count()

#: The SocketCAN interface of the SocketCAN tier, or None (virtual buses).
VCAN = os.environ.get("CANOLA_VCAN") or None

#: SDO time-outs (ms) of the nodes in tests over python-can (threads on the wall clock): a
#: bound a starved machine meets (load 20 on 2 cores gives a thread a tenth of a core), not
#: an expected answer time. The SocketCAN tier runs in an emulated VM (canvm, no KVM) where
#: python-canopen takes more than a second to work through a block of 127 segments, and
#: where a loaded host starved a peer for more than 5 s between two segments (a server's
#: 5 s time-out fired mid-transfer at load 30): there, 20 s.
SDO_TIMEOUT_MS = 20000 if VCAN else 5000


os.environ[SESSION_VAR] = str(os.getpid())

# Tests end the programs they start with Ctrl-C (SIGINT) as a user does. A test run started
# as a background command of a script inherits SIGINT ignored, and so would every program
# it starts (Python leaves an ignored SIGINT ignored): take back Python's handler, which the
# programs started then have as their default.
if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


#: The environment that names a default bus (canola.bus.open.default_bus): the tests name
#: their buses themselves, whatever the developer's shell says.
BUS_ENVIRONMENT = ("CANOLA_BUS", "CAN_INTERFACE", "CAN_CHANNEL", "CAN_CONFIG", "CAN_BITRATE")


@pytest.fixture(autouse=True)
def _no_default_bus(monkeypatch: pytest.MonkeyPatch) -> None:
    for name in BUS_ENVIRONMENT:
        monkeypatch.delenv(name, raising=False)


@pytest.fixture(autouse=True)
def _nothing_left_running(request: pytest.FixtureRequest) -> Iterator[None]:
    """Mark the processes this test starts; after it, none may still run."""
    mark = f"{os.getpid()}:{request.node.nodeid}"
    os.environ[TEST_VAR] = mark
    yield
    del os.environ[TEST_VAR]
    found = left_running(TEST_VAR, mark)
    if found:
        pytest.fail(f"processes left running (killed now): {describe(found)}")


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """The processes of module- and session-wide fixtures are gone too."""
    found = left_running(SESSION_VAR, str(os.getpid()))
    if found:
        print(f"\nprocesses left running by the tests (killed now): {describe(found)}")
        session.exitstatus = pytest.ExitCode.TESTS_FAILED


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


def wait_until(check: Callable[[], bool], timeout: float = 30.0) -> bool:
    """Poll ``check`` every 5 ms until it is true or ``timeout`` seconds have passed; its
    last answer. The bound is for a starved machine: the wait ends when ``check`` holds."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if check():
            return True
        time.sleep(0.005)
    return check()
