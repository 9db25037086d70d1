# SPDX-License-Identifier: Apache-2.0
"""The tests' waits on other processes end (bounded.py): a process that says nothing, as a
forked device that died before its "ready" (test_store_kill.py waited 28 minutes on such a
readline()), fails the wait in its time instead of hanging the run."""

from __future__ import annotations

import subprocess
import sys
import time
from collections.abc import Iterator

import pytest
from bounded import Lines, first_line

pytestmark = pytest.mark.realtime


@pytest.fixture
def silent() -> Iterator[subprocess.Popen[str]]:
    """A process that holds its stdout open and writes nothing."""
    proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)"],
                            stdout=subprocess.PIPE, text=True)
    yield proc
    proc.kill()
    proc.wait(60)
    assert proc.stdout is not None
    proc.stdout.close()


@pytest.mark.parametrize("wait", ["first_line", "Lines"])
def test_a_silent_process_fails_the_wait_in_its_time(silent: subprocess.Popen[str],
                                                     wait: str) -> None:
    began = time.monotonic()
    with pytest.raises(AssertionError, match=r"the silent one: no(thing| line) within 0.5 s"):
        if wait == "first_line":
            first_line(silent.stdout, "the silent one", 0.5)
        else:
            Lines(silent.stdout, "the silent one").line(0.5)
    assert time.monotonic() - began < 60  # returned: no hang (0.5 s unloaded)


def test_lines_come_in_order_then_the_end() -> None:
    proc = subprocess.Popen([sys.executable, "-c", "print('a'); print('b')"],
                            stdout=subprocess.PIPE, text=True)
    try:
        lines = Lines(proc.stdout, "the printer")
        assert [lines.line(60), lines.line(60), lines.line(60)] == ["a\n", "b\n", ""]
    finally:
        proc.wait(60)
        assert proc.stdout is not None
        proc.stdout.close()
