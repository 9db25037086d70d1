# SPDX-License-Identifier: Apache-2.0
"""canola's version is written once (include/canola/version.h) and every place that carries
it agrees: the C header's parts and string, CMake's project version (read from the header;
tests/packaging/c-install checks the installed pkg-config and CMake package files), the
Python package's metadata, ``canola.__version__`` and ``canola --version``."""

from __future__ import annotations

import re
import subprocess
import sys
from importlib import metadata
from pathlib import Path

import canola

ROOT = Path(__file__).resolve().parents[2]
HEADER = ROOT / "include" / "canola" / "version.h"


def header_version() -> str:
    text = HEADER.read_text(encoding="utf-8")
    parts = [re.search(rf"^#define CANOLA_VERSION_{p} (\d+)$", text, re.M) for p in
             ("MAJOR", "MINOR", "PATCH")]
    string = re.search(r'^#define CANOLA_VERSION "([^"]+)"', text, re.M)
    assert all(parts) and string, f"{HEADER}: the version's defines are missing"
    joined = ".".join(m.group(1) for m in parts if m)
    assert string.group(1) == joined, f"CANOLA_VERSION {string.group(1)} but parts say {joined}"
    return joined


def test_python_package_carries_the_header_version() -> None:
    version = header_version()
    assert metadata.version("canola") == version
    assert canola.__version__ == version


def test_the_command_says_the_version() -> None:
    out = subprocess.run([sys.executable, "-m", "canola.cli", "--version"], capture_output=True,
                         text=True, timeout=120, check=True)
    assert out.stdout.strip() == f"canola {header_version()}"


def test_no_other_file_writes_the_version() -> None:
    # CMake reads the header; pyproject.toml leaves the version to setup.py, which reads it.
    cmake = (ROOT / "CMakeLists.txt").read_text(encoding="utf-8")
    assert re.search(r"project\(canola VERSION \$\{_canola_version\}", cmake)
    pyproject = (ROOT / "python" / "pyproject.toml").read_text(encoding="utf-8")
    assert 'dynamic = ["version"]' in pyproject
    assert not re.search(r'^version\s*=', pyproject, re.M)


def test_a_checkout_run_without_installing_has_the_header_version(tmp_path: Path) -> None:
    """The C build runs odgen from the source tree with the system's Python, where no
    package metadata exists (a fresh clone's plain build failed on it): the package seen
    through a folder without its egg-info, by an interpreter without site-packages."""
    (tmp_path / "canola").symlink_to(ROOT / "python" / "src" / "canola")
    code = ("import sys; sys.path.insert(0, sys.argv[1]); import canola; "
            "print(canola.__version__)")
    out = subprocess.run([sys.executable, "-S", "-c", code, str(tmp_path)],
                         capture_output=True, text=True, timeout=120, check=True)
    assert out.stdout.strip() == header_version()
