# SPDX-License-Identifier: Apache-2.0
"""Where the gateway listens: ``tcp:HOST:PORT``, ``tcp:PORT`` (loopback), ``unix:PATH`` or
``stdio``."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["DEFAULT_LISTEN", "Listen", "parse_listen"]

DEFAULT_LISTEN = "tcp:127.0.0.1:6000"


@dataclass(frozen=True)
class Listen:
    """Where to listen: ``kind`` is "tcp" (host, port), "unix" (path) or "stdio"."""

    kind: str
    host: str = ""
    port: int = 0
    path: str = ""

    def __str__(self) -> str:
        if self.kind == "tcp":
            host = f"[{self.host}]" if ":" in self.host else self.host
            return f"tcp:{host}:{self.port}"
        return f"unix:{self.path}" if self.kind == "unix" else "stdio"


def parse_listen(text: str) -> Listen:
    """``tcp:HOST:PORT``, ``tcp:PORT`` (loopback), ``unix:PATH`` or ``stdio``."""
    if text == "stdio":
        return Listen("stdio")
    kind, _, rest = text.partition(":")
    if kind == "unix" and rest:
        return Listen("unix", path=rest)
    if kind == "tcp" and rest:
        host, _, port = rest.rpartition(":")
        host = host.strip("[]") or "127.0.0.1"
        if port.isdigit() and 0 <= int(port) <= 65535:
            return Listen("tcp", host=host, port=int(port))
    raise ValueError(f"cannot listen on {text!r} (tcp:HOST:PORT, unix:PATH or stdio)")
