# SPDX-License-Identifier: Apache-2.0
"""atheris fuzz target: the CiA 309-3 gateway line parser and value formats.

    build-py/venv/bin/python fuzz/fuzz_gateway_parser.py -max_total_time=30

Any input must give a request, None, or ParseError (a CiA 309-3 code >= 100); a request
that carries written bytes must format back to text without a line break, and that text
must read back as the same bytes.

Seeds: fuzz/corpus/gateway/ (a line of every command family); dictionary:
fuzz/gateway.dict (``-dict=``). ``make fuzz-gateway`` passes both.
"""

from __future__ import annotations

import sys
from pathlib import Path

import atheris

# the sources themselves: an editable install's import finder escapes atheris' import hook
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "python" / "src"))

with atheris.instrument_imports(include=["canola"]):
    from canola.gateway.formats import format_value, parse_value
    from canola.gateway.parser import ParseError, parse_line
    from canola.gateway.requests import SdoWrite


def test_one_input(data: bytes) -> None:
    line = data.decode("utf-8", "replace")
    try:
        request = parse_line(line)
    except ParseError as exc:
        assert int(exc.code) >= 100
        return
    if isinstance(request, SdoWrite):
        try:
            text = format_value(request.type, request.data)
        except ValueError:
            return
        assert "\n" not in text and "\r" not in text
        assert parse_value(request.type, text) == request.data, (request.type, text)


if __name__ == "__main__":
    atheris.Setup(sys.argv, test_one_input)
    atheris.Fuzz()
