# SPDX-License-Identifier: Apache-2.0
"""canola boot, canola flash, canola lss: the CLI against canola.Devices on a python-can
virtual bus in this process (each command opens its own bus on the channel)."""

from __future__ import annotations

import itertools
import json
import os
import zlib
from collections.abc import Callable, Iterator
from pathlib import Path

import can
import pytest
from cli_helpers import cli, cli_on_sim_bus, one_line_error
from conftest import wait_until
from lss_models import ChattyLssSlave
from managed import PRODUCT, REVISION, VENDOR, model, write_dcf

from canola import Device
from canola.core import SimBus
from canola.lss import UNCONFIGURED
from canola.program import ProgramSlot

pytestmark = pytest.mark.realtime

_channels = itertools.count()

Net = tuple[list[str], Callable[..., Device]]


#: SDO time-out of the boots (ms): long enough for python-can threads on a starved machine
#: (what a present node answers ends the wait; only the absent node 4 costs all of it).
SDO_MS = "10000"  # a bound a starved machine meets: 2000 ms failed node 2 with B at load 30


@pytest.fixture
def net() -> Iterator[Net]:
    """Bus options for the CLI, and a maker of started devices on that channel."""
    channel = f"canola-cli302-{os.getpid()}-{next(_channels)}"
    devices: list[Device] = []
    buses: list[can.BusABC] = []

    def device(node_id: int, *, vendor: int = VENDOR, serial: int = 1,
               program: bool = False) -> Device:
        bus = can.Bus(interface="virtual", channel=channel)
        buses.append(bus)
        dev = Device(model(vendor=vendor, serial=serial), node_id, bus)
        if program:
            ProgramSlot(dev)
        dev.start()
        devices.append(dev)
        return dev

    yield ["--bus", f"virtual://{channel}"], device
    for dev in devices:
        dev.stop()
    for bus in buses:
        bus.shutdown()


# ---- canola boot


@pytest.fixture
def plant(tmp_path: Path) -> Path:
    """Node 2 sends its heartbeat every 100 ms (its DCF) and the master watches it with
    5000 ms: a bound the device's thread meets on a starved machine (with 500 ms node 2
    failed at load 30; the output was not kept, a late heartbeat is the likely cause)."""
    write_dcf(tmp_path / "node2.dcf", 2, {(0x1017, 0): "100", (0x2001, 0): "0x2A"},
              serial=2)
    path = tmp_path / "plant.yaml"
    path.write_text("""
nodes:
  - {id: 2, dcf: node2.dcf, heartbeat_ms: 5000}
  - {id: 3, optional: true, identity: {vendor: 0xCA0}}
  - {id: 4, optional: true}
""")
    return path


def test_boot_yaml(capsys: pytest.CaptureFixture[str], net: Net, plant: Path) -> None:
    opts, device = net
    two = device(2, serial=2)
    device(3, vendor=0xBAD)
    code, out, err = cli(capsys, "boot", str(plant), *opts, "--sdo-timeout", SDO_MS)
    assert (code, err) == (0, ""), out
    assert out.splitlines() == [
        "node 2 (mandatory): running",
        "node 3 (optional): failed: D: vendor-ID does not match (0x1018:01 is 0x00000BAD)",
        "node 4 (optional): failed: B: no answer to the read of the device type (SDO abort "
        "0x05040000 (SDO protocol timed out))",
        "network started",
    ]
    assert two.od[0x2001, 0] == 0x2A  # written and confirmed by SDO
    # the NMT start has no answer: the device's thread applies it when it gets there
    assert wait_until(lambda: two.nmt_state == "OPERATIONAL")


def test_boot_json_and_halted(capsys: pytest.CaptureFixture[str], net: Net, plant: Path
                              ) -> None:
    opts, device = net
    device(2, serial=2)
    device(3, vendor=0xBAD)
    code, out, _ = cli(capsys, "boot", str(plant), *opts, "--sdo-timeout", SDO_MS, "--json")
    assert code == 0
    doc = json.loads(out)
    assert doc["started"] and doc["settled"]
    three = next(n for n in doc["nodes"] if n["node"] == 3)
    assert (three["state"], three["reason"], three["value"]) == ("failed", "D", 0xBAD)
    assert {"node": 0, "kind": "network-started"}.items() <= doc["events"][-1].items()
    # the same network with node 3 mandatory does not start: exit 1
    strict = plant.with_name("strict.yaml")
    strict.write_text(plant.read_text().replace("{id: 3, optional: true,", "{id: 3,"))
    code, out, err = cli(capsys, "boot", str(strict), *opts, "--sdo-timeout", SDO_MS)
    assert (code, err) == (1, "")
    assert out.splitlines()[-1] == "network not started: mandatory node(s) 3 failed"


def test_boot_dcf_files(capsys: pytest.CaptureFixture[str], net: Net, tmp_path: Path) -> None:
    opts, device = net
    dev = device(6, serial=6)
    dcf = write_dcf(tmp_path / "six.dcf", 6, {(0x2000, 0): "300"}, serial=6)
    code, out, _ = cli(capsys, "boot", str(dcf), *opts)
    assert code == 0 and out.splitlines() == ["node 6 (mandatory): running", "network started"]
    assert dev.od[0x2000, 0] == 300


@pytest.mark.parametrize(("text", "expected"), [
    ("nodes: [", "plant.yaml: line 1, column 9: not valid YAML"),
    ("nodes: [{id: 2, speed: 1}]", "plant.yaml: nodes[0].speed: unknown key"),
    ("nodes: [{id: 127}]", "plant.yaml: nodes[0].id: node 127 is the master itself"),
])
def test_boot_bad_description(capsys: pytest.CaptureFixture[str], tmp_path: Path, text: str,
                              expected: str) -> None:
    path = tmp_path / "plant.yaml"
    path.write_text(text)
    code, out, err = cli(capsys, "boot", str(path), "--bus", "virtual://unused")
    assert (code, out) == (2, "")
    one_line_error(err)
    assert err.startswith("canola boot: error: ") and expected in err


@pytest.mark.parametrize("args", [
    ["boot", "--bus", "virtual://x"],
    ["boot", "none.yaml", "--bus", "virtual://x"],
    ["boot", "a.yaml", "b.dcf", "--bus", "virtual://x"],
    ["boot", "n.dcf", "--bus", "virtual://x", "--sdo-timeout", "0"],
    ["boot", "n.dcf", "--bus", "virtual://x", "--master-id", "0"],
    ["boot", "n.dcf"],
])
def test_boot_usage_errors(capsys: pytest.CaptureFixture[str], args: list[str]) -> None:
    code, out, err = cli(capsys, *args)
    assert (code, out) == (2, "")
    one_line_error(err)


def test_boot_bad_timeout(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    dcf = write_dcf(tmp_path / "n.dcf", 5, {})
    code, _, err = cli(capsys, "boot", str(dcf), "--bus", "virtual://x", "--timeout", "-1")
    assert code == 2 and "bad --timeout -1" in err
    one_line_error(err)


# ---- canola flash


def test_flash(capsys: pytest.CaptureFixture[str], net: Net, tmp_path: Path) -> None:
    opts, device = net
    device(5, program=True)
    image = bytes(range(256)) * 80  # 20 KiB
    (tmp_path / "fw.bin").write_bytes(image)
    code, out, err = cli(capsys, "flash", "5", str(tmp_path / "fw.bin"), *opts, "--progress")
    assert code == 0
    assert out == (f"node 5: {len(image)} bytes, program started, identification "
                   f"0x{zlib.crc32(image):08X}\n")
    assert err.endswith("\n") and "100.0%" in err and f"{len(image)}/{len(image)} B" in err
    assert err.count("\r") >= 2  # redrawn as it went
    code, out, err = cli(capsys, "flash", "5", str(tmp_path / "fw.bin"), *opts, "--json",
                         "--ident", f"{zlib.crc32(image):x}", "--no-clear")
    assert (code, err) == (0, "")
    assert json.loads(out) == {"node": 5, "bytes": len(image), "ident": zlib.crc32(image)}


def test_flash_failures(capsys: pytest.CaptureFixture[str], net: Net, tmp_path: Path) -> None:
    opts, device = net
    device(5, program=True)
    fw = tmp_path / "fw.bin"
    fw.write_bytes(b"abc")
    code, _, err = cli(capsys, "flash", "5", str(fw), *opts, "--ident", "1234")
    assert code == 1
    one_line_error(err)
    assert "failed at verify: the device reports software identification" in err
    code, _, err = cli(capsys, "flash", "9", str(fw), *opts, "--sdo-timeout", "100")
    assert code == 1 and "node 9 failed at stop: SDO abort 0x05040000" in err
    one_line_error(err)
    code, _, err = cli(capsys, "flash", "5", str(tmp_path / "none.bin"), *opts)
    assert code == 1 and "cannot read" in err
    (tmp_path / "empty.bin").write_bytes(b"")
    code, _, err = cli(capsys, "flash", "5", str(tmp_path / "empty.bin"), *opts)
    assert code == 1 and "is empty" in err
    one_line_error(err)


@pytest.mark.parametrize("args", [
    ["flash", "200", "f.bin", "--bus", "virtual://x"],
    ["flash", "5", "--bus", "virtual://x"],
    ["flash", "5", "f.bin", "--bus", "virtual://x", "--ident", "xyz"],
    ["flash", "5", "f.bin", "--bus", "virtual://x", "--program", "0"],
    ["flash", "5", __file__],  # no bus (and no default bus)
])
def test_flash_usage_errors(capsys: pytest.CaptureFixture[str], args: list[str]) -> None:
    code, out, err = cli(capsys, *args)
    assert (code, out) == (2, "")
    one_line_error(err)


# ---- canola lss

#: LSS time-out of the CLI tests on python-can (ms): requests that end on an answer wait
#: for it, so it only bounds them, generously for starved threads (a device that is absent
#: costs it once).
LSS_MS = "2000"


@pytest.fixture
def sim_net(monkeypatch: pytest.MonkeyPatch) -> tuple[list[str], SimBus]:
    """Bus options for the CLI that open one simulated bus (virtual time), and that bus.
    Fastscan reads a missing answer as a 1 bit, and 134 steps each wait out the LSS
    time-out: on python-can's threads a starved machine delivers an answer in the next
    step and corrupts the scan (and it takes 134 time-outs of wall clock per device). On
    the simulated bus the commands run the same code in virtual time: exact and quick."""
    return cli_on_sim_bus(monkeypatch)


def test_lss_scan_set_id_inquire(capsys: pytest.CaptureFixture[str],
                                 sim_net: tuple[list[str], SimBus]) -> None:
    opts, bus = sim_net
    dev = Device(model(serial=0x11), UNCONFIGURED, bus)
    dev.start()
    Device(model(serial=0x22), 9, bus).start()  # has a node-ID: fastscan does not find it
    address = f"{VENDOR:08X}:{PRODUCT:08X}:{REVISION:08X}:00000011"
    code, out, err = cli(capsys, "lss", "scan", *opts)
    assert (code, err) == (0, "")
    assert out.splitlines()[0] == address
    assert out.splitlines()[1].startswith("1 device(s) without node-ID (fastscan took ")

    code, out, _ = cli(capsys, "lss", "inquire", address, *opts)
    assert code == 0
    assert out == (f"vendor 0x{VENDOR:08X} product 0x{PRODUCT:08X} revision "
                   f"0x{REVISION:08X} serial 0x00000011 node-ID none\n")

    code, out, err = cli(capsys, "lss", "set-id", "ca0:302:10000:11", "40", *opts)
    assert (code, err) == (0, "")
    assert out == f"{address}: node-ID 40\n"
    bus.run_for(100_000)  # the device boots with its node-ID
    assert (dev.nmt_state, dev.node_id) == ("PRE-OPERATIONAL", 40)

    other = f"{VENDOR:X}:{PRODUCT:X}:{REVISION:X}:22"
    code, out, _ = cli(capsys, "lss", "set-id", other, "41", *opts, "--json")
    assert json.loads(out) == {"address": f"{VENDOR:08X}:{PRODUCT:08X}:{REVISION:08X}:00000022",
                               "node_id": 41, "stored": False}
    code, out, _ = cli(capsys, "lss", "inquire", address, *opts, "--json")
    assert json.loads(out)["node_id"] == 40
    code, out, _ = cli(capsys, "lss", "scan", *opts, "--json")
    assert (code, json.loads(out)) == (0, [])


def test_lss_scan_ends_against_slaves_that_answer_in_configuration(
        capsys: pytest.CaptureFixture[str], sim_net: tuple[list[str], SimBus]) -> None:
    opts, bus = sim_net
    ChattyLssSlave(bus, (0x2E0, 0x17, 3, 0x100), port_id=100)
    code, out, err = cli(capsys, "lss", "scan", *opts, "--max-devices", "3")
    assert (code, err) == (0, "")
    assert out.splitlines()[0] == "000002E0:00000017:00000003:00000100"
    assert out.splitlines()[1].startswith("1 device(s) without node-ID")
    # bounded (1 s of virtual time): the limit reached is said, with the advice
    code, out, err = cli(capsys, "lss", "scan", *opts, "--time-limit", "1")
    assert (code, out) == (1, "")
    assert "not done within 1 s" in err and "--time-limit" in err and "--timeout" in err
    one_line_error(err)


def test_lss_failures(capsys: pytest.CaptureFixture[str], net: Net) -> None:
    opts, device = net
    device(7, serial=0x77)
    code, _, err = cli(capsys, "lss", "set-id", "1:2:3:4", "5", *opts, "--timeout", LSS_MS)
    assert code == 1 and "no device with address 00000001:00000002:00000003:00000004" in err
    one_line_error(err)
    address = f"{VENDOR:X}:{PRODUCT:X}:{REVISION:X}:77"
    code, _, err = cli(capsys, "lss", "set-id", address, "8", *opts, "--timeout", LSS_MS,
                       "--store")
    assert code == 1 and "store configuration: refused" in err
    one_line_error(err)


@pytest.mark.parametrize("args", [
    ["lss"],
    ["lss", "scan"],
    ["lss", "scan", "--bus", "virtual://x", "--timeout", "0"],
    ["lss", "scan", "--bus", "virtual://x", "--time-limit", "0"],
    ["lss", "scan", "--bus", "virtual://x", "--max-devices", "128"],
    ["lss", "set-id", "1:2:3", "5", "--bus", "virtual://x"],
    ["lss", "set-id", "1:2:3:4:5", "5", "--bus", "virtual://x"],
    ["lss", "set-id", "1:2:3:g", "5", "--bus", "virtual://x"],
    ["lss", "set-id", "1:2:3:4", "128", "--bus", "virtual://x"],
    ["lss", "set-id", "1:2:3:4", "--bus", "virtual://x"],
    ["lss", "inquire", "--bus", "virtual://x"],
    ["lss", "jump", "--bus", "virtual://x"],
])
def test_lss_usage_errors(capsys: pytest.CaptureFixture[str], args: list[str]) -> None:
    code, out, err = cli(capsys, *args)
    assert (code, out) == (2, "")
    one_line_error(err)


def test_help(capsys: pytest.CaptureFixture[str]) -> None:
    for args in (["boot", "--help"], ["flash", "--help"], ["lss", "scan", "--help"],
                 ["lss", "set-id", "--help"], ["lss", "inquire", "--help"]):
        code, out, _ = cli(capsys, *args)
        assert code == 0 and "usage: canola" in out


def test_boot_gives_up_at_the_timeout(capsys: pytest.CaptureFixture[str], net: Net,
                                      tmp_path: Path) -> None:
    opts, _ = net
    dcf = write_dcf(tmp_path / "n.dcf", 5, {})  # nobody answers as node 5
    code, out, err = cli(capsys, "boot", str(dcf), *opts, "--timeout", "0.3")
    assert (code, err) == (1, "")
    assert out.splitlines()[-1] == "network not started: the boot did not end within 0.3 s"
    code, out, _ = cli(capsys, "boot", str(dcf), *opts, "--timeout", "0.3", "--json")
    assert code == 1 and json.loads(out)["settled"] is False


# ---- who announces itself on the bus


def _own_frames(listener: can.BusABC, master_id: int = 127) -> list[str]:
    """Error control frames (boot-up, heartbeat) of node ``master_id`` seen so far."""
    seen = []
    while (msg := listener.recv(0.05)) is not None:
        if msg.arbitration_id == 0x700 + master_id:
            seen.append(f"{msg.arbitration_id:03X}#{bytes(msg.data).hex().upper()}")
    return seen


def test_one_shot_commands_are_silent_unless_asked(capsys: pytest.CaptureFixture[str],
                                                    net: Net, tmp_path: Path) -> None:
    opts, device = net
    device(5, serial=5)
    listener = can.Bus(interface="virtual", channel=opts[1].removeprefix("virtual://"))
    try:
        _own_frames(listener)
        for args in (["sdo", "read", "5", "0x1018:1"], ["sdo", "write", "5", "0x1017:0", "u16",
                                                       "0"],
                     ["scan", "--nodes", "1-8", "--timeout", "200"], ["nmt", "preop", "all"],
                     ["lss", "scan", "--timeout", "10", "--max-devices", "1"],
                     ["dump", "--duration", "0.2"]):
            code, _, err = cli(capsys, *args, *opts)
            assert (code, err) == (0, ""), args
            assert _own_frames(listener) == [], args  # no boot-up 77F#00, no heartbeat
        # asked to: the master takes part (its boot-up)
        assert cli(capsys, "sdo", "read", "5", "0x1018:1", *opts, "--announce")[0] == 0
        assert _own_frames(listener) == ["77F#00"]
        code, _, _ = cli(capsys, "sdo", "read", "5", "0x1018:1", *opts, "--announce",
                         "--master-id", "100")
        assert code == 0 and _own_frames(listener, 100) == ["764#00"]
        # the master of canola boot runs the network: it announces itself
        dcf = write_dcf(tmp_path / "n5.dcf", 5, {}, serial=5)
        assert cli(capsys, "boot", str(dcf), *opts)[0] == 0
        assert _own_frames(listener)[:1] == ["77F#00"]
    finally:
        listener.shutdown()
