"""Shared pieces of the CLI tests: run ``canola`` in this process and check its errors."""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable, Iterator

import pytest

from canola.cli import main


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
