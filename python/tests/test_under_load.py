# SPDX-License-Identifier: Apache-2.0
"""tests/under_load.sh, the script behind the suite's load runs: one line per run with its
verdict and the load it ran under, the count of runs passed, and an exit status that says
whether every run passed. Driven with short commands (``true``, ``false``) and one hog, its
logs in a folder of the test's own (never the checkout's build-load/, where a real batch may
be writing)."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "tests" / "under_load.sh"

pytestmark = pytest.mark.realtime


def under_load(logs: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(["bash", str(SCRIPT), "--logs", str(logs), *args],
                          capture_output=True, text=True, timeout=120, check=False)


def test_passing_runs_give_their_load_and_exit_zero(tmp_path: Path) -> None:
    done = under_load(tmp_path, "--hogs", "1", "--runs", "2", "--", "true")
    assert done.returncode == 0, done.stdout + done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("under_load.sh: 1 CPU hogs on ")
    for k in (1, 2):
        line = next(x for x in lines if x.startswith(f"run {k}: "))
        assert re.fullmatch(rf"run {k}: PASS in 0m\d+s \(1-min load mean [\d.]+, peak [\d.]+ "
                            r"over the run; now [\d.]+ [\d.]+ [\d.]+\)", line), line
    assert lines[-1].startswith("under_load.sh: 2 of 2 runs passed beside 1 CPU hogs")
    assert (tmp_path / "run-1.log").exists() and (tmp_path / "run-2.log").exists()


def test_a_failing_run_is_counted_and_the_exit_status_says_so(tmp_path: Path) -> None:
    done = under_load(tmp_path, "--hogs", "0", "--", "sh", "-c", "echo broken; exit 3")
    assert done.returncode == 1
    assert re.search(r"^run 1: FAIL \(exit 3\) in .*, log: .*run-1\.log$", done.stdout, re.M)
    assert done.stdout.splitlines()[-1].startswith("under_load.sh: 0 of 1 runs passed")
    assert (tmp_path / "run-1.log").read_text() == "broken\n"


@pytest.mark.parametrize(("args", "says"), [
    (["--bogus"], "unknown option --bogus"),
    (["--runs", "0"], "--runs and --at-once 1 or more"),
    (["--at-once", "2"], "--at-once 2 needs --fresh"),
])
def test_a_bad_argument_gets_one_line_and_exit_two(tmp_path: Path, args: list[str],
                                                    says: str) -> None:
    done = under_load(tmp_path, *args)
    assert done.returncode == 2
    assert done.stdout == ""
    assert done.stderr.count("\n") == 1 and says in done.stderr, done.stderr
