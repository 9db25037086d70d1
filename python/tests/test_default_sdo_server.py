# SPDX-License-Identifier: Apache-2.0
"""The default SDO server answers on 0x600/0x580 + node-ID whatever the DCF says.

CiA 301 fixes the default server's COB-IDs (0x1200 sub1 and sub2, read-only). A real DCF
(OreSat's battery card) sets both to 0x80000000, not valid: the device must still be
reachable, 0x1200 must read the COB-IDs it serves on, and the device says where the file
deviates (a warning naming the file and the entry). In virtual time, on the simulated bus.
"""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from canola.core import SimBus
from canola.device import Device
from canola.master import Master

EDS = Path(__file__).parent / "data" / "cli_device.eds"

def _cob_id(sub: int, name: str, base: int) -> str:
    """Section [1200subN]: a COB-ID that OreSat's DCF sets to 0x80000000 (not valid)."""
    return (f"\n[1200sub{sub}]\nParameterName={name}\nObjectType=0x7\nDataType=0x0007\n"
            f"AccessType=ro\nDefaultValue=$NODEID+0x{base:X}\nParameterValue=0x80000000\n"
            "PDOMapping=0\n")


SERVER_PARAMETERS = ("""
[1200]
ParameterName=SDO server parameter
ObjectType=0x9
SubNumber=3

[1200sub0]
ParameterName=Highest sub-index supported
ObjectType=0x7
DataType=0x0005
AccessType=ro
DefaultValue=2
PDOMapping=0
""" + _cob_id(1, "COB-ID client to server", 0x600)
                     + _cob_id(2, "COB-ID server to client", 0x580))


def _dcf(tmp_path: Path) -> Path:
    """cli_device.eds with OreSat's 0x1200: both COB-IDs 0x80000000."""
    text = EDS.read_text()
    text = text.replace("[OptionalObjects]\nSupportedObjects=5\n",
                        "[OptionalObjects]\nSupportedObjects=6\n6=0x1200\n")
    path = tmp_path / "battery.dcf"
    path.write_text(text + SERVER_PARAMETERS)
    return path


def test_device_from_invalid_server_cob_ids_answers_sdo(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    dcf = _dcf(tmp_path)
    bus = SimBus()
    master = Master(bus, node_id=1)
    device = Device(dcf, 5, bus)
    master.start()
    with caplog.at_level(logging.WARNING, logger="canola.node"):
        device.start()
    bus.run_for(1000)
    sdo = master.sdo(5)
    assert sdo.read(0x1200, 1, "u32") == 0x605
    assert sdo.read(0x1200, 2, "u32") == 0x585
    assert sdo.upload(0x1018, 1) == (0xCA0).to_bytes(4, "little")
    assert any(line.split()[-1].startswith("585#") for line in bus.trace)
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert warnings == [
        f"device 5: {dcf}: [1200] sub1/sub2 are not 0x605/0x585, the COB-IDs CiA 301 fixes "
        "for the default SDO server: served on those regardless"]


def test_device_with_fixed_cob_ids_says_nothing(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    dcf = _dcf(tmp_path)
    dcf.write_text(dcf.read_text().replace("ParameterValue=0x80000000\n", ""))
    bus = SimBus()
    with caplog.at_level(logging.WARNING, logger="canola.node"):
        Device(dcf, 5, bus).start()
    bus.run_for(1000)
    assert [r for r in caplog.records if r.levelno >= logging.WARNING] == []
