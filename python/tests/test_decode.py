# SPDX-License-Identifier: Apache-2.0
"""The CANopen decoder and the candump reader, on hand-made frames and on real traffic of the
C core (SimBus trace: expedited, segmented and block SDO, NMT, heartbeats)."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from canola.bus.candump import CandumpError, LogFrame, parse_line, read_log
from canola.core import Od, SimBus
from canola.decode import Decoder, emcy_text, format_value
from canola.emcycodes import emcy_class, emcy_line, register_text
from canola.formats import eds
from canola.formats.odgen import GenerateOptions
from canola.simnode import Node

SAMPLE = Path(__file__).parent / "golden" / "sample.eds"


def _texts(lines: list[str]) -> list[str]:
    decoder = Decoder()
    out = []
    for frame in read_log(io.StringIO("\n".join(lines))):
        out.append(decoder.decode(frame.can_id, frame.data, rtr=frame.rtr,
                                  extended=frame.extended).text)
    return out


def test_simple_services() -> None:
    assert _texts([
        "(1.0) can0 000#0105", "(1.0) can0 000#8100", "(1.0) can0 080#", "(1.0) can0 080#03",
        "(1.0) can0 705#05", "(1.0) can0 705#7F", "(1.0) can0 705#00", "(1.0) can0 705#R",
        "(1.0) can0 705#85", "(1.0) can0 083#1042080000000000", "(1.0) can0 083#0000000000000000",
        "(1.0) can0 185#0102", "(1.0) can0 205#", "(1.0) can0 485#R",
        "(1.0) can0 100#E80300000100",
    ]) == [
        "NMT start node 5", "NMT reset-node all", "SYNC", "SYNC counter 3",
        "node 5 heartbeat OPERATIONAL", "node 5 heartbeat PRE-OPERATIONAL", "node 5 boot-up",
        "node 5 guarding request", "node 5 guarding OPERATIONAL toggle 1",
        "EMCY node 3 0x4210 device temperature, error register 0x08 (temperature)",
        "EMCY node 3 0x0000 error reset / no error, error register 0x00 (none)",
        "TPDO1 node 5 01 02", "RPDO1 node 5 (empty)", "TPDO4 node 5 remote request",
        "TIME 1984-01-02 00:00:01.000",
    ]


def test_emcy_names_and_values() -> None:
    assert emcy_text(0x8130) == "life guard / heartbeat error"
    assert emcy_text(0x3210) == "voltage inside the device"  # its group, 0x32xx
    assert emcy_text(0x3410) == "voltage"  # its class, 0x3xxx
    assert emcy_text(0xFF42) == "device specific"
    assert emcy_text(0x8150) == "CAN-ID collision (another node uses this node-ID)"
    assert emcy_text(0xFF11) == "stored communication parameters refused (defaults in use)"
    assert emcy_class(0x8150) == "monitoring" and emcy_class(0x4210) == "temperature"
    assert register_text(0) == "none"
    assert register_text(0x91) == "generic, communication, manufacturer"
    assert emcy_line(0x8150, 0x11, b"\x00\x05\x00\x00\x00") == (
        "0x8150 CAN-ID collision (another node uses this node-ID), error register 0x11 "
        "(generic, communication), data 00 05 00 00 00")
    assert format_value(b"\x04\x00\x00\x00") == "0x00000004"
    assert format_value(b"canola sample") == "'canola sample' (13 bytes)"
    assert format_value(bytes(40)).endswith("... ] (40 bytes)".replace(" ]", "]"))


def test_untyped_values_numbers_and_utf8_text() -> None:
    # four bytes are a number, even when they happen to be letters
    assert format_value(b"ABCD") == "0x44434241"
    assert format_value(b"abc") == "0x636261"
    assert format_value(b"\x00\x10\x00\x20") == "0x20001000"
    # longer values read as text when they are printable UTF-8
    assert format_value("2 €uro".encode()) == "'2 €uro' (8 bytes)"
    assert format_value("Größe µm".encode()) == "'Größe µm' (11 bytes)"
    assert format_value(b"canola\x00\x00") == "'canola' (8 bytes)"
    assert format_value(b"\x01\x02\x03\x04\x05") == "0x0504030201"
    assert format_value(b"\xe2\x82abcdefgh") == "[E2 82 61 62 63 64 65 66 67 68] (10 bytes)"


def test_sdo_expedited_and_abort_by_hand() -> None:
    assert _texts([
        "(1.0) can0 605#4018100100000000", "(1.0) can0 585#4318100104000000",
        "(1.0) can0 605#2B171000E8030000", "(1.0) can0 585#6017100000000000",
        "(1.0) can0 605#4055550000000000", "(1.0) can0 585#8055550000000206",
        "(1.0) can0 585#00", "(1.0) can0 585#0000000000000000",
    ]) == [
        "SDO upload 0x1018:01 request (node 5)", "SDO upload 0x1018:01 = 0x00000004 (node 5)",
        "SDO download 0x1017:00 = 0x03E8 (node 5)", "SDO download 0x1017:00 ok (node 5)",
        "SDO upload 0x5555:00 request (node 5)",
        "SDO abort 0x5555:00 0x06020000 Object does not exist in the object dictionary by "
        "server (node 5)",
        "SDO bad response length 1 (node 5)", "SDO upload segment outside a transfer (node 5)",
    ]


@pytest.fixture
def sim() -> tuple[SimBus, Node, Node]:
    model = eds.parse(SAMPLE)
    opts = GenerateOptions(min_string_size=64)
    bus = SimBus()
    master = Node(bus, Od.from_eds(model, 1, opts), 1)
    device = Node(bus, Od.from_eds(model, 2, opts), 2)
    master.start()
    device.start()
    bus.run_for(10_000)
    return bus, master, device


@pytest.mark.parametrize("mode", ["expedited", "segmented", "block"])
def test_sdo_transfers_of_the_core(sim: tuple[SimBus, Node, Node], mode: str) -> None:
    bus, master, _ = sim
    text = b"a string written by SDO, longer than one block segment or two"
    value = (0xCAFEF00D).to_bytes(4, "little")
    master.sdo_download(2, 0x200C, 0, value, mode)  # type: ignore[arg-type]
    master.sdo_upload(2, 0x200C, 0, mode)  # type: ignore[arg-type]
    if mode != "expedited":
        master.sdo_download(2, 0x2013, 0, text, mode)  # type: ignore[arg-type]
        master.sdo_upload(2, 0x2013, 0, mode)  # type: ignore[arg-type]
    master.nmt("start", 2)
    texts = _texts(bus.trace)
    assert "node 1 boot-up" in texts and "NMT start node 2" in texts
    sdo = [t for t in texts if t.startswith("SDO") and " = " in t]
    kind = "block " if mode == "block" else ""
    expect_int = [f"SDO {kind}download 0x200C:00 = 0xCAFEF00D (node 2)",
                  f"SDO {kind}upload 0x200C:00 = 0xCAFEF00D (node 2)"]
    if mode == "expedited":
        expect_int = [t.replace("block ", "") for t in expect_int]
        assert sdo == expect_int
    else:
        quoted = f"{text.decode()!r} ({len(text)} bytes)"
        assert sdo[:2] == expect_int
        assert sdo[-2:] == [f"SDO {kind}download 0x2013:00 = {quoted} (node 2)",
                            f"SDO {kind}upload 0x2013:00 = {quoted} (node 2)"]
    assert not [t for t in texts if "outside a transfer" in t or "bad" in t]


def test_decoder_survives_every_byte_pattern() -> None:
    decoder = Decoder()
    for can_id in (0x000, 0x080, 0x085, 0x100, 0x185, 0x585, 0x605, 0x705, 0x7E5, 0x7FF):
        for first in range(256):
            for length in (0, 1, 2, 6, 8):
                data = bytes([first] + [0xA5] * 7)[:length]
                event = decoder.decode(can_id, data)
                assert event.text and "\n" not in event.text


def test_candump_formats() -> None:
    assert parse_line("(1700000000.123456) can0 705#05") == LogFrame(
        1700000000.123456, "can0", 0x705, b"\x05", False, False)
    assert parse_line("  vcan0  705   [1]  05") == LogFrame(None, "vcan0", 0x705, b"\x05",
                                                              False, False)
    assert parse_line(" (000.000100)  can0  12345678   [2]  01 02") == LogFrame(
        0.0001, "can0", 0x12345678, b"\x01\x02", True, False)
    assert parse_line("  can0  705   [1]  remote request") == LogFrame(
        None, "can0", 0x705, b"", False, True)
    assert parse_line("(1.5) can0 705#R") == LogFrame(1.5, "can0", 0x705, b"", False, True)
    assert parse_line("") is None and parse_line("# comment") is None
    for bad in ("hello", "(1.0) can0 705#0", "(1.0) can0 800#", "  can0  705   [2]  05",
                "(1.0) can0 705##105", "(1.0) can0 705#010203040506070809"):
        with pytest.raises(CandumpError):
            parse_line(bad)
    with pytest.raises(CandumpError, match=r"^log:2: "):
        list(read_log(io.StringIO("(1.0) can0 705#05\nbroken\n"), "log"))
