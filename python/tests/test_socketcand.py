# SPDX-License-Identifier: Apache-2.0
"""The socketcand protocol functions: splitting, parsing, formatting (pure, no sockets)."""

from __future__ import annotations

import contextlib
import random

import pytest

from canola.bus.socketcand import (
    MAX_ELEMENT,
    Frame,
    ProtocolError,
    format_error,
    format_frame,
    format_send,
    parse_command,
    parse_server_element,
    split_elements,
)


def test_split_complete_and_partial() -> None:
    elements, rest = split_elements(b"< open vcan0 >< rawmode >\n  < send 1")
    assert elements == ["< open vcan0 >", "< rawmode >"]
    assert rest == b"< send 1"
    assert split_elements(b"  \r\n") == ([], b"")


@pytest.mark.parametrize("bad", [b"hello", b"< a < b >", b"x< hi >", b"< caf\xc3\xa9 >",
                                 b"< bell\x07 >", b"<" + b"1" * MAX_ELEMENT,
                                 b"< " + b"1" * MAX_ELEMENT + b" >"])
def test_split_rejects_garbage(bad: bytes) -> None:
    with pytest.raises(ProtocolError):
        split_elements(bad)


def test_parse_send_as_python_can_writes_it() -> None:
    # python-can: f"< send {id:03X} {len:X} {' '.join(f'{b:x}' for b in data)} >"
    cmd = parse_command("< send 123 3 1 a ff >")
    assert cmd.verb == "send"
    assert cmd.frame == Frame(0x123, b"\x01\x0a\xff")
    empty = parse_command("< send 000 0  >")
    assert empty.frame == Frame(0, b"")
    ext = parse_command("< send 1AAAAAAA 2 1 F1 >")
    assert ext.frame == Frame(0x1AAAAAAA, b"\x01\xf1", extended=True)
    assert parse_command("< sendrtr 70A 1 >").frame == Frame(0x70A, rtr=True, dlc=1)


@pytest.mark.parametrize("bad", [
    "< send >", "< send 123 >", "< send 800 0 >", "< send 1234 0 >", "< send 3FFFFFFF 0 >",
    "< send 123 9 1 2 3 4 5 6 7 8 9 >", "< send 123 2 1 >", "< send 123 1 1 2 >",
    "< send 123 1 123 >", "< send 12g 0 >", "< send 123 x >", "< open >",
    "< open a b >", "< open " + "a" * 17 + " >", "< open bad/name >", "< frobnicate >",
    "< rawmode now >", "<>", "< >",
])
def test_parse_rejects(bad: str) -> None:
    with pytest.raises(ProtocolError) as info:
        parse_command(bad)
    assert "\n" not in str(info.value)


def test_known_but_unoffered_commands_parse() -> None:
    assert parse_command("< subscribe 0 0 123 >").verb == "subscribe"


def test_format_frame_is_what_python_can_parses() -> None:
    assert format_frame(Frame(0x123, b"\x11\x22"), 23.4242421) == "< frame 123 23.424242 1122 >"
    assert format_frame(Frame(0x80), 1.0) == "< frame 080 1.000000  >"
    assert format_frame(Frame(0x1ABC, b"\x01", extended=True), 0.5) == (
        "< frame 00001ABC 0.500000 01 >")
    assert format_frame(Frame(0x705, rtr=True, dlc=1), 2.0) == "< rtr 705 2.000000 1 >"


def test_round_trips() -> None:
    for frame in (Frame(0x7FF, bytes(range(8))), Frame(0, b""),
                  Frame(0x1FFFFFFF, b"\xff", extended=True), Frame(0x123, rtr=True, dlc=4)):
        assert parse_command(format_send(frame)).frame == frame
        verb, back, stamp = parse_server_element(format_frame(frame, 12.5))
        assert back == frame and stamp == 12.5
        assert verb == ("rtr" if frame.rtr else "frame")


def test_error_text_is_safe() -> None:
    text = format_error("bad <thing>\nnext line " + "x" * 200)
    assert text.startswith("< error bad (thing) next line") and text.endswith(" >")
    assert "\n" not in text and len(text) < 120
    assert split_elements(text.encode())[0] == [text]


def test_frame_checks() -> None:
    with pytest.raises(ProtocolError):
        Frame(0x800)
    with pytest.raises(ProtocolError):
        Frame(1, bytes(9))
    with pytest.raises(ProtocolError):
        Frame(1, b"\x00", rtr=True)


def test_random_input_only_raises_protocol_error() -> None:
    rng = random.Random(1234)
    alphabet = b"<> sendopraw0123456789ABCDEFabcdefx\n\t\x00\xff"
    for _ in range(20000):
        blob = bytes(rng.choice(alphabet) for _ in range(rng.randrange(0, 60)))
        try:
            elements, rest = split_elements(blob)
        except ProtocolError:
            continue
        assert len(rest) <= MAX_ELEMENT
        for element in elements:
            with contextlib.suppress(ProtocolError):
                parse_command(element)
            with contextlib.suppress(ProtocolError):
                parse_server_element(element)
