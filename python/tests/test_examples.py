# SPDX-License-Identifier: Apache-2.0
"""The examples in python/examples run (so they cannot rot) and print what they promise."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def _run(*args: str) -> str:
    done = subprocess.run([sys.executable, *args], capture_output=True, text=True,
                          timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    return done.stdout


@pytest.mark.slow
def test_master_example() -> None:
    out = _run(str(EXAMPLES / "master_example.py"))
    assert "node 5: 'canola interop', vendor 0xCA0" in out
    assert "heartbeat: node 6 state OPERATIONAL" in out
    assert "block download of 1000 bytes done; read back: 1000 bytes" in out
    assert "EMCY from node 6: 0x4210 register 0x09" in out
    assert "heartbeat: node 6 lost OPERATIONAL" in out
    assert "the last 3412" in out
    assert "abort 0x06020000" in out
    assert out == _run(str(EXAMPLES / "master_example.py"))  # virtual time: deterministic


@pytest.mark.slow
@pytest.mark.realtime
def test_device_example() -> None:
    # it counts to 22 (100 ms apart: a starved machine takes longer, it still gets there)
    out = _run(str(EXAMPLES / "device_example.py"), "--count", "22",
               "--channel", "canola-example-test")
    assert "state PRE-OPERATIONAL" in out
    assert "NMT state: OPERATIONAL" in out
    assert "EMCY 0xFF00 raised, error register 129" in out
    assert "counted to 22" in out
