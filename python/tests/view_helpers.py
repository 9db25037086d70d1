# SPDX-License-Identifier: Apache-2.0
"""A ``canola`` command run as a process for the ``canola view`` tests: its output read line
by line with bounded waits, Ctrl-C to end it."""

from __future__ import annotations

import contextlib
import ctypes
import os
import queue
import signal
import subprocess
import sys
import threading
import time

from leftovers import end_process


class CanolaProcess:
    def __init__(self, *args: str) -> None:
        # faulthandler: SIGABRT to a process that hangs prints every thread's stack
        env = dict(os.environ, PYTHONUNBUFFERED="1", PYTHONFAULTHANDLER="1")
        self.proc = subprocess.Popen([sys.executable, "-m", "canola.cli", *args],
                                     stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                     text=True, env=env)
        self.lines: queue.Queue[str] = queue.Queue()
        self.seen: list[str] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.put(line.rstrip("\n"))

    def wait_line(self, start: str, timeout: float) -> str:
        """The first line (from now) that starts with ``start``."""
        end = time.monotonic() + timeout
        while (left := end - time.monotonic()) > 0:
            try:
                line = self.lines.get(timeout=left)
            except queue.Empty:
                break
            self.seen.append(line)
            if line.startswith(start):
                return line
        raise AssertionError(f"no line {start!r} within {timeout:.0f} s; output so far:\n"
                             + "\n".join(self.seen))

    def signal_another_thread(self, sig: int) -> None:
        """``sig`` to one of the process's threads that is not its main thread (a signal
        to a process lands on whichever thread the kernel picks)."""
        pid = self.proc.pid
        tids = sorted(int(t) for t in os.listdir(f"/proc/{pid}/task") if int(t) != pid)
        assert tids, "the process has no other thread"
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.tgkill(pid, tids[0], sig) != 0:
            raise OSError(ctypes.get_errno(), f"tgkill {pid} {tids[0]}")

    def stop(self) -> int:
        """Ctrl-C, as a user ends it: the exit code (it must end within 60 s)."""
        code, ended = end_process(self.proc, signal.SIGINT)
        if not ended:
            self._reader.join(10)  # the process is gone: its output ends
            rest = []
            with contextlib.suppress(queue.Empty):
                while True:
                    rest.append(self.lines.get_nowait())
            raise AssertionError(f"canola {self.proc.args[3:]} did not end on Ctrl-C within "
                                 "60 s; its threads:\n" + "\n".join(rest))
        return code
