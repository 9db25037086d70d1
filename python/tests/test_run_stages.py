# SPDX-License-Identifier: Apache-2.0
"""tests/run-stages, behind `make test`: its summary names the failed tests at its very end
(a CI log is often read from its end only). Driven with a copy of the script beside a
Makefile of the test's own, whose targets print what pytest and ctest print."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

pytestmark = pytest.mark.realtime

PYTEST_FAILING = [
    "FAILED tests/test_a.py::test_one - AssertionError: assert 1 == 2",
    "ERROR tests/test_b.py::test_two - TimeoutError",
]


def make_target(name: str, lines: list[str], status: int) -> str:
    body = "".join(f"\t@echo '{line}'\n" for line in lines)
    return f"{name}:\n{body}\t@exit {status}\n"


def run_stages(tmp_path: Path, makefile: str, *stages: str) -> subprocess.CompletedProcess[str]:
    (tmp_path / "tests").mkdir()
    shutil.copy(ROOT / "tests" / "run-stages", tmp_path / "tests" / "run-stages")
    (tmp_path / "Makefile").write_text(makefile)
    return subprocess.run(["bash", str(tmp_path / "tests" / "run-stages"), *stages],
                          capture_output=True, text=True, timeout=120, check=False)


def test_the_failed_tests_are_named_after_the_table(tmp_path: Path) -> None:
    ctest = ["90% tests passed, 1 tests failed out of 10", "",
             "The following tests FAILED:", "\t  3 - test_sdo_server (Failed)",
             "Errors while running CTest"]
    done = run_stages(tmp_path,
                      make_target("test-pytest", [*PYTEST_FAILING,
                                                   "== 5 passed, 1 failed, 1 error in 2s =="], 1)
                      + make_target("test-plain", ctest, 8), "pytest", "plain")
    assert done.returncode == 1
    tail = done.stdout.splitlines()[-6:]
    assert tail == [
        "failed in Python tests (pytest) (build-logs/pytest.log):",
        *(f"  {line}" for line in PYTEST_FAILING),
        "failed in C tests, plain build (build-logs/plain.log):",
        "  3 - test_sdo_server (Failed)",
        "total: 14 passed, 3 failed",
    ], done.stdout
    assert "failed in" not in done.stdout.split("== summary")[0]


def test_a_long_list_is_cut_at_ten(tmp_path: Path) -> None:
    failing = [f"FAILED tests/test_x.py::test_{k}" for k in range(13)]
    done = run_stages(tmp_path, make_target("test-pytest", [*failing, "13 failed in 1s"], 1),
                      "pytest")
    lines = done.stdout.splitlines()
    at = lines.index("failed in Python tests (pytest) (build-logs/pytest.log):")
    assert lines[at + 1:at + 11] == [f"  {line}" for line in failing[:10]]
    assert lines[at + 11] == "  ... and 3 more"


def test_a_passing_stage_names_nothing(tmp_path: Path) -> None:
    done = run_stages(tmp_path, make_target("test-pytest", ["== 4 passed in 1s =="], 0),
                      "pytest")
    assert done.returncode == 0, done.stdout
    assert "failed in" not in done.stdout
    assert done.stdout.splitlines()[-1] == "total: 4 passed, 0 failed"
