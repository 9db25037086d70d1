# SPDX-License-Identifier: Apache-2.0
"""canola.odnames (entries named as python-canopen names them) and canola.pdomap (PDOs
from a dictionary, decoded, read and configured by SDO), without a bus."""

from __future__ import annotations

import struct
from pathlib import Path

import canopen
import pytest

from canola.errors import SdoAbort
from canola.formats import eds
from canola.master import SdoTimeout
from canola.odnames import EntryError, entry_name, find_entry, parse_address, value_text
from canola.pdomap import (
    Mapped,
    Pdo,
    PdoConfigError,
    PdoError,
    configure_pdo,
    decode,
    mapped_entry,
    parse_pdo_name,
    pdos_from_od,
    read_pdo,
    read_pdos,
    type_bits,
)

ROOT = Path(__file__).resolve().parents[2]
DRIVE = ROOT / "examples" / "eds" / "drive.eds"
DRIVE_DCF = ROOT / "examples" / "eds" / "drive.dcf"


@pytest.fixture(scope="module")
def od() -> eds.ObjectDictionary:
    return eds.parse(DRIVE, node_id=5)


def test_every_name_is_python_canopens(od: eds.ObjectDictionary) -> None:
    """For every entry, python-canopen finds the same entry under canola's name, and
    canola finds it back."""
    theirs = canopen.import_od(str(DRIVE), 5)
    count = 0
    for obj in od.objects.values():
        for sub, var in obj.subs.items():
            name = entry_name(od, obj.index, sub)
            assert name is not None
            item = theirs[name]
            assert (item.index, item.subindex) == (obj.index, sub), name
            assert find_entry(od, name) is var
            count += 1
    assert count > 50


@pytest.mark.parametrize(("text", "address"), [
    ("Producer heartbeat time", (0x1017, 0)), ("producer HEARTBEAT time", (0x1017, 0)),
    ("Identity object.Vendor-ID", (0x1018, 1)), ("Identity object.4", (0x1018, 4)),
    ("0x1017", (0x1017, 0)), ("1018:2", (0x1018, 2)), ("0x1018:0x3", (0x1018, 3)),
    ("  Statusword ", (0x6041, 0)),
])
def test_find_entry(od: eds.ObjectDictionary, text: str, address: tuple[int, int]) -> None:
    var = find_entry(od, text)
    assert (var.index, var.subindex) == address


@pytest.mark.parametrize(("text", "message"), [
    ("Statusw", "has no entry named 'Statusw' (did you mean 'Statusword'?)"),
    ("Identity object", "name one of its entries, e.g. 'Identity object.Serial number'"),
    ("Identity object.Vendor", "has no entry named"),
    ("0x9999", "has no entry 0x9999:00"), ("0x1018:9", "has no entry 0x1018:09"),
])
def test_find_entry_errors(od: eds.ObjectDictionary, text: str, message: str) -> None:
    with pytest.raises(EntryError, match=message.replace("(", r"\(").replace(")", r"\)")
                       .replace("?", r"\?").replace(".", r"\.")):
        find_entry(od, text)


def test_names_that_match_several_entries_are_refused() -> None:
    text = ("[1000]\nParameterName=Device type\nObjectType=7\nDataType=7\nAccessType=ro\n"
            "[2000]\nParameterName=Speed\nObjectType=7\nDataType=6\nAccessType=rw\n"
            "[2001]\nParameterName=speed\nObjectType=7\nDataType=6\nAccessType=rw\n")
    od = eds.parse(text)
    assert find_entry(od, "Speed").index == 0x2000  # exact first
    with pytest.raises(EntryError, match="names several entries"):
        find_entry(od, "SPEED")


@pytest.mark.parametrize(("text", "address"), [
    ("0x1018:1", (0x1018, 1)), ("1018", (0x1018, 0)), ("0X6041:0", (0x6041, 0)),
    ("0x10180", None), ("0x1018:", None), ("0x1018:256", None), ("Statusword", None), ("", None),
])
def test_parse_address(text: str, address: tuple[int, int] | None) -> None:
    assert parse_address(text) == address


def test_value_text(od: eds.ObjectDictionary) -> None:
    assert value_text(od[0x1018].subs[1], b"\xa0\x0c\x00\x00") == "3232"
    assert value_text(od[0x6064].subs[0], b"\x18\xfc\xff\xff") == "-1000"
    assert value_text(od[0x6064].subs[0], b"\x18\xfc") == "0xFC18"  # not its size: bytes
    assert value_text(None, b"") == "(empty)"


def test_pdos_from_the_eds_and_a_dcf(od: eds.ObjectDictionary) -> None:
    pdos = {p.name: p for p in pdos_from_od(od)}
    assert sorted(pdos) == ["RPDO1", "TPDO1"]
    tpdo = pdos["TPDO1"]
    assert (tpdo.cob_id, tpdo.valid, tpdo.transmission_type, tpdo.event_timer_ms) == (
        0x185, True, 255, 0)
    assert tpdo.entries == [Mapped(0x6041, 0, 16, "Statusword", 0x0006)]
    # a DCF's ParameterValue comes before the default
    text = DRIVE_DCF.read_text().replace("[1A00sub1]\n", "[1A00sub1]\nParameterValue=0x60640020\n")
    dcf = eds.parse(text, filename="drive.dcf")
    assert {p.name: p for p in pdos_from_od(dcf)}["TPDO1"].entries == [
        Mapped(0x6064, 0, 32, "Position actual value", 0x0004)]


def test_decode_bit_level_and_dummies() -> None:
    pdo = Pdo("TPDO", 1, 0x181, entries=[
        Mapped(0x2000, 1, 1, "a", 0x0001), Mapped(0x0005, 0, 7, "0x0005:00"),  # dummy
        Mapped(0x2000, 2, 16, "b", 0x0003), Mapped(0x2000, 3, 4, "c"),
        Mapped(0x2000, 4, 32, "d", 0x0007)])
    data = bytes([0x01 | 0x7E, 0x18, 0xFC, 0x0A, 0, 0, 0])  # d does not fit: left out
    decoded = decode(pdo, data)
    assert decoded == [(pdo.entries[0], True), (pdo.entries[2], -1000), (pdo.entries[3], 0xA)]
    assert decoded[0][1] is True  # a BOOLEAN, not the number 1


def test_decode_reals_and_strings() -> None:
    pdo = Pdo("RPDO", 2, 0x305, entries=[Mapped(0x2000, 0, 32, "r", 0x0008),
                                          Mapped(0x2001, 0, 24, "s", 0x0009),
                                          Mapped(0x2002, 0, 8, "n", 0x0007)])  # not its size
    data = struct.pack("<f", 2.5) + b"abc" + b"\x07"
    assert [v for _, v in decode(pdo, data)] == [2.5, "abc", 7]
    assert (type_bits(0x0008), type_bits(0x0011), type_bits(0x000C), type_bits(0x0009),
            type_bits(0x0001), type_bits(0x0016), type_bits(0x9999)) == (
        32, 64, 48, None, 1, 24, None)


def test_mapped_entry(od: eds.ObjectDictionary) -> None:
    assert mapped_entry(od, "Position actual value").word == 0x60640020
    assert mapped_entry(od, "0x6041:0").word == 0x60410010
    assert mapped_entry(None, "0x6041:0:8").word == 0x60410008
    with pytest.raises(PdoError, match="may not be mapped"):
        mapped_entry(od, "Producer heartbeat time")
    with pytest.raises(PdoError, match="give its size in bits"):
        mapped_entry(None, "0x6041:0")
    with pytest.raises(PdoError, match="bad PDO"):
        parse_pdo_name("TPDO513")
    assert parse_pdo_name("rpdo4") == ("RPDO", 4)


class FakeSdo:
    """A device's dictionary as (index, sub) -> bytes, every transfer recorded."""

    def __init__(self, entries: dict[tuple[int, int], bytes]) -> None:
        self.entries = dict(entries)
        self.log: list[tuple[str, int, int, bytes]] = []

    def upload(self, index: int, sub: int, *, timeout: float | None = None) -> bytes:
        del timeout
        if (index, sub) not in self.entries:
            raise SdoAbort(0x06020000 if not any(i == index for i, _ in self.entries)
                           else 0x06090011)
        self.log.append(("read", index, sub, self.entries[index, sub]))
        return self.entries[index, sub]

    def download(self, index: int, sub: int, data: bytes, *,
                 timeout: float | None = None) -> None:
        del timeout
        self.log.append(("write", index, sub, data))
        self.entries[index, sub] = data


def _device() -> FakeSdo:
    return FakeSdo({(0x1800, 1): (0x40000185).to_bytes(4, "little"), (0x1800, 2): b"\xff",
                    (0x1800, 3): b"\0\0", (0x1800, 5): b"\0\0", (0x1A00, 0): b"\x01",
                    (0x1A00, 1): (0x60410010).to_bytes(4, "little")})


def test_configure_follows_the_cia301_procedure(od: eds.ObjectDictionary) -> None:
    dev = _device()
    configure_pdo(dev, "TPDO1", [mapped_entry(od, "Statusword"),
                                 mapped_entry(od, "Position actual value")],
                  transmission_type=254, event_timer_ms=100)
    writes = [(i, s, d) for kind, i, s, d in dev.log if kind == "write"]
    assert writes == [
        (0x1800, 1, (0xC0000185).to_bytes(4, "little")),  # invalid (bit 31)
        (0x1800, 2, b"\xfe"), (0x1800, 5, b"\x64\x00"),
        (0x1A00, 0, b"\x00"),  # count 0
        (0x1A00, 1, (0x60410010).to_bytes(4, "little")),
        (0x1A00, 2, (0x60640020).to_bytes(4, "little")),
        (0x1A00, 0, b"\x02"),  # count
        (0x1800, 1, (0x40000185).to_bytes(4, "little")),  # valid again, bit 30 kept
    ]
    back = read_pdo(dev, "TPDO1", od)
    assert (back.valid, back.rtr_allowed, back.transmission_type, back.event_timer_ms,
            [m.name for m in back.entries]) == (True, False, 254, 100,
                                                ["Statusword", "Position actual value"])
    with pytest.raises(PdoError, match="a PDO holds 64"):
        configure_pdo(dev, "TPDO1", [mapped_entry(od, "Position actual value")] * 3)


class RefusingSdo(FakeSdo):
    """A device that refuses one write (``refuse``: (index, sub) -> abort code) and, from
    the ``dead_after``-th write on, answers nothing."""

    def __init__(self, refuse: dict[tuple[int, int], int], dead_after: int = 1000) -> None:
        super().__init__(_device().entries)
        self.refuse, self.dead_after, self.writes = refuse, dead_after, 0

    def download(self, index: int, sub: int, data: bytes, *,
                 timeout: float | None = None) -> None:
        self.writes += 1
        if self.writes >= self.dead_after:
            raise SdoTimeout(5, 1000)
        if (index, sub) in self.refuse:
            raise SdoAbort(self.refuse[index, sub])
        super().download(index, sub, data, timeout=timeout)


def test_a_remap_that_fails_half_way_restores_the_previous_configuration(
        od: eds.ObjectDictionary) -> None:
    """The newcomer's TPDO1 was left invalid with its new mapping, and the message did
    not say so."""
    dev = RefusingSdo({(0x1A00, 2): 0x06040041})  # the second entry cannot be mapped
    before = dict(dev.entries)
    with pytest.raises(PdoConfigError) as info:
        configure_pdo(dev, "TPDO1", [mapped_entry(od, "Statusword"),
                                     mapped_entry(od, "Position actual value")],
                      transmission_type=254, event_timer_ms=100)
    assert str(info.value) == (
        "TPDO1: SDO abort 0x06040041: Object cannot be mapped to the PDO (writing "
        "0x1A00:02 = 0x60640020); the previous configuration is restored (COB-ID "
        "0x40000185 (valid), 1 entries)")
    assert dev.entries == before  # every value back, the PDO valid again
    undo = [(i, s) for kind, i, s, _ in dev.log if kind == "write"][5:]  # after the refusal
    assert undo == [(0x1800, 1), (0x1800, 2), (0x1800, 5), (0x1A00, 0), (0x1A00, 1),
                    (0x1A00, 0), (0x1800, 1)]  # CiA 301's order, valid last


def test_a_remap_whose_undo_fails_says_what_the_pdo_was_left_with(
        od: eds.ObjectDictionary) -> None:
    dev = RefusingSdo({(0x1A00, 2): 0x06040041}, dead_after=6)  # dies during the undo
    with pytest.raises(PdoConfigError) as info:
        configure_pdo(dev, "TPDO1", [mapped_entry(od, "Statusword"),
                                     mapped_entry(od, "Position actual value")])
    assert info.value.state == (
        "restoring failed (0x1A00:00 = 0x00): TPDO1 is left with COB-ID 0xC0000185 "
        "(invalid) and mapping count 0")
    assert dev.entries[0x1800, 1] == (0xC0000185).to_bytes(4, "little")
    assert dev.entries[0x1A00, 0] == b"\x00"


def test_a_failed_read_before_the_remap_changes_nothing(od: eds.ObjectDictionary) -> None:
    dev = _device()
    del dev.entries[0x1800, 5]  # no event timer on this device
    with pytest.raises(SdoAbort):
        configure_pdo(dev, "TPDO1", [mapped_entry(od, "Statusword")], event_timer_ms=100)
    assert [kind for kind, *_ in dev.log] == ["read"]  # the COB-ID; then no write


def test_read_pdos_leaves_out_what_the_device_lacks() -> None:
    dev = _device()
    del dev.entries[0x1800, 3]  # no inhibit time: None
    pdos = read_pdos(dev)  # the pre-defined set: only TPDO1 exists
    assert [p.name for p in pdos] == ["TPDO1"]
    assert pdos[0].inhibit_100us is None and pdos[0].entries[0].name == "0x6041:00"
