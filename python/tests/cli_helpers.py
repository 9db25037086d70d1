# SPDX-License-Identifier: Apache-2.0
"""Shared pieces of the CLI tests: run ``canola`` in this process and check its errors."""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable, Iterator

import pytest

import canola.cli.common
from canola.cli import main
from canola.core import SimBus


def cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    """Run ``canola ARGS...`` through canola.cli.main: exit code, stdout, stderr."""
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def one_line_error(err: str) -> None:
    """The CLI's error convention: one line on stderr, never a traceback."""
    assert len(err.strip().splitlines()) == 1, err
    assert "Traceback" not in err


@contextlib.contextmanager
def repeating(action: Callable[[], None], pause: float = 0.3) -> Iterator[None]:
    """Do ``action`` again and again (``pause`` seconds apart) while the block runs: the
    command under test opens its bus at a moment the test does not know (slow under
    emulation), so it sees some round from its start."""
    stop = threading.Event()

    def run() -> None:
        while not stop.wait(pause):
            action()

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join(5)


class SharedSimBus(SimBus):
    """A simulated bus that outlives the commands: each command shuts its bus down when it
    ends; the nodes stay on this one for the next command."""

    def shutdown(self) -> None:
        """Nothing to release: the bus lives as long as the test."""


def cli_on_sim_bus(monkeypatch: pytest.MonkeyPatch,
                   bitrate: int = 500_000) -> tuple[list[str], SimBus]:
    """Bus options for the CLI that open one simulated bus, and that bus: the commands run
    in virtual time (exact and quick; :meth:`canola.Master.wait` runs the bus)."""
    bus = SharedSimBus(bitrate)
    monkeypatch.setattr(canola.cli.common, "open_bus",
                        lambda *, iface=None, url=None, timeout=3.0: bus)
    return ["--bus", "virtual://simulated"], bus
