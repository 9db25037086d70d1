"""The EDS in the everyday commands: ``--eds``/``--dcf`` (per node: ``--eds N=FILE``) give
``canola sdo``, ``scan``, ``dump`` and ``monitor`` entry names, types, typed values and PDO
mappings. Against a canola device (node 5) and python-canopen's LocalNode (node 6) on one
python-can virtual bus, the commands run in this process."""

from __future__ import annotations

import contextlib
import itertools
import json
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import can
import canopen
import pytest
from cli_helpers import cli, one_line_error
from conftest import wait_until

import canola

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


@contextlib.contextmanager
def repeating(action: Callable[[], None], pause: float = 0.2) -> Iterator[None]:
    """Do ``action`` again and again while the block runs (a live command opens its bus
    at a moment the test does not know)."""
    stop = threading.Event()
    thread = threading.Thread(target=lambda: [action() for _ in iter(
        lambda: stop.wait(pause), True)], daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join(5)


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
        with repeating(change):
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
