# SPDX-License-Identifier: Apache-2.0
"""The C core through cffi: two nodes from the sample EDS on a simulated bus."""

from __future__ import annotations

from pathlib import Path

import pytest

from canola import Error, SdoAbort
from canola.core import Od, SimBus
from canola.formats import eds
from canola.formats.odgen import GenerateOptions
from canola.simnode import Node

SAMPLE = Path(__file__).parent / "golden" / "sample.eds"
MODES = ("auto", "segmented", "block")


@pytest.fixture
def net() -> tuple[SimBus, Node, Node]:
    model = eds.parse(SAMPLE)
    opts = GenerateOptions(min_string_size=64)
    bus = SimBus()
    master = Node(bus, Od.from_eds(model, 1, opts), 1)
    device = Node(bus, Od.from_eds(model, 2, opts), 2)
    master.start()
    device.start()
    bus.run_for(10_000)
    return bus, master, device


def _lines(bus: SimBus) -> list[str]:
    return [line.split()[-1] for line in bus.trace]


def test_bootup_in_trace(net: tuple[SimBus, Node, Node]) -> None:
    bus, master, device = net
    assert "701#00" in _lines(bus)
    assert "702#00" in _lines(bus)
    assert bus.trace[0].startswith("(0.000000) sim0 ")
    assert master.state == device.state == 0x7F
    assert device.state_name == "pre-operational"


def test_local_read_write(net: tuple[SimBus, Node, Node]) -> None:
    _, _, device = net
    assert device.read(0x1018, 1) == (0xCA0).to_bytes(4, "little")
    assert device.read(0x200C, 0) == (2).to_bytes(4, "little")  # $NODEID
    device.write(0x200C, 0, (0x12345678).to_bytes(4, "little"))
    assert device.get_uint(0x200C, 0) == 0x12345678
    with pytest.raises(SdoAbort) as exc:
        device.write(0x1018, 1, b"\0\0\0\0")
    assert exc.value.code == 0x06010002
    with pytest.raises(SdoAbort) as exc:
        device.write(0x200C, 0, b"\0")
    assert exc.value.code == 0x06070013


def test_sdo_read_identity(net: tuple[SimBus, Node, Node]) -> None:
    bus, master, _ = net
    assert master.sdo_upload(2, 0x1018, 1) == (0xCA0).to_bytes(4, "little")
    assert "602#4018100100000000" in _lines(bus)
    assert master.sdo_upload(2, 0x1008, 0, "segmented") == b"canola sample"


@pytest.mark.parametrize("mode", MODES)
def test_sdo_u32_and_string(net: tuple[SimBus, Node, Node], mode: str) -> None:
    _, master, device = net
    value = (0xCAFEF00D).to_bytes(4, "little")
    master.sdo_download(2, 0x200C, 0, value, mode)  # type: ignore[arg-type]
    assert master.sdo_upload(2, 0x200C, 0, mode) == value  # type: ignore[arg-type]
    assert device.get_uint(0x200C, 0) == 0xCAFEF00D
    text = f"written in {mode} mode, longer than seven bytes".encode()
    master.sdo_download(2, 0x2013, 0, text, mode)  # type: ignore[arg-type]
    assert master.sdo_upload(2, 0x2013, 0, mode) == text  # type: ignore[arg-type]
    assert device.read(0x2013, 0) == text


@pytest.mark.parametrize("mode", MODES)
def test_sdo_abort_unknown_object(net: tuple[SimBus, Node, Node], mode: str) -> None:
    _, master, _ = net
    with pytest.raises(SdoAbort) as exc:
        master.sdo_upload(2, 0x5555, 0, mode)  # type: ignore[arg-type]
    assert exc.value.code == 0x06020000
    assert "does not exist" in str(exc.value)
    with pytest.raises(SdoAbort) as exc:
        master.sdo_download(2, 0x5555, 0, b"\1\2\3\4\5\6\7\x08", mode)  # type: ignore[arg-type]
    assert exc.value.code == 0x06020000


def test_sdo_timeout(net: tuple[SimBus, Node, Node]) -> None:
    _, master, _ = net
    with pytest.raises(SdoAbort) as exc:  # nobody at 0x7F: the client's own time-out
        master.sdo_upload(0x7F, 0x1000, 0)
    assert exc.value.code == 0x05040000
    with pytest.raises(Error, match="no completion"):
        master.sdo_upload(0x7E, 0x1000, 0, timeout_us=100_000)


def test_nmt_start_and_heartbeat(net: tuple[SimBus, Node, Node]) -> None:
    bus, master, device = net
    master.nmt("start", 2)
    assert device.state == 0x05
    assert master.state == 0x7F
    assert "000#0102" in _lines(bus)
    bus.run_for(1_100_000)  # 0x1017 = 1000 ms
    assert "702#05" in _lines(bus)
    master.nmt("stop", 0)
    assert device.state == master.state == 0x04
