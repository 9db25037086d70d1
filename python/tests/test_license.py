# SPDX-License-Identifier: Apache-2.0
"""Every source file of the repository says its license in an SPDX line (Apache-2.0, the
LICENSE at the root), and the packages carry the license in their metadata.

Source files: C (.c .h .inc), Python (.py .pyi), CMake (CMakeLists.txt, .cmake, .cmake.in),
build and package files (Makefile, .toml, .pc.in) and scripts (any file starting with #!).
Left out, with why: the fuzzers' seed inputs (data, not code) and the generator's golden
files (python/tests/golden: byte-exact output of odgen, whose output belongs to the user
who generates it, so odgen stamps no license on it)."""

from __future__ import annotations

import subprocess
from importlib import metadata
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TAG = "SPDX-License-Identifier: Apache-2.0"
LEFT_OUT = ("fuzz/corpus/", "python/tests/golden/")
SOURCE_SUFFIXES = (".c", ".h", ".inc", ".py", ".pyi", ".cmake", ".cmake.in", ".toml", ".pc.in",
                   ".sh")
SOURCE_NAMES = ("CMakeLists.txt", "Makefile")


def tracked_files() -> list[str]:
    """The repository's files as git knows them (untracked new files included)."""
    try:
        out = subprocess.run(["git", "ls-files", "--cached", "--others", "--exclude-standard"],
                             cwd=ROOT, capture_output=True, text=True, check=True, timeout=300)
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout: the source list comes from git ls-files")
    return [f for f in out.stdout.splitlines() if f]


def is_source(path: str) -> bool:
    if path.startswith(LEFT_OUT):
        return False
    name = path.rsplit("/", 1)[-1]
    if name.endswith(SOURCE_SUFFIXES) or name in SOURCE_NAMES:
        return True
    full = ROOT / path
    if full.is_symlink() or not full.is_file():
        return False
    with full.open("rb") as f:
        return f.read(2) == b"#!"


def has_spdx_line(path: Path) -> bool:
    """The SPDX line stands in the first three lines (after a #! line, a file's first)."""
    head = path.read_text(encoding="utf-8", errors="replace").split("\n")[:3]
    return any(TAG in line for line in head)


def test_every_source_file_has_its_spdx_line() -> None:
    sources = [f for f in tracked_files() if is_source(f)]
    assert len(sources) > 300  # the walk found the tree, not an empty list
    missing = [path for path in sources if not has_spdx_line(ROOT / path)]
    assert not missing, (f"{len(missing)} source file(s) without '{TAG}' in their first "
                         f"three lines: {', '.join(missing[:20])}")


def test_the_check_sees_a_file_without_the_line(tmp_path: Path) -> None:
    # The rule above, applied to a file that lacks the line and to one that has it.
    bare = tmp_path / "x.c"
    bare.write_text("/* x.c -- no license line */\nint x;\n")
    stamped = tmp_path / "y.sh"
    stamped.write_text(f"#!/bin/sh\n# {TAG}\necho y\n")
    late = tmp_path / "z.py"
    late.write_text('"""z"""\n\n\n# ' + TAG + "\n")
    assert not has_spdx_line(bare)
    assert not has_spdx_line(late)
    assert has_spdx_line(stamped)


def test_license_text_and_package_metadata() -> None:
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert "Apache License" in text and "Version 2.0, January 2004" in text
    pyproject = (ROOT / "python" / "pyproject.toml").read_text(encoding="utf-8")
    assert 'license = "Apache-2.0"' in pyproject
    assert (ROOT / "python" / "LICENSE").read_text(encoding="utf-8") == text
    assert "License: Apache-2.0" in (ROOT / "cmake" / "canola.pc.in").read_text()
    assert 'set(canola_LICENSE "Apache-2.0")' in (ROOT / "cmake" /
                                                  "canolaConfig.cmake.in").read_text()


def test_installed_package_says_its_license() -> None:
    meta = metadata.metadata("canola")
    assert meta.get("License-Expression") == "Apache-2.0" or meta.get("License") == "Apache-2.0"
