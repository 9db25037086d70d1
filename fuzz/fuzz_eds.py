# SPDX-License-Identifier: Apache-2.0
"""libFuzzer target (atheris): the EDS/DCF parser, canola.eds, on arbitrary bytes.

The parser's contract (canola.eds.parse): bad input raises EdsError and never another
exception. Beyond that, whatever parses must survive a round trip: the text write() gives
back parses again, to the same objects. Any other exception, or a round trip that fails,
is a finding (atheris reports the exception and saves the input).

Without atheris (no wheel for this Python) the script replays its arguments' files, so
the seed corpus still runs. For hours, with build-py/venv/bin/python as python:
    python fuzz/fuzz_eds.py -max_total_time=3600 build-fuzz/corpus-eds fuzz/corpus/eds
"""

from __future__ import annotations

from replay import main

try:
    import atheris
except ImportError:  # replay only
    atheris = None

if atheris is not None:
    with atheris.instrument_imports():
        from canola import EdsError
        from canola.formats import eds
else:
    from canola import EdsError
    from canola.formats import eds


def one_input(data: bytes) -> None:
    for strict in (False, True):
        try:
            od = eds.parse(data, strict=strict, filename="fuzz.eds")
        except EdsError:
            continue
        text = eds.write(od)
        again = eds.parse(text, filename="roundtrip.eds")
        if sorted(again.objects) != sorted(od.objects):
            raise AssertionError(f"round trip changed the objects: {sorted(od.objects)} -> "
                                 f"{sorted(again.objects)}")


if __name__ == "__main__":
    main("fuzz_eds", one_input, atheris)
