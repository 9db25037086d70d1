# SPDX-License-Identifier: Apache-2.0
"""Helpers of the issue 7 tests: devices of managed_device.eds with an identity of their
own, and DCF files made from that EDS."""

from __future__ import annotations

from pathlib import Path

from canola.formats import eds

DATA = Path(__file__).parent / "data"
EDS = DATA / "managed_device.eds"
VENDOR = 0xCA0
PRODUCT = 0x302
REVISION = 0x00010000
DEVICE_TYPE = 0x00020192


def model(*, vendor: int = VENDOR, serial: int = 1, product: int = PRODUCT) -> eds.ObjectDictionary:
    """The device's dictionary with this identity (0x1018 defaults)."""
    m = eds.parse(EDS)
    ident = m.objects[0x1018].subs
    ident[1].default_value = f"0x{vendor:X}"
    ident[2].default_value = f"0x{product:X}"
    ident[4].default_value = f"0x{serial:X}"
    return m


def write_dcf(path: Path, node_id: int, values: dict[tuple[int, int], str], *,
              serial: int | None = None) -> Path:
    """A DCF of the device for ``node_id`` with these ParameterValues (texts)."""
    m = eds.parse(EDS)
    m.device_commissioning = {"NodeID": str(node_id), "NodeName": f"node{node_id}",
                              "Baudrate": "500"}
    for (index, sub), text in values.items():
        m.objects[index].subs[sub].parameter_value = text
    if serial is not None:
        m.objects[0x1018].subs[4].parameter_value = f"0x{serial:X}"
    path.write_text(eds.write(m, dcf=True), encoding="latin-1")
    return path
