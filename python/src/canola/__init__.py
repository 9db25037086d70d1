# SPDX-License-Identifier: Apache-2.0
"""canola: the Python side of the canola CANopen stack."""

import importlib
from importlib import metadata
from typing import TYPE_CHECKING, Any

from canola.errors import Diagnostic, EdsError, Error, SdoAbort

if TYPE_CHECKING:
    from canola.device import Device
    from canola.master import Master, SdoTimeout

#: The installed package's version: include/canola/version.h's, read when it was built.
__version__ = metadata.version("canola")

__all__ = ["Device", "Diagnostic", "EdsError", "Error", "Master", "SdoAbort", "SdoTimeout",
           "__version__"]


def __getattr__(name: str) -> Any:
    # Device and Master load the C core (cffi) on first use, not on `import canola`.
    module = {"Device": "canola.device", "Master": "canola.master",
              "SdoTimeout": "canola.master"}.get(name)
    if module is not None:
        return getattr(importlib.import_module(module), name)
    if name in ("eds", "values", "odgen"):  # canola.eds etc. as the docs use them
        return importlib.import_module(f"canola.formats.{name}")
    raise AttributeError(f"module 'canola' has no attribute {name!r}")
