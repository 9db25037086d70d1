# SPDX-License-Identifier: Apache-2.0
"""The canola command against real devices: a hub (``canola bus serve``) and two devices
(``canola device``) in their own processes, the CLI in this process (and a few runs as
programs), python-canopen as an independent peer on the same hub."""

from __future__ import annotations

import contextlib
import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import canopen
import pytest
from bounded import first_line
from cli_helpers import cli, one_line_error

from canola.bus.open import open_bus

pytestmark = [pytest.mark.slow, pytest.mark.realtime]  # processes: a hub, devices

#: The SDO time-out (ms) of the CLI's requests to the device processes, and of the devices'
#: SDO servers between the segments of a transfer (their default of 1 s aborted a transfer
#: whose client a starved machine ran late: 0x05040000): a starved machine schedules a
#: process late, never not at all. Calls that test a time-out give their own.
SDO_MS = "10000"

DATA = Path(__file__).parent / "data"
EDS = DATA / "cli_device.eds"
PY = sys.executable


class Proc:
    """A child process whose output lines are collected by a thread."""

    def __init__(self, *args: str) -> None:
        self.popen = subprocess.Popen([PY, "-m", "canola.cli", *args], stdout=subprocess.PIPE,
                                      stderr=subprocess.STDOUT, text=True)
        self.lines: list[str] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.popen.stdout is not None
        for line in self.popen.stdout:
            self.lines.append(line.rstrip("\n"))

    def wait_for(self, pattern: str, timeout: float = 60.0) -> re.Match[str]:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for line in list(self.lines):
                m = re.search(pattern, line)
                if m is not None:
                    return m
            if self.popen.poll() is not None and not self._reader.is_alive():
                break
            time.sleep(0.02)
        raise AssertionError(f"no {pattern!r} in {self.lines}")

    def stop(self) -> int:
        if self.popen.poll() is None:
            self.popen.send_signal(signal.SIGTERM)
        try:
            return self.popen.wait(30)
        except subprocess.TimeoutExpired:
            self.popen.kill()
            return self.popen.wait(10)


_HUBS: dict[str, Proc] = {}  # the hub behind each net URL (it logs who joins: -v)


def wait_joined(url: str, count: int, timeout: float = 60.0) -> None:
    """Wait until ``count`` clients have joined the hub behind ``url``."""
    hub, channel = _HUBS[url], url.rsplit("/", 1)[1]
    deadline = time.monotonic() + timeout
    while sum(line.endswith(f" joined {channel}") for line in list(hub.lines)) < count:
        assert time.monotonic() < deadline, hub.lines
        time.sleep(0.02)


def joined(url: str) -> int:
    channel = url.rsplit("/", 1)[1]
    return sum(line.endswith(f" joined {channel}") for line in list(_HUBS[url].lines))


@pytest.fixture(scope="module")
def net() -> Iterator[tuple[str, list[Proc]]]:
    hub = Proc("-v", "bus", "serve", "--port", "0")
    devices: list[Proc] = []
    try:
        port = hub.wait_for(r"127\.0\.0\.1:(\d+)").group(1)
        url = f"socketcand://127.0.0.1:{port}/net"
        _HUBS[url] = hub
        devices = [Proc("device", "--eds", str(EDS), "--node-id", str(n), "--bus", url,
                        "--sdo-timeout", SDO_MS) for n in (5, 6)]
        for dev in devices:
            dev.wait_for("PRE-OPERATIONAL")
        yield url, devices
    finally:
        codes = [dev.stop() for dev in devices]
        hub.stop()
    assert codes == [0, 0]  # SIGTERM stops a device cleanly


@pytest.fixture
def procs() -> Iterator[Callable[..., Proc]]:
    """Start ``canola ARGS...`` processes that are stopped when the test ends, pass or fail."""
    made: list[Proc] = []

    def start(*args: str) -> Proc:
        made.append(Proc(*args))
        return made[-1]

    yield start
    for proc in made:
        proc.stop()


@contextlib.contextmanager
def python_canopen(url: str) -> Iterator[canopen.RemoteNode]:
    """python-canopen's view of device 5, connected now: a client that joins the hub after
    the CLI's transfers cannot receive their last frames late (which python-canopen's SDO
    client would take for answers)."""
    # on canola's socketcand client (python-can's fails to join a busy hub on a busy
    # machine: canola.bus.socketcand_bus)
    network = canopen.Network(open_bus(url=url))
    network.connect()
    try:
        node = network.add_node(5, str(EDS))
        node.sdo.RESPONSE_TIMEOUT = int(SDO_MS) / 1000  # processes on a starved machine
        yield node
    finally:
        network.disconnect()


def sdo(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    """``canola sdo ARGS...`` with the generous time-out unless ARGS give one."""
    timeout = [] if "--timeout" in args else ["--timeout", SDO_MS]
    return cli(capsys, "sdo", *args, *timeout)


def test_sdo_read(capsys: pytest.CaptureFixture[str], net: tuple[str, list[Proc]]) -> None:
    url = net[0]
    assert sdo(capsys, "read", "5", "0x1018:1", "--bus", url) == (0, "0x00000CA0\n", "")
    assert sdo(capsys, "read", "6", "0x1018:4", "u32", "--bus", url) == (
        0, f"{0x12345678}\n", "")
    assert sdo(capsys, "read", "5", "0x1008", "vs", "--bus", url) == (
        0, "canola cli test\n", "")
    assert sdo(capsys, "read", "5", "0x1008:0", "--bus", url)[1] == (
        "'canola cli test' (15 bytes)\n")
    # four bytes of letters are still a number; UTF-8 text is shown as text
    assert sdo(capsys, "write", "5", "0x2000:0", "u32", "0x44434241", "--bus", url)[0] == 0
    assert sdo(capsys, "read", "5", "0x2000:0", "--bus", url)[1] == "0x44434241\n"
    assert sdo(capsys, "write", "5", "0x2002:0", "vs", "2 € each", "--bus", url)[0] == 0
    assert sdo(capsys, "read", "5", "0x2002:0", "--bus", url)[1] == (
        "'2 € each' (10 bytes)\n")
    assert sdo(capsys, "read", "5", "0x2002:0", "vs", "--bus", url)[1] == "2 € each\n"
    code, out, _ = sdo(capsys, "read", "5", "0x2001:0", "i16", "--bus", url, "--json")
    assert code == 0
    assert json.loads(out) == {"node": 5, "index": 0x2001, "sub": 0, "raw": "fbff",
                               "type": "i16", "value": -5}


def test_sdo_write_read_back_and_python_canopen_agrees(
        capsys: pytest.CaptureFixture[str], net: tuple[str, list[Proc]]) -> None:
    url = net[0]
    for index, dtype, text, back in (("0x2000:0", "u32", "0xCAFE0001", str(0xCAFE0001)),
                                     ("0x2001:0", "i16", "-300", "-300"),
                                     ("0x2003:0", "r32", "2.25", "2.25"),
                                     ("0x2002:0", "vs", "hi there", "hi there")):
        assert sdo(capsys, "write", "5", index, dtype, text, "--bus", url) == (0, "", "")
        assert sdo(capsys, "read", "5", index, dtype, "--bus", url) == (0, back + "\n",
                                                                               "")
    with python_canopen(url) as remote:
        assert remote.sdo[0x2000].raw == 0xCAFE0001
        assert remote.sdo[0x2001].raw == -300
        remote.sdo[0x2000].raw = 77
    assert sdo(capsys, "read", "5", "0x2000:0", "u32", "--bus", url)[1] == "77\n"
    # device 6 was not touched
    assert sdo(capsys, "read", "6", "0x2000:0", "--bus", url)[1] == "0x11111111\n"


@pytest.mark.parametrize(("args", "code", "message"), [
    (["read", "5", "0x1018-1"], 2, "bad object"),
    (["read", "5", "0x10180:1"], 2, "bad object"),
    (["read", "5", "0x1018:256"], 2, "bad object"),
    (["read", "128", "0x1018:1"], 2, "bad node-ID"),
    (["read", "5", "0x1018:1", "u7"], 2, "unknown type"),
    (["write", "5", "0x2000:0", "u8", "300"], 2, "UNSIGNED8"),
    (["write", "5", "0x2000:0", "u32", "lots"], 2, "UNSIGNED32"),
    (["write", "5", "0x2005:0", "u16", "1"], 1, "SDO abort 0x06010002"),
    (["write", "5", "0x2000:0", "u16", "1"], 1, "SDO abort 0x0607001"),
    (["read", "5", "0x5555:0"], 1, "node 5 0x5555:00: SDO abort 0x06020000: Object does not"),
    (["read", "5", "0x1018:9"], 1, "SDO abort 0x06090011"),
    (["read", "9", "0x1000:0", "--timeout", "300"], 1,
     "no response from node 9 (SDO time-out 300 ms, after "),
])
def test_sdo_errors(capsys: pytest.CaptureFixture[str], net: tuple[str, list[Proc]],
                    args: list[str], code: int, message: str) -> None:
    got, out, err = sdo(capsys, *args, "--bus", net[0])
    assert (got, out) == (code, "")
    one_line_error(err)
    assert message in err


@pytest.mark.parametrize("block", [True, False])
def test_sdo_upload_download_files(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                   net: tuple[str, list[Proc]], block: bool) -> None:
    url = net[0]
    blob = os.urandom(3000)
    src, dst = tmp_path / "fw.bin", tmp_path / "back.bin"
    src.write_bytes(blob)
    mode = [] if block else ["--no-block"]
    code, out, err = sdo(capsys, "download", "5", "0x2004:0", str(src), "--bus", url,
                         "--progress", *mode)
    assert (code, out) == (0, "")
    assert "100.0% 3000/3000 B" in err and "Traceback" not in err
    code, _, err = sdo(capsys, "upload", "5", "0x2004:0", str(dst), "--bus", url,
                       "--progress", "--json", *mode)
    assert code == 0 and "100.0% 3000/3000 B" in err
    assert dst.read_bytes() == blob
    with python_canopen(url) as remote:
        assert remote.sdo[0x2004].raw == blob  # python-canopen reads the same bytes


def test_sdo_file_errors(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                         net: tuple[str, list[Proc]]) -> None:
    url = net[0]
    big = tmp_path / "big.bin"
    big.write_bytes(bytes(10000))  # more than the device's DOMAIN room
    code, _, err = sdo(capsys, "download", "5", "0x2004:0", str(big), "--bus", url)
    assert code == 1 and "SDO abort" in err
    one_line_error(err)
    code, _, err = sdo(capsys, "download", "5", "0x2004:0", str(tmp_path / "none"),
                       "--bus", url)
    assert code == 1 and "cannot read" in err
    one_line_error(err)
    code, _, err = sdo(capsys, "upload", "5", "0x2004:0", str(tmp_path / "no/such"),
                       "--bus", url)
    assert code == 1 and "cannot write" in err
    one_line_error(err)


def test_nmt_scan_monitor(capsys: pytest.CaptureFixture[str],
                          net: tuple[str, list[Proc]]) -> None:
    url, devices = net
    code, out, _ = cli(capsys, "scan", "--bus", url, "--json", "--timeout", "3000")
    assert code == 0
    assert [n["node"] for n in json.loads(out)] == [5, 6]
    assert cli(capsys, "nmt", "start", "5", "--bus", url)[0] == 0
    devices[0].wait_for("node 5: OPERATIONAL")
    # 0x1017 = 100 ms: several heartbeats of each in 2 s, however busy the machine
    code, out, _ = cli(capsys, "monitor", "--bus", url, "--json", "--duration", "2")
    nodes = {n["node"]: n for n in json.loads(out)["nodes"]}
    assert nodes[5]["state"] == "OPERATIONAL" and nodes[6]["state"] == "PRE-OPERATIONAL"
    assert 0 <= nodes[5]["heartbeat_age"] < 2  # heard during the run
    assert cli(capsys, "nmt", "preop", "all", "--bus", url)[0] == 0
    devices[0].wait_for("node 5: PRE-OPERATIONAL")
    assert cli(capsys, "nmt", "reset-node", "6", "--bus", url)[0] == 0
    devices[1].wait_for("node 6: INITIALISING|node 6: BOOT")


def test_dump_sees_an_sdo_read(capsys: pytest.CaptureFixture[str],
                               net: tuple[str, list[Proc]]) -> None:
    url = net[0]
    before = joined(url)
    # it ends on the two frames it shows (not after a time: a busy machine may take long)
    dump = subprocess.Popen([PY, "-m", "canola.cli", "dump", "--bus", url, "--node", "6",
                             "--service", "sdo", "--count", "2", "--json"],
                            stdout=subprocess.PIPE, text=True)
    try:
        wait_joined(url, before + 1)  # the dump process is listening
        assert sdo(capsys, "read", "6", "0x1018:2", "--bus", url)[:2] == (
            0, "0x00000042\n")
        out, _ = dump.communicate(timeout=300)
    finally:
        if dump.poll() is None:
            dump.kill()
            dump.wait(10)
    texts = [json.loads(line)["text"] for line in out.splitlines()]
    assert texts == ["SDO upload 0x1018:02 request (node 6)",
                     "SDO upload 0x1018:02 = 0x00000042 (node 6)"]


def test_cli_as_programs(net: tuple[str, list[Proc]]) -> None:
    url = net[0]
    ok = subprocess.run([PY, "-m", "canola.cli", "sdo", "read", "6", "0x1000:0", "u32",
                         "--bus", url, "--timeout", SDO_MS], capture_output=True, text=True,
                        timeout=300, check=False)
    assert (ok.returncode, ok.stdout, ok.stderr) == (0, f"{0x20192}\n", "")
    bad = subprocess.run([PY, "-m", "canola.cli", "sdo", "read", "99", "0x1000:0", "--bus", url,
                          "--timeout", "200"], capture_output=True, text=True, timeout=300,
                         check=False)
    assert bad.returncode == 1
    assert bad.stderr.startswith("canola: no response from node 99 (SDO time-out 200 ms, after ")


def test_device_errors(tmp_path: Path, net: tuple[str, list[Proc]]) -> None:
    url = net[0]
    broken = tmp_path / "broken.eds"
    broken.write_text("[1000]\nDataType=0x0007\n")
    for args in (["--eds", str(tmp_path / "none.eds"), "--node-id", "7"],
                 ["--eds", str(broken), "--node-id", "7"],
                 ["--eds", str(EDS), "--node-id", "7", "--store",
                  str(tmp_path / "noparent" / "dir")]):  # a missing folder alone is made
        proc = subprocess.run([PY, "-m", "canola.cli", "device", *args, "--bus", url],
                              capture_output=True, text=True, timeout=300, check=False)
        assert proc.returncode == 1, args
        one_line_error(proc.stderr)


CANOPEN_PEER = """
import sys, canopen
from canola.bus.open import open_bus
url, eds = sys.argv[1:3]
net = canopen.Network(open_bus(url=url))  # canola's socketcand client: see python_canopen
net.connect()
node = canopen.LocalNode(9, eds)
net.add_node(node)
node.nmt.state = "PRE-OPERATIONAL"
node.nmt.start_heartbeat(100)
print("ready", flush=True)
sys.stdin.read()  # until the test closes stdin
print("0x2000 =", hex(node.sdo[0x2000].raw), flush=True)
node.nmt.stop_heartbeat()
net.disconnect()
"""


def test_python_canopen_process_on_the_same_hub(capsys: pytest.CaptureFixture[str],
                                                net: tuple[str, list[Proc]]) -> None:
    url = net[0]
    peer = subprocess.Popen([PY, "-c", CANOPEN_PEER, url, str(EDS)],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert first_line(peer.stdout, "the python-canopen peer", 120) == "ready\n"
        code, out, _ = cli(capsys, "scan", "--bus", url, "--json", "--timeout", "3000")
        assert code == 0 and [n["node"] for n in json.loads(out)] == [5, 6, 9]
        assert sdo(capsys, "read", "9", "0x1008:0", "vs", "--bus", url)[1] == (
            "canola cli test\n")
        assert sdo(capsys, "write", "9", "0x2000:0", "u32", "0xBEEF", "--bus", url)[0] == 0
        out, _ = peer.communicate("", timeout=300)
        assert out == "0x2000 = 0xbeef\n"
    finally:
        if peer.poll() is None:
            peer.kill()
            peer.wait(10)


def test_device_stops_on_sigint(net: tuple[str, list[Proc]],
                                procs: Callable[..., Proc]) -> None:
    dev = procs("device", "--eds", str(EDS), "--node-id", "20", "--bus", net[0])
    dev.wait_for("node 20: PRE-OPERATIONAL")
    dev.popen.send_signal(signal.SIGINT)
    assert dev.popen.wait(30) == 0
    dev.wait_for("node 20 stopped")


def test_commands_end_when_the_hub_goes_away(procs: Callable[..., Proc]) -> None:
    hub = procs("-v", "bus", "serve", "--port", "0")  # -v: the hub logs who joins
    port = hub.wait_for(r"127\.0\.0\.1:(\d+)").group(1)
    url = f"socketcand://127.0.0.1:{port}/gone"
    device = procs("device", "--eds", str(EDS), "--node-id", "7", "--bus", url)
    device.wait_for("node 7: PRE-OPERATIONAL")
    dump = procs("dump", "--bus", url)  # no duration: runs until the bus goes
    monitor = procs("monitor", "--bus", url, "--once", "--duration", "60")
    dump.wait_for("node 7 heartbeat")
    # all three on the bus before it goes (else one meets a refused connection instead)
    deadline = time.monotonic() + 60
    while sum(" joined gone" in line for line in list(hub.lines)) < 3:
        assert time.monotonic() < deadline, hub.lines
        time.sleep(0.02)
    assert hub.stop() == 0
    for proc in (device, dump, monitor):
        assert proc.popen.wait(60) == 1
        proc.wait_for("^canola: the bus connection was closed by the server$")


def test_device_domain_and_string_sizes(capsys: pytest.CaptureFixture[str],
                                        net: tuple[str, list[Proc]], tmp_path: Path) -> None:
    """canola device --domain-size/--string-size: values larger than the SDO buffer go
    into the entries' RAM, by block and segmented download; a default device refuses them
    with the CiA code for 'too long'."""
    url = net[0]
    dev = Proc("device", "--eds", str(EDS), "--node-id", "22", "--bus", url,
               "--sdo-timeout", SDO_MS, "--domain-size", "65536", "--string-size", "10000")
    try:
        dev.wait_for("node 22: PRE-OPERATIONAL")
        data = os.urandom(10 * 1024)
        (tmp_path / "in.bin").write_bytes(data)
        for extra in ([], ["--no-block"]):
            code, _, err = sdo(capsys, "download", "22", "0x2004:0",
                               str(tmp_path / "in.bin"), "--bus", url, *extra)
            assert (code, err) == (0, "")
            code, _, err = sdo(capsys, "upload", "22", "0x2004:0",
                               str(tmp_path / "out.bin"), "--bus", url, *extra)
            assert (code, err) == (0, "")
            assert (tmp_path / "out.bin").read_bytes() == data
        text = "x" * 9000
        # a whole segmented transfer's bound (1,286 segments through the hub to another
        # process: more than 30 s at load 50), at most the SDO client's 65,535 ms
        slow = ["--bus", url, "--timeout", "65000"]
        assert sdo(capsys, "write", "22", "0x2002:0", "vs", text, *slow)[0] == 0
        assert sdo(capsys, "read", "22", "0x2002:0", "vs", *slow)[1] == text + "\n"
        # device 5 runs with the default 4096-byte DOMAIN
        code, _, err = sdo(capsys, "download", "5", "0x2004:0",
                           str(tmp_path / "in.bin"), "--bus", url)
        assert code == 1 and "0x06070012" in err
    finally:
        assert dev.stop() == 0


def test_device_size_options_in_help_and_checked(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = cli(capsys, "device", "--help")
    assert code == 0
    assert "--domain-size BYTES" in out and "--string-size BYTES" in out
    assert "1..67108864" in out and "1..65535" in out
    for bad in (["--domain-size", "0"], ["--domain-size", "67108865"],
                ["--string-size", "65536"]):
        code, out, err = cli(capsys, "device", "--eds", str(EDS), "--node-id", "5",
                             "--bus", "virtual://x", *bad)
        assert (code, out) == (2, "")
        one_line_error(err)
