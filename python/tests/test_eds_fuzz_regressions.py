# SPDX-License-Identifier: Apache-2.0
"""Inputs the EDS fuzzer (fuzz/fuzz_eds.py) found: each parses, or fails with EdsError only,
and what parses survives write() and parse() again."""

from __future__ import annotations

from canola.formats import eds

NEGATIVE_DATA_TYPE = """[FileInfo]
FileName=x.eds

[DeviceInfo]
VendorNumber=1
ProductNumber=2

[OptionalObjects]
SupportedObjects=1
1=0x2000

[2000]
ParameterName=odd
ObjectType=0x7
DataType=0x00-7
AccessType=rw
DefaultValue=0
"""


def test_negative_data_type_is_written_back_readably() -> None:
    od = eds.parse(NEGATIVE_DATA_TYPE)
    var = od.objects[0x2000].subs[0]
    assert var.data_type == -7
    text = eds.write(od)
    assert "DataType=-0x0007" in text
    again = eds.parse(text)
    assert again.objects[0x2000].subs[0].data_type == -7
