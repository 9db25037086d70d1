# SPDX-License-Identifier: Apache-2.0
"""Nothing a test starts may outlive it: processes are found by a mark in their environment.

Before each test ``conftest`` puts ``CANOLA_TEST_PROCESS=<pytest's pid>:<test id>`` into this
process's environment, so every process the test starts (and whatever those start, even
when their parent is gone) inherits it; after the test, :func:`left_running` finds those
still alive. The whole session is marked the same way (``CANOLA_TEST_SESSION``) for the
processes of module- and session-wide fixtures, checked when pytest ends. Linux (/proc)
only: elsewhere nothing is found.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import time
from pathlib import Path

TEST_VAR = "CANOLA_TEST_PROCESS"
SESSION_VAR = "CANOLA_TEST_SESSION"


def _marked(var: str, value: str) -> list[tuple[int, str]]:
    """(pid, command line) of the processes whose environment has ``var=value``."""
    needle = f"{var}={value}".encode()
    found = []
    for entry in Path("/proc").glob("[0-9]*"):
        pid = int(entry.name)
        if pid == os.getpid():
            continue
        try:
            if needle not in (entry / "environ").read_bytes().split(b"\0"):
                continue
            cmdline = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:  # gone meanwhile, or not ours to read
            continue
        if cmdline:  # a zombie has none: it is only waiting to be reaped
            found.append((pid, cmdline.strip()[:120]))
    return found


def left_running(var: str, value: str, grace: float = 5.0) -> list[tuple[int, str]]:
    """The marked processes still alive after up to ``grace`` seconds of waiting for them to
    end; each is then killed (SIGKILL), so one test's leftover cannot disturb the next."""
    end = time.monotonic() + grace
    while (found := _marked(var, value)) and time.monotonic() < end:
        time.sleep(0.05)
    for pid, _ in found:
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)
    return found


def end_process(popen: subprocess.Popen[str], sig: int, grace: float = 60.0) -> tuple[int, bool]:
    """Send ``sig`` (unless it has ended) and wait up to ``grace`` seconds: (exit code, True).
    A process that does not end gets SIGABRT, which with PYTHONFAULTHANDLER in its
    environment prints every thread's stack on its output (where it hangs), then SIGKILL:
    (exit code, False)."""
    if popen.poll() is None:
        popen.send_signal(sig)
    try:
        return popen.wait(grace), True
    except subprocess.TimeoutExpired:
        pass
    popen.send_signal(signal.SIGABRT)
    try:
        return popen.wait(10), False
    except subprocess.TimeoutExpired:
        popen.kill()
        return popen.wait(10), False


def describe(found: list[tuple[int, str]]) -> str:
    return "; ".join(f"pid {pid}: {cmd}" for pid, cmd in found)
