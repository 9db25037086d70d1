"""Shared pieces of the CLI tests: run ``canola`` in this process and check its errors."""

from __future__ import annotations

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
