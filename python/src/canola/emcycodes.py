# SPDX-License-Identifier: Apache-2.0
"""Emergency messages in words: CiA 301 error codes (table 21), the error register
(0x1001), and the codes canola's core raises itself.

    >>> emcy_text(0x8150)
    'CAN-ID collision (another node uses this node-ID)'
    >>> emcy_text(0x4210)
    'device temperature'
    >>> register_text(0x11)
    'generic, communication'
    >>> emcy_line(0x8130, 0x11)
    '0x8130 life guard / heartbeat error, error register 0x11 (generic, communication)'
"""

from __future__ import annotations

__all__ = ["emcy_class", "emcy_line", "emcy_text", "register_text"]

#: Error codes of CiA 301 and of canola's core, exact.
_CODES = {
    0x0000: "error reset / no error", 0x1000: "generic error",
    0x2000: "current", 0x2100: "current, device input side", 0x2200: "current inside the device",
    0x2300: "current, device output side",
    0x3000: "voltage", 0x3100: "mains voltage", 0x3200: "voltage inside the device",
    0x3300: "output voltage",
    0x4000: "temperature", 0x4100: "ambient temperature", 0x4200: "device temperature",
    0x5000: "device hardware",
    0x6000: "device software", 0x6100: "internal software", 0x6200: "user software",
    0x6300: "data set",
    0x7000: "additional modules",
    0x8000: "monitoring", 0x8100: "communication",
    0x8110: "CAN overrun (objects lost)", 0x8120: "CAN in error passive mode",
    0x8130: "life guard / heartbeat error", 0x8140: "recovered from bus-off",
    0x8150: "CAN-ID collision (another node uses this node-ID)",
    0x8200: "protocol error", 0x8210: "PDO not processed (length error)",
    0x8220: "PDO length exceeded", 0x8230: "DAM MPDO not processed (no such object)",
    0x8240: "unexpected SYNC data length", 0x8250: "RPDO time-out",
    0x9000: "external error", 0xF000: "additional functions", 0xFF00: "device specific",
    # canola's core (include/canola/storage.h): a stored parameter image refused at reset
    0xFF11: "stored communication parameters refused (defaults in use)",
    0xFF12: "stored application parameters refused (defaults in use)",
}

#: Error register (0x1001) bits, CiA 301 7.5.2.2.
_REGISTER_BITS = ("generic", "current", "voltage", "temperature", "communication",
                  "device profile", "reserved", "manufacturer")


def emcy_class(code: int) -> str:
    """The class of an error code: its first hex digit's group ("temperature")."""
    if code & 0xFF00 == 0xFF00:
        return "device specific"
    return _CODES.get(code & 0xF000, "unknown error code") if code else _CODES[0]


def emcy_text(code: int) -> str:
    """The meaning of an error code: the code itself, else the group of its high byte
    (0x4210: device temperature), else its class (0x4310: temperature)."""
    for key in (code, code & 0xFF00, code & 0xF000):
        if key in _CODES and (key or not code):
            return _CODES[key]
    return emcy_class(code)


def register_text(register: int) -> str:
    """The bits set in an error register, in words ("none" for 0)."""
    bits = [name for bit, name in enumerate(_REGISTER_BITS) if register >> bit & 1]
    return ", ".join(bits) or "none"


def emcy_line(code: int, register: int, manufacturer: bytes = b"") -> str:
    """One EMCY in words: code and meaning, the error register decoded, and the
    manufacturer bytes when any is set."""
    text = (f"0x{code:04X} {emcy_text(code)}, error register 0x{register:02X} "
            f"({register_text(register)})")
    if any(manufacturer):
        text += f", data {manufacturer.hex(' ').upper()}"
    return text
