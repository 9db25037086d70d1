# SPDX-License-Identifier: Apache-2.0
"""canola: the Python side of the canola CANopen stack."""

import importlib
import re
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any

from canola.errors import Diagnostic, EdsError, Error, SdoAbort

if TYPE_CHECKING:
    from canola.device import Device
    from canola.master import Master, SdoTimeout



def _version() -> str:
    """The installed package's version (include/canola/version.h's, read when it was built);
    run from a checkout without installing (the C build runs odgen so), the header's."""
    try:
        return metadata.version("canola")
    except metadata.PackageNotFoundError:
        header = Path(__file__).resolve().parents[3] / "include" / "canola" / "version.h"
        try:
            found = re.search(r'^#define CANOLA_VERSION "([^"]+)"',
                              header.read_text(encoding="utf-8"), re.M)
        except OSError:
            found = None
        return found.group(1) if found else "0+unknown"


#: include/canola/version.h's version.
__version__ = _version()

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
