# SPDX-License-Identifier: Apache-2.0
"""CiA 309-3 gateway error codes (the ``ERROR:<code>`` replies that are not SDO aborts)."""

from __future__ import annotations

from enum import IntEnum

__all__ = ["GatewayError", "GatewayFailure"]


class GatewayError(IntEnum):
    """Internal error codes of CiA 309-3 (100 and up)."""

    REQUEST_NOT_SUPPORTED = 100
    SYNTAX = 101
    INTERNAL_STATE = 102
    TIMEOUT = 103
    NO_DEFAULT_NET = 104
    NO_DEFAULT_NODE = 105
    UNSUPPORTED_NET = 106
    UNSUPPORTED_NODE = 107
    LOST_GUARDING_MESSAGE = 200
    LOST_CONNECTION = 201
    HEARTBEAT_STARTED = 202
    HEARTBEAT_LOST = 203
    WRONG_NMT_STATE = 204
    BOOT_UP = 205
    ERROR_PASSIVE = 300
    BUS_OFF = 301
    CAN_BUFFER_OVERFLOW = 303
    CAN_INIT = 304
    CAN_ACTIVE = 305
    PDO_ALREADY_USED = 400
    PDO_LENGTH_EXCEEDED = 401
    LSS_MANUFACTURER = 501
    LSS_NODE_ID_NOT_SUPPORTED = 502
    LSS_BIT_RATE_NOT_SUPPORTED = 503
    LSS_STORE_FAILED = 504
    LSS_MEDIA_ERROR = 505
    OUT_OF_MEMORY = 600


class GatewayFailure(Exception):  # noqa: N818 -- a reply, not a programming error
    """A request that ends in ``ERROR:<code>``; ``detail`` says why (for logs only);
    ``note``, when given, goes into the reply too, as a comment (``ERROR:204 #...``, as
    CANopenNode's gateway describes its errors)."""

    def __init__(self, code: GatewayError, detail: str = "", *, note: str = "") -> None:
        self.code = code
        self.detail = detail
        self.note = note
        super().__init__(f"gateway error {int(code)} ({code.name.lower()}){': ' if detail else ''}"
                         f"{detail}")
