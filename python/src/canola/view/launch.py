# SPDX-License-Identifier: Apache-2.0
"""Starting ``canola view`` (the command, and ``canola demo --view``): the address to listen
on, the write token, the model, reader and server, and the lines that tell the user where
the page is and what it may do."""

from __future__ import annotations

import secrets
import socket
import sys
from collections.abc import Callable
from typing import TextIO

import can

from canola.decode import Decoder
from canola.errors import Error
from canola.master import Master
from canola.nodedicts import NodeDictionaries
from canola.view.actions import BusActions
from canola.view.model import BusModel
from canola.view.runner import View
from canola.view.server import is_loopback

__all__ = ["DEFAULT_LISTEN", "parse_listen", "start_view"]

DEFAULT_LISTEN = "127.0.0.1:8080"


#: Hosts that mean "every address of this machine": no URL can name them.
WILDCARDS = ("0.0.0.0", "::")


def page_url(host: str, port: int) -> str:
    """The page's URL on ``host`` (an IPv6 address in brackets)."""
    return f"http://[{host}]:{port}/" if ":" in host else f"http://{host}:{port}/"


def parse_listen(text: str) -> tuple[str, int]:
    """``HOST:PORT`` (``[::1]:8080`` for IPv6; port 0: any free one). Raises Error."""
    host, colon, port = text.strip().rpartition(":")
    host = host.strip("[]")
    if not colon or not host or not port.isdigit() or not 0 <= int(port) <= 65535:
        raise Error(f"bad --listen {text!r}: HOST:PORT, e.g. {DEFAULT_LISTEN}")
    return host, int(port)


def start_view(*, open_bus: Callable[[], can.BusABC], open_master: Callable[[], Master],
               dictionaries: NodeDictionaries, decoder: Decoder | None = None,
               listen: str = DEFAULT_LISTEN, allow_write: bool = False,
               bitrate: int = 500_000, out: TextIO = sys.stdout,
               where: str = "") -> View:
    """Start reading the bus and serving the page; prints its URL (and the token, the
    warnings) to ``out`` / stderr. Raises Error when the address cannot be bound."""
    host, port = parse_listen(listen)
    local = is_loopback(host)
    token = secrets.token_urlsafe(16)
    model = BusModel(decoder or Decoder(dictionaries), dictionaries, bitrate=bitrate)
    view = View(model, BusActions(open_master, dictionaries), open_bus, host=host, port=port,
                allow_write=allow_write, token=token, loopback_only=local)
    port = view.start()
    # url: the page for other machines (and the token); local_url: the one printed first
    local_url = url = page_url(host, port)
    if host in WILDCARDS:  # no URL names it: loopback here, the machine's name elsewhere
        local_url = page_url("::1" if ":" in host else "127.0.0.1", port)
        url = page_url(socket.gethostname(), port)
        where = f"on every address: {url}" + (f", {where}" if where else "")
    if not local:
        print(f"canola view: warning: listening on {host}:{port}, not on a loopback address: "
              "every machine that reaches it sees the bus", file=sys.stderr)
    print(f"canola view: {local_url}" + (f" ({where})" if where else ""), file=out)
    if not allow_write:
        print("canola view: writes and NMT commands are off (--allow-write turns them on)",
              file=out)
    elif local:
        print("canola view: writes and NMT commands on, from this machine", file=out)
    else:
        print(f"canola view: writes and NMT commands on: from this machine, or from the page "
              f"opened as {url}#token={token}", file=out)
    out.flush()
    return view
