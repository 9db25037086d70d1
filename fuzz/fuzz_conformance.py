# SPDX-License-Identifier: Apache-2.0
"""libFuzzer target (atheris): canola.conformance against a hostile node, whose answers are
the fuzzer's bytes.

    build-py/venv/bin/python fuzz/fuzz_conformance.py -max_total_time=30 fuzz/corpus/conformance

A scripted node on the simulated bus answers each request of the tester (on its SDO COB-ID)
with the next frames of the input: a byte says how many (0..3), then per frame a byte says
its length (0..8; bit 7: on the heartbeat COB-ID instead) and the bytes follow. When the
input ends the node falls silent. The tester runs its SDO and dictionary checks against it
in virtual time, with short time-outs.

Contract: the run ends with a report (or, when nothing useful answers the first request,
canola.Error "node 5 does not answer SDO"); every check has its verdict, none is an error
of the tester (an exception of its own), and the reports render. Any other exception is a
finding. Without atheris the script replays its arguments' files (the seed corpus).
"""

from __future__ import annotations

import sys
from pathlib import Path

from replay import main

try:
    import atheris
except ImportError:  # replay only
    atheris = None

# the sources themselves: an editable install's import finder escapes atheris' import hook;
# the tests' fake node's dictionary
_ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(_ROOT / "python" / "src"), str(_ROOT / "python" / "tests")]

# the rest of canola first, uninstrumented: the fuzzer is after the tester's own handling
from conformance_fakes import FAKE_EDS  # noqa: E402

from canola import Error, Master  # noqa: E402 -- after the path
from canola.core import SimBus  # noqa: E402
from canola.formats import eds  # noqa: E402
from canola.master import Frame  # noqa: E402

if atheris is not None:
    with atheris.instrument_imports(include=["canola.conformance"]):
        import canola.conformance as cc
        from canola.conformance import checks  # noqa: F401 -- instrumented too
else:
    import canola.conformance as cc

NODE = 5
CHECKS = ["dictionary.mandatory", "sdo.expedited_upload", "sdo.segmented_download",
          "sdo.segmented_upload", "sdo.toggle_download", "sdo.block_download",
          "sdo.block_upload", "sdo.block_size"]
#: Short waits in virtual time: each costs the fuzzer time, not the verdicts any meaning.
OPTIONS = cc.Options(timeout=0.01, boot_timeout=0.02, server_timeout=0.02, quiet=0.005,
                     transfer_timeout=1.0)
MODEL = eds.parse(FAKE_EDS, node_id=NODE)  # the dictionary of the tests' fake node


class Scripted:
    """Node :data:`NODE`: every request on its SDO COB-ID is answered with the next frames
    of ``script``; NMT reset commands with a boot-up."""

    def __init__(self, bus: SimBus, script: bytes) -> None:
        self.script = script
        self.at = 0
        self.port = Master(bus, 100)
        self.port.on_frame(self._request, cob_id=0x600 + NODE)
        self.port.on_frame(self._nmt, cob_id=0x000)
        self.port.start()

    def _nmt(self, frame: Frame) -> None:
        if frame.data[:1] in (b"\x81", b"\x82") and frame.data[1:2] in (b"\0", bytes([NODE])):
            self.port.send(0x700 + NODE, b"\0")

    def _next(self, n: int) -> bytes:
        piece = self.script[self.at:self.at + n]
        self.at += n
        return piece

    def _request(self, _frame: Frame) -> None:
        count = self._next(1)
        for _ in range(count[0] % 4 if count else 0):
            head = self._next(1)
            if not head:
                return
            cob = 0x700 + NODE if head[0] & 0x80 else 0x580 + NODE
            self.port.send(cob, self._next((head[0] & 0x7F) % 9))


def one_input(data: bytes) -> None:
    bus = SimBus()
    Scripted(bus, data)
    try:
        report = cc.run(bus, NODE, MODEL, only=CHECKS, options=OPTIONS)
    except Error as exc:
        assert str(exc).startswith(f"node {NODE} does not answer SDO"), exc
        return
    assert [r.check.name for r in report.results] == CHECKS
    for result in report.results:
        for finding in result.findings:
            assert "error of the tester" not in finding.got, (result.check.name, finding)
    cc.markdown(report)
    cc.junit(report)


if __name__ == "__main__":
    main("fuzz_conformance", one_input, atheris)
