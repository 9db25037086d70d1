# SPDX-License-Identifier: Apache-2.0
"""The README's ``canola`` command block works as written: every line of it runs, in its
order, against the files it names (``examples/eds/``), on a ``canola bus serve`` hub with
a ``canola device``. What the test makes its own: the hub's port (the README's 29536 may
be taken), the gateway's port, and the two program images
(``firmware.bin``, ``app.bin``), which a user brings; every other word runs as written.
Commands that run until stopped (hub, device, gateway) are stopped by SIGINT or SIGTERM
once they showed what they are for; every other one must end by itself (the README gives
each a bound: a count or a duration)."""

from __future__ import annotations

import os
import re
import shlex
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from canola.cli import build_parser

pytestmark = [pytest.mark.slow, pytest.mark.realtime]  # processes: a hub, a device, ...

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"

#: What a command's output must show (a regex), by the command's start.
EXPECTED = {
    "canola scan": r"node 5: device type 0x00020192, canola SD-1 \(drive\.eds\)",
    "canola sdo read 5 0x1018:1": r"^0x00000CA0$",
    "canola sdo read 5 Identity object.Vendor-ID": r"^3232$",
    "canola pdo show": r"TPDO1  COB-ID 0x185 valid",
    "canola pdo map": r"  2  0x6064:00 32 bits  Position actual value",
    "canola eds show": r"^0x1018  0x01    Vendor-ID\s+UNSIGNED32\s+ro\s+0x00000CA0\s+no$",
    "canola eds diff examples": r"^0x1017:00 Producer heartbeat time: value: A \(none\), B 1000$",
    "canola eds diff drive5.dcf": r"^0x1A00:02 \S.*: value: A 0, B 1617166368 \(0x60640020\)$",
    "canola monitor": r"TPDO1: Statusword = \d+ \(0x[0-9A-F]+\), Position actual value = ",
    "canola dump": r"TPDO1 node 5 Statusword = \d+ \(0x[0-9A-F]+\), Position actual value = ",
    "canola boot": r"network started",
    "canola lss scan": r"0 device\(s\) without node-ID",
    "canola lss set-id": r"00000CA0:00000402:00010002:00402007: node-ID 7",
    "canola flash": r"node 5: 2000 bytes, program started",
    "canola gateway": r"listening on tcp:127\.0\.0\.1:\d+",
    "canola device": r"node 5: PRE-OPERATIONAL",
    "canola bus serve": r"127\.0\.0\.1:\d+",
}
#: Commands that run until stopped.
LONG_RUNNING = ("canola bus serve", "canola device", "canola gateway")


def readme_block() -> list[str]:
    """The lines of the first ``sh`` block after the heading of the canola command."""
    text = README.read_text(encoding="utf-8")
    section = text[text.index("### The `canola` command"):]
    block = re.search(r"```sh\n(.*?)```", section, re.DOTALL)
    assert block is not None
    return [line for line in block.group(1).splitlines() if line.strip()]


class Proc:
    """A command run in the background, its output (stdout and stderr) collected."""

    def __init__(self, argv: list[str], cwd: Path, env: dict[str, str]) -> None:
        self.popen = subprocess.Popen(argv, cwd=cwd, env=env, stdout=subprocess.PIPE,
                                      stderr=subprocess.STDOUT, text=True)
        self.out: list[str] = []
        self._reader = threading.Thread(target=lambda: self.out.extend(self.popen.stdout
                                                                       or ()), daemon=True)
        self._reader.start()

    def wait_for(self, pattern: str, timeout: float = 120.0) -> re.Match[str]:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            m = re.search(pattern, "".join(self.out), re.MULTILINE)
            if m is not None:
                return m
            if self.popen.poll() is not None and not self._reader.is_alive():
                break
            time.sleep(0.05)
        raise AssertionError(f"no {pattern!r} in {''.join(self.out)!r}")

    def stop(self, sig: int = signal.SIGTERM) -> int:
        if self.popen.poll() is None:
            self.popen.send_signal(sig)
        try:
            code = self.popen.wait(60)
        except subprocess.TimeoutExpired:
            self.popen.kill()
            code = self.popen.wait(10)
        self._reader.join(10)
        return code


@pytest.fixture
def background() -> Iterator[list[Proc]]:
    procs: list[Proc] = []
    yield procs
    for proc in reversed(procs):
        proc.stop()


def _expected(words: list[str]) -> str | None:
    line = " ".join(words)
    matches = [key for key in EXPECTED if line.startswith(key)]
    return EXPECTED[max(matches, key=len)] if matches else None


def _accepts(words: list[str], option: str) -> bool:
    """Whether ``canola WORDS...`` takes ``option`` (asked of the CLI's own parser)."""
    _, unknown = build_parser().parse_known_args([*words[1:], option, "1"])
    return option not in unknown


def _starved_machine_timeouts(words: list[str]) -> list[str]:
    """Time-outs a starved machine meets, for the commands that wait for the device: it is
    another process behind the hub and answers later than the defaults (a run at load 28
    got no answer to `canola lss set-id` in LSS's 100 ms, nor to `canola pdo map` in the
    SDO's 1000 ms). Bounds, not waits: each command ends when its answer came."""
    if words[1] == "lss":  # a fastscan waits this long for each probe nobody answers
        return ["--timeout", "3000"]
    if words[1] in ("sdo", "scan"):
        return ["--timeout", "10000"]
    return ["--sdo-timeout", "10000"] if _accepts(words, "--sdo-timeout") else []


def test_the_readme_block_runs_as_written(tmp_path: Path, background: list[Proc]) -> None:
    lines = readme_block()
    assert len(lines) >= 20 and lines[0].startswith("export CANOLA_BUS=")
    (tmp_path / "examples").symlink_to(ROOT / "examples")  # the repository's root, as cwd
    (tmp_path / "firmware.bin").write_bytes(os.urandom(3000))
    (tmp_path / "app.bin").write_bytes(os.urandom(2000))
    store = tmp_path / "drive-store"  # canola device makes it, as the README says
    env = {k: v for k, v in os.environ.items()
           if k not in ("CANOLA_BUS", "CAN_INTERFACE", "CAN_CHANNEL", "CAN_CONFIG")}
    ran = []
    for line in lines:
        words = shlex.split(line, comments=True)
        if words[0] == "export":
            name, _, value = words[1].partition("=")
            env[name] = value  # the hub's port is put in once the hub runs
            ran.append(line)
            continue
        in_background = words[-1] == "&"
        words = [w for w in words if w != "&"]
        assert words[0] == "canola", line
        argv = [sys.executable, "-m", "canola.cli", *words[1:]]
        if words[:3] == ["canola", "bus", "serve"]:
            argv += ["--port", "0"]
        if words[:2] == ["canola", "gateway"]:
            argv += ["--listen", "tcp:127.0.0.1:0"]
        argv += _starved_machine_timeouts(words)
        expected = _expected(words)
        if in_background or " ".join(words).startswith(LONG_RUNNING):
            proc = Proc(argv, tmp_path, env)
            background.append(proc)
            assert expected is not None, line
            m = proc.wait_for(expected)
            if words[:3] == ["canola", "bus", "serve"]:  # the hub's port, for CANOLA_BUS
                port = m.group(0).rsplit(":", 1)[1]
                env["CANOLA_BUS"] = env["CANOLA_BUS"].replace(":29536/", f":{port}/")
            if not in_background:  # a live command: Ctrl-C ends it, cleanly
                assert proc.stop(signal.SIGINT) == 0, proc.out
                background.remove(proc)
        else:
            done = subprocess.run(argv, cwd=tmp_path, env=env, capture_output=True,
                                  text=True, timeout=300, check=False)
            assert (done.returncode, done.stderr) == (0, ""), (line, done.stdout,
                                                               done.stderr)
            if expected is not None:
                assert re.search(expected, done.stdout, re.MULTILINE), (line, done.stdout)
        ran.append(line)
    assert ran == lines
    assert sorted(p.name for p in store.iterdir()) == ["app.params", "comm.params"]
