# SPDX-License-Identifier: Apache-2.0
"""The EDS in the everyday commands: ``--eds``/``--dcf`` (per node: ``--eds N=FILE``) give
``canola sdo``, ``scan``, ``dump`` and ``monitor`` entry names, types, typed values and PDO
mappings. Against a canola device (node 5) and python-canopen's LocalNode (node 6) on one
python-can virtual bus, the commands run in this process."""

from __future__ import annotations

import datetime
import itertools
import json
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import can
import canopen
import pytest
from cli_helpers import cli, one_line_error, repeating
from conftest import wait_until

import canola
from canola.decode import Decoder

pytestmark = pytest.mark.realtime  # python-can threads

ROOT = Path(__file__).resolve().parents[2]
DRIVE = str(ROOT / "examples" / "eds" / "drive.eds")
SDO_MS = "10000"  # a starved machine answers late, never not at all
_channels = itertools.count()


@dataclass
class Net:
    bus_url: str
    device: canola.Device
    peer: can.BusABC  # sends test frames, listens


@pytest.fixture(scope="module")
def net() -> Iterator[Net]:
    channel = f"cli-eds-{next(_channels)}"
    device_bus = can.Bus(interface="virtual", channel=channel)
    peer = can.Bus(interface="virtual", channel=channel)
    network = canopen.Network()
    network.connect(interface="virtual", channel=channel)
    local = canopen.LocalNode(6, DRIVE)
    network.add_node(local)
    device = canola.Device(DRIVE, 5, device_bus)
    device.start()
    try:
        yield Net(f"virtual://{channel}", device, peer)
    finally:
        device.stop()
        network.disconnect()
        device_bus.shutdown()
        peer.shutdown()


def sdo(capsys: pytest.CaptureFixture[str], net: Net, *args: str) -> tuple[int, str, str]:
    return cli(capsys, "sdo", *args, "--bus", net.bus_url, "--timeout", SDO_MS)


def test_sdo_names_and_types_from_the_eds(capsys: pytest.CaptureFixture[str],
                                          net: Net) -> None:
    for node in ("5", "6"):  # canola's device, python-canopen's LocalNode
        assert sdo(capsys, net, "read", node, "Identity object.Vendor-ID", "--eds", DRIVE) == (
            0, f"{0xCA0}\n", "")
        assert sdo(capsys, net, "read", node, "0x1018:2", "--dcf", DRIVE) == (
            0, f"{0x402}\n", "")
        assert sdo(capsys, net, "write", node, "Producer heartbeat time", "0", "--eds",
                   DRIVE) == (0, "", "")
        assert sdo(capsys, net, "read", node, "Producer heartbeat time", "--eds", DRIVE) == (
            0, "0\n", "")
    # the type the EDS gives is the one written: UNSIGNED16, two bytes
    code, out, _ = sdo(capsys, net, "write", "5", "producer heartbeat time", "0",
                       "--eds", DRIVE, "--json")
    assert code == 0 and json.loads(out) == {"node": 5, "index": 0x1017, "sub": 0,
                                             "name": "Producer heartbeat time",
                                             "raw": "0000"}
    code, out, _ = sdo(capsys, net, "read", "5", "Statusword", "--eds", "5=" + DRIVE,
                       "--json")
    assert code == 0
    assert json.loads(out) == {"node": 5, "index": 0x6041, "sub": 0, "name": "Statusword",
                               "raw": "5002", "type": "u16", "value": 0x250}
    # a TYPE given still wins over the EDS
    assert sdo(capsys, net, "read", "5", "Statusword", "u8", "--eds", DRIVE)[0] == 1


def test_sdo_upload_download_by_name(capsys: pytest.CaptureFixture[str], net: Net,
                                     tmp_path: Path) -> None:
    blob = bytes(range(256)) * 4
    src, back = tmp_path / "fw.bin", tmp_path / "back.bin"
    src.write_bytes(blob)
    assert sdo(capsys, net, "download", "5", "Firmware", str(src), "--eds", DRIVE) == (
        0, "", "")
    code, out, _ = sdo(capsys, net, "upload", "5", "firmware", str(back), "--eds", DRIVE,
                       "--json")
    assert code == 0 and json.loads(out) == {"node": 5, "index": 0x2004, "sub": 0,
                                             "name": "Firmware", "bytes": len(blob)}
    assert back.read_bytes() == blob


@pytest.mark.parametrize(("args", "code", "message"), [
    (["read", "5", "Producer heartbeat tme", "--eds", DRIVE], 2,
     "did you mean 'Producer heartbeat time'"),
    (["read", "5", "Identity object", "--eds", DRIVE], 2,
     "name one of its entries, e.g. 'Identity object."),
    (["read", "5", "Producer heartbeat time"], 2, "entry names need --eds FILE"),
    (["read", "6", "Producer heartbeat time", "--eds", "5=" + DRIVE], 2,
     "entry names need --eds FILE"),
    (["write", "5", "0x1017", "100"], 2, "give TYPE VALUE"),
    (["write", "5", "Producer heartbeat time", "70000", "--eds", DRIVE], 2, "UNSIGNED16"),
    (["write", "5", "Producer heartbeat time", "u16", "1", "2", "--eds", DRIVE], 2,
     "too many arguments"),
    (["read", "5", "0x1017", "--eds", "0=" + DRIVE], 2, "bad dictionary"),
    (["read", "5", "0x1017", "--eds", DRIVE, "--eds", DRIVE], 2, "two dictionaries"),
    (["read", "5", "0x1017", "--eds", "/no/such.eds"], 1, "/no/such.eds"),
    (["read", "5", "Statusword", "u8", "--eds", DRIVE], 1, "UNSIGNED8 has 1 byte(s)"),
])
def test_sdo_name_errors(capsys: pytest.CaptureFixture[str], net: Net, args: list[str],
                         code: int, message: str) -> None:
    got, out, err = sdo(capsys, net, *args)
    assert (got, out) == (code, ""), err
    one_line_error(err)
    assert message in err


def test_scan_compares_with_the_eds(capsys: pytest.CaptureFixture[str], net: Net,
                                    tmp_path: Path) -> None:
    other = tmp_path / "other.eds"
    other.write_text(Path(DRIVE).read_text().replace("DefaultValue=0x00020192",
                                                     "DefaultValue=0x00020191"))
    code, out, _ = cli(capsys, "scan", "--bus", net.bus_url, "--timeout", "3000",
                       "--eds", DRIVE, "--eds", f"6={other}")
    assert code == 0
    lines = out.splitlines()
    assert "node 5: device type 0x00020192, canola SD-1 (drive.eds)" in lines
    assert ("node 6: device type 0x00020192, not canola SD-1: other.eds says device type "
            "0x00020191") in lines


def test_dump_file_names_sdo_entries_and_decodes_pdos(capsys: pytest.CaptureFixture[str],
                                                       tmp_path: Path) -> None:
    log = tmp_path / "x.log"
    log.write_text("(1.0) can0 605#4017100000000000\n"
                   "(1.1) can0 585#4B171000E8030000\n"
                   "(1.2) can0 185#3702\n"
                   "(1.3) can0 186#3702\n"
                   "(1.4) can0 205#0F00\n")
    code, out, _ = cli(capsys, "dump", str(log), "--eds", "5=" + DRIVE)
    assert code == 0
    lines = [line.split(None, 2)[2] for line in out.splitlines()]
    assert lines == [
        "SDO upload 0x1017:00 Producer heartbeat time request (node 5)",
        "SDO upload 0x1017:00 Producer heartbeat time = 1000 (node 5)",
        "TPDO1 node 5 Statusword = 567 (0x237)",
        "TPDO1 node 6 37 02",  # no EDS for node 6: bytes
        "RPDO1 node 5 Controlword = 15 (0xF)",
    ]
    code, out, _ = cli(capsys, "dump", str(log), "--eds", DRIVE, "--json")
    events = [json.loads(line) for line in out.splitlines()]
    assert events[3]["values"] == {"Statusword": 0x237} and events[3]["node"] == 6


def test_dump_and_monitor_live_decode_the_device_pdos(capsys: pytest.CaptureFixture[str],
                                                      net: Net) -> None:
    net.device.nmt_apply("start")
    assert wait_until(lambda: net.device.nmt_state == "OPERATIONAL", 30)
    words = itertools.cycle([0x0237, 0x0233])

    def change() -> None:  # an event-driven TPDO1 (type 255) at each change
        net.device.od[0x6041][0] = next(words)

    try:
        with repeating(change, 0.2):
            code, out, _ = cli(capsys, "dump", "--bus", net.bus_url, "--duration", "3",
                               "--eds", DRIVE, "--node", "5", "--service", "pdo")
            assert code == 0
            assert "TPDO1 node 5 Statusword = 567 (0x237)" in out, out
            code, out, _ = cli(capsys, "monitor", "--bus", net.bus_url, "--duration", "3",
                               "--eds", DRIVE, "--json")
            node5 = {n["node"]: n for n in json.loads(out)["nodes"]}[5]
            assert node5["pdo_values"]["Statusword"] in (0x237, 0x233)
            code, out, _ = cli(capsys, "monitor", "--bus", net.bus_url, "--duration", "3",
                               "--eds", DRIVE, "--once")
            assert "TPDO1: Statusword = " in out
    finally:
        net.device.nmt_apply("preop")


def _pdo(capsys: pytest.CaptureFixture[str], net: Net, *args: str) -> tuple[int, str, str]:
    return cli(capsys, "pdo", *args, "--bus", net.bus_url, "--sdo-timeout", SDO_MS)


@pytest.mark.parametrize("node", [5, 6])  # canola's device, python-canopen's LocalNode
def test_pdo_show_and_map(capsys: pytest.CaptureFixture[str], net: Net, node: int) -> None:
    code, out, _ = _pdo(capsys, net, "show", str(node), "--eds", DRIVE)
    assert code == 0
    assert out.splitlines()[:2] == [
        f"RPDO1  COB-ID 0x{0x200 + node:03X} valid, transmission type 255 "
        "(event-driven (profile))",
        "  1  0x6040:00 16 bits  Controlword"]
    assert (f"TPDO1  COB-ID 0x{0x180 + node:03X} valid, transmission type 255 "
            "(event-driven (profile)), inhibit 0 us, event timer 0 ms") in out
    code, out, err = _pdo(capsys, net, "map", str(node), "TPDO1", "Statusword",
                          "Position actual value", "--type", "254", "--event-timer", "100",
                          "--eds", DRIVE)
    assert (code, err) == (0, ""), err
    assert out.splitlines() == [
        f"TPDO1  COB-ID 0x{0x180 + node:03X} valid, transmission type 254 "
        "(event-driven (manufacturer)), inhibit 0 us, event timer 100 ms",
        "  1  0x6041:00 16 bits  Statusword",
        "  2  0x6064:00 32 bits  Position actual value"]
    # read back by show, as JSON, without an EDS: addresses for names
    code, out, _ = _pdo(capsys, net, "show", str(node), "TPDO1", "--json")
    pdo = json.loads(out)["pdos"][0]
    assert [(e["index"], e["sub"], e["bits"], e["name"]) for e in pdo["entries"]] == [
        (0x6041, 0, 16, "0x6041:00"), (0x6064, 0, 32, "0x6064:00")]
    assert (pdo["transmission_type"], pdo["event_timer_ms"], pdo["valid"]) == (254, 100, True)
    # back as the EDS has it, by addresses
    assert _pdo(capsys, net, "map", str(node), "TPDO1", "0x6041:0:16", "--type", "255",
                "--event-timer", "0")[0] == 0


@pytest.mark.parametrize(("args", "code", "message"), [
    (["map", "5", "TPDO9", "Statusword", "--eds", DRIVE], 1, "node 5 TPDO9: SDO abort"),
    (["map", "5", "XPDO1", "Statusword", "--eds", DRIVE], 2, "bad PDO 'XPDO1'"),
    (["map", "5", "TPDO1", "Statusword"], 2, "names need --eds FILE"),
    (["map", "5", "TPDO1", "Producer heartbeat time", "--eds", DRIVE], 2,
     "may not be mapped into a PDO"),
    (["map", "5", "TPDO1", "0x6041:0"], 2, "give its size in bits"),
    (["map", "5", "TPDO1", "--type", "256"], 2, "bad transmission type"),
    (["map", "5", "TPDO1", *["0x6064:0:32"] * 3], 2, "a PDO holds 64"),
    (["show", "5", "TPDO7"], 1, "node 5 has none of the PDOs asked for"),
])
def test_pdo_errors(capsys: pytest.CaptureFixture[str], net: Net, args: list[str],
                    code: int, message: str) -> None:
    got, out, err = _pdo(capsys, net, *args)
    assert (got, out) == (code, ""), err
    one_line_error(err)
    assert message in err


def test_pdo_map_that_the_device_refuses_half_way_restores_the_pdo(
        capsys: pytest.CaptureFixture[str], net: Net) -> None:
    """0x1017 (not PDO-mappable on the device) as the second entry: the device refuses
    the mapping (at its count, as CiA 301 lets it) after the PDO was made invalid and its
    entries written; the command puts the
    previous configuration back and says so (it left TPDO1 invalid with its new mapping,
    silently)."""
    before = json.loads(_pdo(capsys, net, "show", "5", "TPDO1", "--json")[1])
    code, out, err = _pdo(capsys, net, "map", "5", "TPDO1", "0x6041:0:16", "0x1017:0:16")
    assert (code, out) == (1, "")
    one_line_error(err)
    assert re.fullmatch(
        r"canola: node 5 TPDO1: SDO abort 0x06040041: Object cannot be mapped to the PDO "
        r"\(sent by node 5 after \d+\.\d\d s\) \(writing 0x1A00:00 = 0x02\); the previous "
        r"configuration is restored \(COB-ID 0x00000185 \(valid\), 1 entries\)\n", err), err
    assert json.loads(_pdo(capsys, net, "show", "5", "TPDO1", "--json")[1]) == before


def test_pdo_map_changes_what_the_device_sends(capsys: pytest.CaptureFixture[str],
                                               net: Net) -> None:
    assert _pdo(capsys, net, "map", "5", "TPDO1", "Statusword", "Position actual value",
                "--type", "255", "--event-timer", "100", "--eds", DRIVE)[0] == 0
    net.device.od[0x6064][0] = -1000
    net.device.od[0x6041][0] = 0x250
    net.device.nmt_apply("start")
    try:
        # the EDS's mapping is not the device's any more: said so
        code, out, _ = cli(capsys, "dump", "--bus", net.bus_url, "--duration", "3",
                           "--eds", DRIVE, "--id", "0x185", "--count", "1")
        assert code == 0
        assert out.split(None, 2)[2] == (
            "TPDO1 node 5 Statusword = 592 (0x250) (6 bytes, the mapping has 16 bits)\n")
        # the device's own mapping, read by SDO first
        code, out, _ = cli(capsys, "dump", "--bus", net.bus_url, "--duration", "3",
                           "--eds", DRIVE, "--id", "0x185", "--count", "1",
                           "--read-pdos", "5", "--sdo-timeout", SDO_MS)
        assert code == 0
        assert out.split(None, 2)[2] == (
            "TPDO1 node 5 Statusword = 592 (0x250), Position actual value = -1000\n"), out
        code, out, _ = cli(capsys, "monitor", "--bus", net.bus_url, "--duration", "2",
                           "--read-pdos", "5", "--sdo-timeout", SDO_MS, "--json")
        node5 = {n["node"]: n for n in json.loads(out)["nodes"]}[5]
        assert node5["pdo_values"] == {"0x6041:00": 0x250, "0x6064:00": 0xFFFFFC18}
    finally:
        net.device.nmt_apply("preop")
        _pdo(capsys, net, "map", "5", "TPDO1", "Statusword", "--event-timer", "0",
             "--eds", DRIVE)


def test_sync_and_time(capsys: pytest.CaptureFixture[str], net: Net) -> None:
    while net.peer.recv(0) is not None:
        pass
    assert cli(capsys, "sync", "5", "--counter", "3", "--count", "4", "--bus",
               net.bus_url) == (0, "", "")
    assert cli(capsys, "time", "--bus", net.bus_url, "--json") == (
        0, '{"frames": 1, "service": "time"}\n', "")
    frames = []
    while (msg := net.peer.recv(5)) is not None and len(frames) < 5:
        if msg.arbitration_id in (0x080, 0x100):
            frames.append((msg.arbitration_id, bytes(msg.data)))
    assert frames[:4] == [(0x080, b"\x01"), (0x080, b"\x02"), (0x080, b"\x03"),
                          (0x080, b"\x01")]
    assert frames[4][0] == 0x100
    today = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d")
    event = Decoder().decode(0x100, frames[4][1])
    assert event.text.startswith("TIME ") and event.text[5:15] in (today, _yesterday())


def _yesterday() -> str:  # the test may run across midnight
    day = datetime.datetime.now(datetime.UTC) - datetime.timedelta(days=1)
    return day.strftime("%Y-%m-%d")


@pytest.mark.parametrize("command", ["dump", "monitor"])
def test_read_pdos_of_a_silent_node(capsys: pytest.CaptureFixture[str], net: Net,
                                    command: str) -> None:
    code, out, err = cli(capsys, command, "--bus", net.bus_url, "--read-pdos", "9",
                         "--sdo-timeout", "300", "--duration", "1")
    assert (code, out) == (1, "")
    one_line_error(err)
    assert "no response from node 9 (SDO time-out 300 ms)" in err
