# SPDX-License-Identifier: Apache-2.0
"""Network descriptions of the CANopen manager: YAML files, DCF files, concise DCFs."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest
from managed import DEVICE_TYPE, EDS, PRODUCT, REVISION, VENDOR, write_dcf

from canola import boot_plan as network
from canola.boot_plan import Identity, NetworkError
from canola.errors import Error
from canola.formats import concise, eds


def test_yaml_network(tmp_path: Path) -> None:
    write_dcf(tmp_path / "drive.dcf", 9, {(0x1017, 0): "100", (0x2001, 0): "0x1234"})
    (tmp_path / "net.yaml").write_text("""
start: all
master_start: false
reset_slaves: true
nodes:
  - id: 2
    identity: {device_type: 0x191, vendor: 0xCA0, product: 1, revision: 0x10000, serial: 7}
    dcf: drive.dcf
    heartbeat_ms: 500
  - id: 3
    optional: true
    boot_on_bootup: false
    keep_alive: true
  - dcf: drive.dcf           # id from the DCF, identity from its values
    mandatory: false
""")
    net = network.load(tmp_path / "net.yaml")
    assert (net.start, net.master_start, net.reset_slaves) == ("all", False, True)
    two, three, nine = net.slaves
    assert two.node_id == 2 and two.mandatory and two.heartbeat_ms == 500
    assert two.identity == Identity(0x191, 0xCA0, 1, 0x10000, 7)
    assert two.dcf == str(tmp_path / "drive.dcf")
    assert two.config is not None
    assert concise.parse(two.config) == [(0x1017, 0, struct.pack("<H", 100)),
                                         (0x2001, 0, struct.pack("<I", 0x1234))]
    assert not three.mandatory and not three.boot_on_bootup and three.keep_alive
    assert three.config is None and three.identity == Identity()
    assert nine.node_id == 9 and not nine.mandatory
    assert nine.identity == Identity(DEVICE_TYPE, VENDOR, PRODUCT, REVISION, 1)
    assert net.slave(3) is three and net.slave(4) is None


def test_dcf_network(tmp_path: Path) -> None:
    a = write_dcf(tmp_path / "a.dcf", 4, {(0x2000, 0): "500"}, serial=0x44)
    b = write_dcf(tmp_path / "b.dcf", 3, {})
    net = network.from_files([a, b])
    assert [s.node_id for s in net.slaves] == [3, 4]
    assert all(s.mandatory for s in net.slaves)
    assert net.slaves[1].identity.serial == 0x44
    assert net.slaves[0].config == concise.build([])
    assert net.start == "each"


def _error(tmp_path: Path, text: str, **kw: int) -> str:
    path = tmp_path / "net.yaml"
    path.write_text(text)
    with pytest.raises(NetworkError) as info:
        network.load(path, **kw)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: ")
    return message[len(f"{path}: "):]


@pytest.mark.parametrize(("text", "expected"), [
    ("nodes: [", "line 1, column 9: not valid YAML: expected the node content"),
    ("- 1\n- 2\n", "expected a mapping, got [1, 2]"),
    ("nodes: []\n", "nodes: expected a list of at least one node"),
    ("nodes:\n  - id: 2\nspeed: 3\n", "speed: unknown key"),
    ("start: some\nnodes: [{id: 2}]\n", "start: expected all, each or none, got 'some'"),
    ("master_start: 1\nnodes: [{id: 2}]\n", "master_start: expected true or false, got 1"),
    ("nodes: [{id: 200}]\n", "nodes[0].id: 200 is outside 1..127"),
    ("nodes: [{id: two}]\n", "nodes[0].id: expected an integer, got 'two'"),
    ("nodes: [{optional: true}]\n", "nodes[0].id: missing (and no DCF NodeID"),
    ("nodes: [{id: 2}, {id: 2}]\n", "nodes[1].id: node 2 is listed twice (also nodes[0])"),
    ("nodes: [{id: 2, colour: red}]\n", "nodes[0].colour: unknown key"),
    ("nodes: [{id: 2, identity: {vendor: -1}}]\n",
     "nodes[0].identity.vendor: -1 is outside 0..4294967295"),
    ("nodes: [{id: 2, identity: {vendr: 1}}]\n", "nodes[0].identity.vendr: unknown key"),
    ("nodes: [{id: 2, identity: 5}]\n", "nodes[0].identity: expected a mapping, got 5"),
    ("nodes: [{id: 2, heartbeat_ms: 70000}]\n",
     "nodes[0].heartbeat_ms: 70000 is outside 0..65535"),
    ("nodes: [{id: 2, mandatory: true, optional: true}]\n",
     "nodes[0].optional: contradicts mandatory"),
    ("nodes: [{id: 2, dcf: 5}]\n", "nodes[0].dcf: expected a file name, got 5"),
    ("nodes: [{id: 2, dcf: nowhere.dcf}]\n", "nodes[0].dcf: "),
])
def test_yaml_errors_name_file_and_key(tmp_path: Path, text: str, expected: str) -> None:
    assert expected in _error(tmp_path, text)


def test_master_itself_is_refused(tmp_path: Path) -> None:
    assert "nodes[0].id: node 1 is the master itself" in _error(
        tmp_path, "nodes: [{id: 1}]\n", node_id_of_master=1)


def test_bad_files(tmp_path: Path) -> None:
    with pytest.raises(NetworkError, match="cannot read"):
        network.load(tmp_path / "none.yaml")
    (tmp_path / "bin.yaml").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(NetworkError, match="not UTF-8"):
        network.load(tmp_path / "bin.yaml")
    with pytest.raises(NetworkError, match="comes alone"):
        network.from_files([tmp_path / "a.yaml", tmp_path / "b.dcf"])
    with pytest.raises(NetworkError, match="no DCF given"):
        network.from_dcfs([])


def test_dcf_errors(tmp_path: Path) -> None:
    plain = tmp_path / "plain.dcf"
    plain.write_text(EDS.read_text())  # no [DeviceComissioning]
    with pytest.raises(NetworkError, match=r"NodeID: missing or outside 1\.\.127"):
        network.from_dcfs([plain])
    a = write_dcf(tmp_path / "a.dcf", 3, {})
    b = write_dcf(tmp_path / "b.dcf", 3, {})
    with pytest.raises(NetworkError, match="node 3 is also"):
        network.from_dcfs([a, b])
    with pytest.raises(NetworkError, match="node 3 is the master itself"):
        network.from_dcfs([a], node_id_of_master=3)
    bad = write_dcf(tmp_path / "bad.dcf", 5, {(0x2000, 0): "lots"})
    with pytest.raises(NetworkError, match=r"bad\.dcf.*\[2000\] ParameterValue"):
        network.from_dcfs([bad])
    with pytest.raises(NetworkError, match="cannot read file"):
        network.from_dcfs([tmp_path / "missing.dcf"])
    assert isinstance(NetworkError("f", None, "x"), Error)


def test_concise_format() -> None:
    records = [(0x1017, 0, b"\x64\x00"), (0x2001, 0, b"\x01\x02\x03\x04"), (0x1008, 0, b"")]
    data = concise.build(records)
    assert data[:4] == b"\x03\x00\x00\x00"
    assert data[4:11] == b"\x17\x10\x00\x02\x00\x00\x00"
    assert concise.parse(data) == records
    for broken in (b"", data[:-1], data + b"\x00", b"\x01\x00\x00\x00\x17\x10"):
        with pytest.raises(ValueError):
            concise.parse(broken)


def test_concise_from_dcf_types() -> None:
    m = eds.parse(EDS)
    m.objects[0x1018].subs[4].parameter_value = "5"  # read-only: not downloaded
    m.objects[0x2000].subs[0].parameter_value = "0x20"
    m.objects[0x1F50].subs[1].parameter_value = "0a0B 0c"  # DOMAIN as hex
    assert concise.from_dcf(m) == [(0x1F50, 1, b"\x0a\x0b\x0c"), (0x2000, 0, b"\x20\x00")]
    text = eds.parse(DCF_STRINGS, filename="s.dcf")
    assert concise.from_dcf(text) == [(0x2002, 0, b"hello"), (0x2003, 0, b"\x01\xff")]


DCF_STRINGS = """[DeviceComissioning]
NodeID=5
[2002]
ParameterName=Name
ObjectType=0x7
DataType=0x0009
AccessType=rw
DefaultValue=
ParameterValue=hello
[2003]
ParameterName=Bytes
ObjectType=0x7
DataType=0x000A
AccessType=rw
ParameterValue=0x01FF
"""


INTEROP = Path(__file__).parent / "data" / "interop.eds"


def _remapping_dcf(tmp_path: Path, node_id: int = 5) -> Path:
    """A DCF of interop.eds that re-maps TPDO1 and RPDO1 (ParameterValues)."""
    m = eds.parse(INTEROP)
    m.device_commissioning = {"NodeID": str(node_id), "NodeName": "remapped"}
    values = {(0x1017, 0): "100",
              (0x1800, 1): "$NODEID+0x180", (0x1800, 2): "1", (0x1800, 3): "10",
              (0x1A00, 0): "1", (0x1A00, 1): "0x20070020",
              (0x1400, 1): "$NODEID+0x200", (0x1600, 0): "1", (0x1600, 1): "0x20010008",
              (0x2005, 0): "9"}
    for (index, sub), text in values.items():
        m.objects[index].subs[sub].parameter_value = text
    path = tmp_path / "remapped.dcf"
    path.write_text(eds.write(m, dcf=True), encoding="latin-1")
    return path


def test_concise_dcf_puts_pdos_in_the_remapping_order(tmp_path: Path) -> None:
    records = concise.from_dcf(eds.parse(_remapping_dcf(tmp_path)))
    u32 = lambda v: struct.pack("<I", v)  # noqa: E731
    assert records == [
        (0x1017, 0, struct.pack("<H", 100)),
        # RPDO1: off, mapping count 0, entries, count, the rest, on
        (0x1400, 1, u32(0x80000205)), (0x1600, 0, b"\x00"), (0x1600, 1, u32(0x20010008)),
        (0x1600, 0, b"\x01"), (0x1400, 1, u32(0x205)),
        # TPDO1 likewise, with its transmission type and inhibit time
        (0x1800, 1, u32(0x80000185)), (0x1A00, 0, b"\x00"), (0x1A00, 1, u32(0x20070020)),
        (0x1A00, 0, b"\x01"), (0x1800, 2, b"\x01"), (0x1800, 3, b"\x0a\x00"),
        (0x1800, 1, u32(0x185)),
        (0x2005, 0, b"\x09"),
    ]


def test_pdo_order_without_cob_id_or_count() -> None:
    mapping = [(0x1A01, 2, b"\x10\x00\x06\x20"), (0x1A01, 1, b"\x08\x00\x05\x20")]
    # the COB-ID from cob_ids (a DCF's DefaultValue), the count from the entries
    assert concise.pdo_order(mapping, {0x1801: struct.pack("<I", 0x286)}) == [
        (0x1801, 1, struct.pack("<I", 0x80000286)), (0x1A01, 0, b"\x00"),
        (0x1A01, 1, b"\x08\x00\x05\x20"), (0x1A01, 2, b"\x10\x00\x06\x20"),
        (0x1A01, 0, b"\x02"), (0x1801, 1, struct.pack("<I", 0x286))]
    # no COB-ID known: the mapping alone; a COB-ID given as off stays off
    assert concise.pdo_order(mapping)[0] == (0x1A01, 0, b"\x00")
    off = struct.pack("<I", 0x80000190)
    assert concise.pdo_order([(0x1802, 1, off)]) == [(0x1802, 1, off), (0x1802, 1, off)]
