# SPDX-License-Identifier: Apache-2.0
"""atheris fuzz target: the socketcand protocol parser of the ``canola bus serve`` hub.

    build-py/venv/bin/python fuzz/fuzz_socketcand.py -max_total_time=30 fuzz/corpus/socketcand

The same functions the hub runs on what clients send (canola.bus.socketcand). Contract: any
bytes give elements or ProtocolError (a one-line message), never another exception; the
rest :func:`split_elements` leaves is at most MAX_ELEMENT bytes; cutting the input in two
(the stream arriving in pieces) gives the same elements; a command that parses formats
back (``format_send``) to an element that parses to the same command, and a server frame
that parses formats back (``format_frame``) to the same frame.
"""

from __future__ import annotations

import sys
from pathlib import Path

import atheris

# the sources themselves: an editable install's import finder escapes atheris' import hook
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "python" / "src"))

with atheris.instrument_imports(include=["canola"]):
    from canola.bus.socketcand import (
        MAX_ELEMENT,
        ProtocolError,
        format_error,
        format_frame,
        format_send,
        parse_command,
        parse_server_element,
        split_elements,
    )


def _split(data: bytes) -> tuple[list[str], bytes] | None:
    try:
        elements, rest = split_elements(data)
    except ProtocolError as exc:
        assert "\n" not in str(exc)
        return None
    assert len(rest) <= MAX_ELEMENT
    return elements, rest


def _one_element(element: str) -> None:
    assert element.startswith("<") and element.endswith(">")
    try:
        command = parse_command(element)
    except ProtocolError as exc:
        assert "\n" not in str(exc)
        assert split_elements(format_error(str(exc)).encode())[0]  # the hub's answer
    else:
        if command.frame is not None:
            again = format_send(command.frame)
            assert split_elements(again.encode()) == ([again], b"")
            assert parse_command(again) == command, (element, again)
    try:
        verb, frame, stamp = parse_server_element(element)
    except ProtocolError as exc:
        assert "\n" not in str(exc)
        return
    if frame is not None:
        again = format_frame(frame, stamp)
        verb2, frame2, _ = parse_server_element(again)
        assert (verb2, frame2) == (verb, frame), (element, again)


def test_one_input(data: bytes) -> None:
    whole = _split(data)
    if whole is None:
        return
    elements, rest = whole
    if data:  # the same stream in two pieces
        cut = data[0] % (len(data) + 1)
        first = _split(data[:cut])
        assert first is not None, data
        second = _split(first[1] + data[cut:])
        assert second is not None, data
        assert (first[0] + second[0], second[1]) == (elements, rest), data
    for element in elements:
        _one_element(element)


if __name__ == "__main__":
    atheris.Setup(sys.argv, test_one_input)
    atheris.Fuzz()
