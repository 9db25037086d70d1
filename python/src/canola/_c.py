# SPDX-License-Identifier: Apache-2.0
"""The one door to the compiled module ``canola._core`` (cffi; built by ``_build_core.py``
from the core and ``port/python``): ``ffi`` and ``lib``, typed by ``_core.pyi`` so that
``mypy --strict`` checks every call into C, and the core's error codes in words. No other
module imports ``canola._core`` (a test checks)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from canola._core import ffi, lib
from canola.errors import Error

if TYPE_CHECKING:
    from canola._core import CData
else:
    CData = ffi.CData

__all__ = ["CData", "check", "ffi", "lib"]

_ERRORS = {
    int(lib.CO_ERR_ARG): "bad argument",
    int(lib.CO_ERR_BUSY): "busy",
    int(lib.CO_ERR_CONFIG): "inconsistent configuration or object dictionary",
    int(lib.CO_ERR_STATE): "not allowed in the current state",
    int(lib.CO_ERR_NOT_FOUND): "not found",
    int(lib.CO_ERR_FULL): "no room",
    int(lib.CO_ERR_ABORT): "object dictionary access failed",
}


def check(err: int, what: str) -> None:
    """Raise :class:`~canola.errors.Error` naming ``what`` unless ``err`` is CO_OK."""
    if err != lib.CO_OK:
        raise Error(f"{what}: {_ERRORS.get(err, 'error')} ({err})")
