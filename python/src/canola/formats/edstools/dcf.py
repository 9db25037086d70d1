# SPDX-License-Identifier: Apache-2.0
"""A DCF from an EDS (``canola eds dcf``): the node-ID in [DeviceComissioning] and the
values given (ParameterValue), each checked against its entry (it exists and may be
written, the value is of its data type and within its LowLimit/HighLimit), so that the
CiA 302-2 manager (``canola boot``) can download every one of them.

    >>> od = eds.parse(Path("drive.eds"), node_id=5)
    >>> text = eds.write(make_dcf(od, 5, {(0x1017, 0): "1000"}), dcf=True)
"""

from __future__ import annotations

import copy
from collections.abc import Mapping

from canola.errors import Error
from canola.formats import eds
from canola.formats.concise import wire
from canola.formats.datatypes import (
    DATA_TYPES,
    INTEGER_TYPES,
    REAL_TYPES,
    Value,
    fit_signed,
    parse_value,
)

__all__ = ["DcfValueError", "make_dcf", "parse_setting"]


class DcfValueError(Error):
    """A value that cannot go into the DCF; the message names the entry and says why."""


def parse_setting(text: str) -> tuple[int, int, str]:
    """``INDEX[:SUB]=VALUE`` (index hex with or without 0x, sub-index decimal or 0x-hex,
    default 0) as (index, sub-index, value text)."""
    address, sep, value = text.partition("=")
    index_text, _, sub_text = address.strip().partition(":")
    try:
        index = int(index_text.removeprefix("0x").removeprefix("0X"), 16)
        sub = int(sub_text, 0) if sub_text else 0
    except ValueError:
        index = sub = -1
    if not sep or not (0 <= index <= 0xFFFF and 0 <= sub <= 0xFF):
        raise DcfValueError(f"bad setting {text!r}: INDEX:SUB=VALUE, e.g. 0x1017:0=1000")
    return index, sub, value.strip()


def make_dcf(od: eds.ObjectDictionary, node_id: int,
             settings: Mapping[tuple[int, int], str], *, node_name: str | None = None,
             baudrate: int | None = None) -> eds.ObjectDictionary:
    """A copy of ``od`` (an EDS parsed with ``node_id``) as the DCF of node ``node_id``:
    [DeviceComissioning] NodeID (NodeName, Baudrate in kbit/s when given) and a
    ParameterValue for each ``(index, sub): text`` of ``settings``. Raises
    :class:`DcfValueError` for the first value that does not fit its entry."""
    dcf = copy.deepcopy(od)
    dcf.node_id = node_id
    commissioning = {"NodeID": str(node_id)}
    if node_name is not None:
        commissioning["NodeName"] = node_name
    if baudrate is not None:
        commissioning["Baudrate"] = str(baudrate)
    dcf.device_commissioning = commissioning
    for (index, sub), text in settings.items():
        var = _writable_entry(dcf, index, sub)
        var.value = _checked_value(var, text, node_id)
        var.parameter_value = text
    return dcf


def _where(var: eds.Variable) -> str:
    return f"0x{var.index:04X}:{var.subindex:02X} ({var.name})"


def _writable_entry(od: eds.ObjectDictionary, index: int, sub: int) -> eds.Variable:
    obj = od.objects.get(index)
    var = None if obj is None else obj.subs.get(sub)
    if var is None:
        raise DcfValueError(f"0x{index:04X}:{sub:02X} is not in {od.file}")
    if var.access_type in ("ro", "const"):
        raise DcfValueError(f"{_where(var)} is {var.access_type}: a configuration cannot "
                            "write it")
    return var


def _checked_value(var: eds.Variable, text: str, node_id: int) -> Value:
    """The value of ``text`` for ``var``; DcfValueError when it does not fit."""
    code = var.data_type
    info = DATA_TYPES.get(code or 0)
    if info is None:
        raise DcfValueError(f"{_where(var)} has no known data type")
    try:
        wire(code, text, node_id)
    except (ValueError, UnicodeEncodeError) as exc:
        raise DcfValueError(f"{_where(var)}: {exc}") from None
    if code not in INTEGER_TYPES and code not in REAL_TYPES:
        return text
    value = parse_value(text, code, node_id)
    if isinstance(value, int) and code in INTEGER_TYPES:
        value = fit_signed(value, text, code)
    assert isinstance(value, int | float)
    low, high = var.low, var.high
    if (isinstance(low, int | float) and value < low) or (
            isinstance(high, int | float) and value > high):
        raise DcfValueError(f"{_where(var)}: {text} is outside LowLimit..HighLimit "
                            f"({var.low_limit}..{var.high_limit})")
    return value
