# SPDX-License-Identifier: Apache-2.0
"""The CiA 309-3 line parser and value formats: pure functions, no network."""

from __future__ import annotations

import base64
import math
import random
import struct
from pathlib import Path

import pytest

from canola.formats import values
from canola.gateway import GatewayError, ParseError, parse_line
from canola.gateway.formats import TYPES, format_value, parse_value
from canola.gateway.parser import LSS_COMMANDS
from canola.gateway.requests import (
    Auth,
    BootUpIndication,
    DisableGuarding,
    DisableHeartbeat,
    EnableGuarding,
    EnableHeartbeat,
    Help,
    InfoVersion,
    Init,
    Lss,
    Nmt,
    PdoRead,
    PdoWrite,
    SdoRead,
    SdoWrite,
    Set,
    SetRpdo,
    SetTpdo,
)


def test_read_forms() -> None:
    assert parse_line("[1] 4 read 0x1017 0 i16\r\n") == SdoRead(1, None, 4, index=0x1017,
                                                                 sub=0, type="i16")
    assert parse_line("[2] 1 4 r 4119 0") == SdoRead(2, 1, 4, index=0x1017, sub=0)
    assert parse_line("[3] r 0x1018 1 U32") == SdoRead(3, None, None, index=0x1018, sub=1,
                                                        type="u32")
    assert parse_line("  [ 7 ]  2 READ 0x2000 010 x8 # comment") == SdoRead(
        7, None, 2, index=0x2000, sub=8, type="x8")


def test_write_forms() -> None:
    assert parse_line("[1] 4 w 0x1017 0 u16 1000") == SdoWrite(
        1, None, 4, index=0x1017, sub=0, type="u16", data=b"\xe8\x03")
    req = parse_line('[2] 4 write 0x2013 0 vs "a ""quoted"" # word"')
    assert isinstance(req, SdoWrite) and req.data == b'a "quoted" # word'
    req = parse_line("[3] w 0x2200 0 d AAEC/w==")
    assert isinstance(req, SdoWrite) and req.data == b"\x00\x01\x02\xff"
    req = parse_line("[4] w 0x2014 0 hex 01 02 ab")
    assert isinstance(req, SdoWrite) and req.data == b"\x01\x02\xab"


def test_nmt_and_set() -> None:
    assert parse_line("[1] 5 start") == Nmt(1, None, 5, command="start")
    assert parse_line("[1] 1 5 preoperational") == Nmt(1, 1, 5, command="preop")
    assert parse_line("[1] 0 reset node") == Nmt(1, None, 0, command="reset_node")
    assert parse_line("[1] reset communication") == Nmt(1, command="reset_comm")
    assert parse_line("[1] 5 reset comm") == Nmt(1, None, 5, command="reset_comm")
    assert parse_line("[9] 1 set node 4") == Set(9, 1, None, what="node", value=4)
    assert parse_line("[9] set sdo_block 1") == Set(9, what="sdo_block", value=1)
    assert parse_line("[9] set sdo_timeout 1000") == Set(9, what="sdo_timeout", value=1000)
    assert parse_line("[9] set events 1") == Set(9, what="events", value=1)


def test_other_commands() -> None:
    assert parse_line("[1] info version") == InfoVersion(1)
    assert parse_line("[1] help") == Help(1)
    assert parse_line("[1] help datatype") == Help(1, topic="datatype")
    assert parse_line("[1] 5 enable heartbeat 200") == EnableHeartbeat(1, None, 5, ms=200)
    assert parse_line("[1] 5 disable heartbeat") == DisableHeartbeat(1, None, 5)
    assert parse_line("[1] 5 enable guarding 100 3") == EnableGuarding(1, None, 5, 100, 3)
    assert parse_line("[1] init 3") == Init(1, bit_timing=3)
    assert parse_line("[1] boot_up_indication Disable") == BootUpIndication(1, enable=False)
    assert parse_line("[1] lss_switch_glob 1") == Lss(1, command="lss_switch_glob", args=(1,))
    assert parse_line("[1] 1 lss_store") == Lss(1, 1, command="lss_store")
    assert parse_line("[1] r p 2") == PdoRead(1, num=2)
    assert parse_line("[1] 1 w pdo 1 2 5 0x10") == PdoWrite(1, 1, num=1, values=(5, 16))
    token = "Zm9vYmFyLXRva2VuLTIwMjQ"
    assert parse_line(f"[3] AUTH {token} # c") == Auth(3, token=token)
    assert "Zm9v" not in repr(parse_line("[3] auth Zm9vYmFyLXRva2VuLTIwMjQ"))  # not in logs
    for bad in ("[4] auth", "[4] auth a b", "[4] 5 auth abc"):
        with pytest.raises(ParseError) as err:
            parse_line(bad)
        assert (err.value.code, err.value.seq) == (GatewayError.SYNTAX, 4)


def test_pdo_configuration() -> None:
    req = parse_line("[1] set rpdo 1 0x201 sync0 2 0x2000 0 b u16")
    assert req == SetRpdo(1, num=1, cob_id=0x201, transmission=0,
                          mapping=(0x20000001, 0x00060010))
    req = parse_line("[1] set tpdox 2 0x282 event 10 500 1 0x6000 0 i8")
    assert req == SetTpdo(1, num=2, cob_id=0x282, transmission=0xFF, inhibit=10, event=500,
                          mapping=(0x60000008,))
    req = parse_line("[1] set tpdo x 2 0x282 sync5 7 0")
    assert req == SetTpdo(1, num=2, cob_id=0x282, transmission=5, sync=7)


def test_blank_and_comment_lines() -> None:
    assert parse_line("") is None
    assert parse_line("   \r\n") is None
    assert parse_line("# just a comment") is None


@pytest.mark.parametrize(("line", "code", "seq"), [
    ("read 0x1000 0", GatewayError.SYNTAX, None),
    ("[x] read 0x1000 0", GatewayError.SYNTAX, None),
    ("[99999999999] r 0x1000 0", GatewayError.SYNTAX, None),
    ("[1] 5 fly", GatewayError.REQUEST_NOT_SUPPORTED, 1),
    ("[2] 5 r", GatewayError.SYNTAX, 2),
    ("[3] 5 r 0x10000 0", GatewayError.SYNTAX, 3),
    ("[4] 5 r 0x1000 256", GatewayError.SYNTAX, 4),
    ("[5] 5 r 0x1000 0 u33", GatewayError.SYNTAX, 5),
    ("[6] 5 r 0x1000 0 u32 extra", GatewayError.SYNTAX, 6),
    ("[7] 5 w 0x1000 0 u8 256", GatewayError.SYNTAX, 7),
    ("[8] 5 w 0x1000 0 u8", GatewayError.SYNTAX, 8),
    ("[9] 5 w 0x1000 0 i8 -129", GatewayError.SYNTAX, 9),
    ("[10] 5 w 0x1000 0 vs \"open", GatewayError.SYNTAX, 10),
    ("[11] 5 w 0x1000 0 d not*base64", GatewayError.SYNTAX, 11),
    ("[12] 1 2 3 start", GatewayError.SYNTAX, 12),
    ("[13] 5 reset everything", GatewayError.SYNTAX, 13),
    ("[14] set nothing 1", GatewayError.REQUEST_NOT_SUPPORTED, 14),
    ("[15] set sdo_block 2", GatewayError.SYNTAX, 15),
    ("[16] 1 info version", GatewayError.SYNTAX, 16),
    ("[17] led", GatewayError.REQUEST_NOT_SUPPORTED, 17),
    ("[18] 300 start", GatewayError.UNSUPPORTED_NODE, 18),
    ("[19] r p 0", GatewayError.SYNTAX, 19),
    ("[20] set rpdo 1 0x201 sometimes 0", GatewayError.SYNTAX, 20),
    ("[21] set tpdo 1 0x181 event 1 vs", GatewayError.SYNTAX, 21),
    ("[22] 5 w 0x1000 0 r32 1e39", GatewayError.SYNTAX, 22),
    ("[23] 5 w 0x1000 0 b 2", GatewayError.SYNTAX, 23),
])
def test_malformed(line: str, code: GatewayError, seq: int | None) -> None:
    with pytest.raises(ParseError) as exc:
        parse_line(line)
    assert exc.value.code == code
    assert exc.value.seq == seq


@pytest.mark.parametrize(("type_name", "text", "wire", "shown"), [
    ("b", "1", b"\x01", "1"),
    ("i8", "-128", b"\x80", "-128"),
    ("i16", "-2", b"\xfe\xff", "-2"),
    ("i24", "0x7FFFFF", b"\xff\xff\x7f", "8388607"),
    ("u32", "0xCAFEF00D", b"\x0d\xf0\xfe\xca", "3405705229"),
    ("u64", "18446744073709551615", b"\xff" * 8, "18446744073709551615"),
    ("i64", "-9223372036854775808", b"\x00" * 7 + b"\x80", "-9223372036854775808"),
    ("u40", "017", b"\x0f\x00\x00\x00\x00", "15"),
    ("x16", "4660", b"\x34\x12", "0x1234"),
    ("r32", "1.5", struct.pack("<f", 1.5), "1.5"),
    ("r32", "0.1", struct.pack("<f", 0.1), "0.1"),
    ("r64", "-2.25e-3", struct.pack("<d", -2.25e-3), "-0.00225"),
    # a NaN keeps its sign both ways (fuzz-gateway found "-nan" shown as "nan")
    ("r32", "-nan", b"\x00\x00\xc0\xff", "-nan"),
    ("r32", "NaN", b"\x00\x00\xc0\x7f", "nan"),
    ("r64", "-nan", b"\x00" * 6 + b"\xf8\xff", "-nan"),
    ("r32", "-infinity", struct.pack("<f", -math.inf), "-inf"),
    ("t", "1000 2", b"\xe8\x03\x00\x00\x02\x00", "1000 2"),
    ("td", "0 0", b"\x00" * 6, "0 0"),
    ("vs", "word", b"word", '"word"'),
    ("vs", '"two ""words"""', b'two "words"', '"two ""words"""'),
    ("vs", '"line\\nbreak\\x01"', b"line\nbreak\x01", '"line\\nbreak\\x01"'),
    ("os", "AQID", b"\x01\x02\x03", "AQID"),
    ("us", "aABpAA==", "hi".encode("utf-16-le"), "aABpAA=="),
    ("d", "", b"", ""),
    ("hex", "0a 0B", b"\x0a\x0b", "0A 0B"),
])
def test_values(type_name: str, text: str, wire: bytes, shown: str) -> None:
    assert parse_value(type_name, text) == wire
    assert format_value(type_name, wire) == shown
    assert parse_value(type_name, shown) == wire


def test_format_length_mismatch() -> None:
    with pytest.raises(ValueError):
        format_value("u16", b"\x01")
    assert format_value(None, b"\x01\x02") == "01 02"


def test_no_value_breaks_the_line() -> None:
    nasty = bytes(range(256))
    for name, spec in TYPES.items():
        text = format_value(name, nasty[:spec.size]) if spec.size else format_value(name, nasty)
        assert "\n" not in text and "\r" not in text
        if spec.kind != "vs":  # vs keeps bytes that are valid UTF-8 only
            assert parse_value(name, text) == (nasty[:spec.size] if spec.size else nasty)


def test_random_lines_never_crash() -> None:
    """Property test over random lines (the atheris target fuzz/fuzz_gateway_parser.py
    does the same without bounds): a request or ParseError, nothing else."""
    rng = random.Random(309)
    words = ["[1]", "[4294967295]", "r", "read", "w", "write", "0x1000", "0", "1", "-1",
             "u8", "i64", "vs", "d", "hex", '"', '""', "#", "set", "node", "sdo_block",
             "start", "reset", "comm", "p", "pdo", "tpdox", "rpdo", "event", "sync3", "lss_store",
             "enable", "heartbeat", "info", "version", "help", "AAAA", "\\x", "\0", "\r"]
    for _ in range(20000):
        if rng.random() < 0.5:
            line = " ".join(rng.choice(words) for _ in range(rng.randint(0, 9)))
        else:
            line = "".join(chr(rng.randint(0, 0x7F)) for _ in range(rng.randint(0, 40)))
        try:
            parse_line(line)
        except ParseError as exc:
            assert int(exc.code) >= 100


def test_types_agree_with_canola_values() -> None:
    """The gateway's text forms and canola.values agree on type codes and wire bytes."""
    for name, code in values.CIA309_NAMES.items():
        assert TYPES[name].code == code
    samples: list[tuple[str, str, values.Value]] = [
        ("b", "1", True), ("i24", "-2", -2), ("u56", "0x10", 16), ("i64", "-1", -1),
        ("r32", "0.5", 0.5), ("r64", "1e300", 1e300), ("t", "5 6", values.TimeOfDay(5, 6)),
        ("td", "7 0", values.TimeOfDay(7, 0)), ("vs", '"a b"', "a b"),
        ("us", base64.b64encode("hé".encode("utf-16-le")).decode(), "hé"),
        ("os", "AAE=", b"\x00\x01"), ("d", "AAE=", b"\x00\x01"),
    ]
    for name, text, value in samples:
        wire = parse_value(name, text)
        assert wire == values.encode(name, value), name
        assert values.decode(name, wire) == value, name


SEEDS = Path(__file__).resolve().parents[2] / "fuzz" / "corpus" / "gateway"


def test_fuzz_seeds_cover_every_command_family() -> None:
    """The seed corpus of fuzz/fuzz_gateway_parser.py: valid lines of every kind of
    request (and the lines that are answered without one), so that the fuzzer starts past
    ``[seq]``."""
    kinds: set[str] = set()
    for seed in sorted(SEEDS.iterdir()):
        try:
            request = parse_line(seed.read_bytes().decode())
        except ParseError as exc:
            kinds.add(f"error {int(exc.code)}")
            continue
        kinds.add(type(request).__name__ if request is not None else "empty")
        if isinstance(request, Lss):
            kinds.add(request.command)
    requests = {cls.__name__ for cls in (SdoRead, SdoWrite, Nmt, Set, SetRpdo, SetTpdo,
                                          PdoRead, PdoWrite, EnableHeartbeat,
                                          DisableHeartbeat, EnableGuarding, DisableGuarding,
                                          Init, BootUpIndication, InfoVersion, Help)}
    assert requests | LSS_COMMANDS - {"_lss_slowscan"} <= kinds
    assert {"empty", "error 100", "error 101"} <= kinds


def test_lss_arguments_are_bounded() -> None:
    assert parse_line("[1] lss_allnodes " + " ".join(["0"] * 11)) == Lss(
        1, command="lss_allnodes", args=(0,) * 11)
    with pytest.raises(ParseError) as exc:
        parse_line("[2] lss_allnodes " + "0 " * 100_000)
    assert (exc.value.code, exc.value.seq) == (GatewayError.SYNTAX, 2)
