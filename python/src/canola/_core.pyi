# Stub of the cffi-generated extension canola._core (built from _build_core.py).
from typing import Any

ffi: Any
lib: Any
