"""canola: the Python side of the canola CANopen stack."""

from canola.errors import Diagnostic, EdsError, Error, SdoAbort

__version__ = "0.1.0"

__all__ = ["Diagnostic", "EdsError", "Error", "SdoAbort", "__version__"]
