# SPDX-License-Identifier: Apache-2.0
"""``canola conformance``: the check list, argument errors, and runs against a canola.Device
on a python-can virtual bus in this process (exit 0 when no check fails, 1 otherwise; the
Markdown and JUnit reports written)."""

from __future__ import annotations

import itertools
import os
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path

import can
import pytest
from cli_helpers import cli, one_line_error

from canola import Device
from canola.conformance import CHECKS, Check, LiveProgress, Result

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "example_od.eds"
_channels = itertools.count()


@pytest.fixture
def device_channel() -> Iterator[str]:
    """A canola.Device (example_od.eds, node 21) on a python-can virtual channel."""
    channel = f"conformance-cli-{os.getpid()}-{next(_channels)}"
    bus = can.Bus(interface="virtual", channel=channel)
    try:
        with Device(EXAMPLE, 21, bus):
            yield channel
    finally:
        bus.shutdown()


def test_list(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = cli(capsys, "conformance", "--list")
    assert code == 0
    assert out.startswith("dictionary: the node's object dictionary against its EDS\n")
    assert all(f"  {c.name} " in out for c in CHECKS)
    code, out, _ = cli(capsys, "conformance", "--list", "--only", "time")
    assert (code, out.splitlines()[1].split()) == (0, ["time.consumer", "CiA", "301",
                                                       "§7.2.6,", "§7.5.2.15"])


@pytest.mark.parametrize(("args", "message"), [
    (["--node-id", "5"], "missing --eds (see canola conformance --help)"),
    (["--eds", "x.eds"], "missing --node-id (see canola conformance --help)"),
    (["--node-id", "5", "--eds", "x.eds", "--bus", "virtual://x", "--only", "nope"],
     "unknown group or check 'nope'"),
    (["--node-id", "200", "--eds", "x.eds", "--bus", "virtual://x"], "bad node-ID '200'"),
    (["--node-id", "5", "--eds", "x.eds", "--bus", "virtual://x", "--tolerance", "0"],
     "bad tolerance '0': 1..100 %"),
    (["--node-id", "5", "--eds", "x.eds", "--bus", "virtual://x", "--timeout", "soon"],
     "bad time 'soon': 0.05..60 s"),
])
def test_bad_arguments(capsys: pytest.CaptureFixture[str], args: list[str],
                       message: str) -> None:
    code, out, err = cli(capsys, "conformance", *args)
    assert (code, out) == (2, "")
    one_line_error(err)
    assert message in err


def test_missing_files(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    code, _, err = cli(capsys, "conformance", "--node-id", "5", "--eds",
                       str(tmp_path / "no.eds"), "--bus", "virtual://x")
    assert (code, err) == (1, f"canola: cannot read {tmp_path / 'no.eds'}: no such file\n")
    broken = tmp_path / "broken.eds"
    broken.write_text("[1000]\nDataType=0x0007\nthis is not a key\n")
    code, _, err = cli(capsys, "conformance", "--node-id", "5", "--eds", str(broken),
                       "--bus", "virtual://x")
    assert code == 1
    one_line_error(err)
    assert f"{broken}:3: [1000] line is neither" in err


@pytest.mark.realtime
def test_no_node_on_the_bus(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = cli(capsys, "conformance", "--node-id", "9", "--eds", str(EXAMPLE),
                         "--bus", f"virtual://conformance-cli-{os.getpid()}-empty",
                         "--timeout", "0.2")
    assert (code, out) == (1, "")
    one_line_error(err)
    assert "node 9 does not answer SDO (no answer to upload 0x1000:0 within 0.2 s)" in err


@pytest.mark.realtime
def test_a_passing_run_and_its_reports(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                       device_channel: str) -> None:
    md, xml = tmp_path / "report.md", tmp_path / "report.xml"
    code, out, err = cli(capsys, "conformance", "--node-id", "21", "--eds", str(EXAMPLE),
                         "--bus", f"virtual://{device_channel}", "--only", "dictionary",
                         "sdo.toggle_upload", "--markdown", str(md), "--junit", str(xml))
    assert (code, err) == (0, ""), out
    lines = out.splitlines()
    assert lines[0] == "[ 1/13] PASSED  dictionary.mandatory"
    assert lines[-2] == "[13/13] PASSED  sdo.toggle_upload"
    assert lines[-1] == "node 21: PASSED (13 passed, 0 failed, 0 skipped)"
    assert "- result: **PASSED** (13 passed, 0 failed, 0 skipped)" in md.read_text()
    root = ET.parse(xml).getroot()
    assert (root.get("tests"), root.get("failures")) == ("13", "0")


@pytest.mark.realtime
def test_a_failing_run_exits_1(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                               device_channel: str) -> None:
    other = tmp_path / "other_vendor.eds"
    other.write_text(EXAMPLE.read_text().replace("VendorNumber=0x00000CA0",
                                                 "VendorNumber=0x00000BAD"))
    md = tmp_path / "report.md"
    code, out, _ = cli(capsys, "conformance", "--node-id", "21", "--eds", str(other),
                       "--bus", f"virtual://{device_channel}", "--only", "dictionary.identity",
                       "--markdown", str(md))
    assert code == 1
    assert out.splitlines() == [
        "[1/1] FAILED  dictionary.identity [CiA 301 §7.5.2.21, CiA 306 §4.4 (DeviceInfo)]  "
        "value of 0x1018:1 (Vendor-ID, ro UNSIGNED32): "
        "expected 0xBAD ([DeviceInfo] VendorNumber), got 0xCA0",
        "node 21: FAILED (0 passed, 1 failed, 0 skipped)"]
    text = md.read_text()
    assert "### `dictionary.identity`" in text
    assert "SDO upload 0x1018:01 = 0x00000CA0 (node 21)" in text


@pytest.mark.realtime
def test_ctrl_c_prints_the_report_of_what_ran(capsys: pytest.CaptureFixture[str],
                                              tmp_path: Path, device_channel: str,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    """Ctrl-C during the second check: the line of the first, the summary, what was
    interrupted, the reports written; exit 130 (it exited 130 with no report before)."""
    shown = LiveProgress.__call__

    def progress(self: LiveProgress, done: int, total: int, check: Check,
                 result: Result | None) -> None:
        if done == 1 and result is None:
            raise KeyboardInterrupt
        shown(self, done, total, check, result)

    monkeypatch.setattr(LiveProgress, "__call__", progress)
    md = tmp_path / "report.md"
    code, out, _ = cli(capsys, "conformance", "--node-id", "21", "--eds", str(EXAMPLE),
                       "--bus", f"virtual://{device_channel}", "--only", "dictionary.mandatory",
                       "dictionary.entries", "--markdown", str(md))
    assert code == 130
    assert out.splitlines() == [
        "[1/2] PASSED  dictionary.mandatory",
        "node 21: INTERRUPTED (1 passed, 0 failed, 0 skipped)",
        "interrupted (Ctrl-C) during dictionary.entries: 1 of 2 checks ran"]
    assert "- result: **INTERRUPTED** (1 passed, 0 failed, 0 skipped)" in md.read_text()
