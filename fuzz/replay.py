# SPDX-License-Identifier: Apache-2.0
"""A Python fuzz target's inputs replayed where atheris is not installed (it has no wheel for
every Python): the seed corpus still runs through the target's contract."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any


def replay(name: str, one_input: Callable[[bytes], None], args: list[str]) -> None:
    """Run ``one_input`` on every file of ``args`` (files, or folders of them; libFuzzer's
    ``-flags`` are left out)."""
    paths = [Path(a) for a in args if not a.startswith("-")]
    files = [p for a in paths for p in (sorted(a.iterdir()) if a.is_dir() else [a])]
    for path in files:
        one_input(path.read_bytes())
    print(f"{name}: replayed {len(files)} inputs (atheris not installed: no fuzzing)")


def main(name: str, one_input: Callable[[bytes], None], atheris: Any) -> None:
    """The target's command line: libFuzzer's under ``atheris``, a replay without it."""
    if atheris is None:
        replay(name, one_input, sys.argv[1:])
    else:
        atheris.Setup(sys.argv, one_input)
        atheris.Fuzz()
