"""Opening python-can buses from what a user types: ``--iface IFACE`` or ``--bus URL``.

URLs:

- ``socketcand://HOST:PORT/CHANNEL``: a socketcand server (``canola bus serve`` or the real
  daemon); PORT defaults to 29536, CHANNEL to ``can0``.
- ``socketcan://IFACE``: SocketCAN, the same as ``--iface IFACE``.
- ``virtual://CHANNEL``: python-can's in-process virtual bus (tests).

Failures are :class:`BusError` with a one-line message; nothing waits longer than
``timeout`` seconds for a server that does not answer.
"""

from __future__ import annotations

import logging
import select
import socket
import urllib.parse

import can

from canola.errors import Error

__all__ = ["BusError", "connection_lost", "open_bus", "parse_bus_url"]

DEFAULT_SOCKETCAND_PORT = 29536

# python-can's socketcand client warns whenever a TCP read ends inside an element, which is
# ordinary on a busy stream: keep its real errors only.
logging.getLogger("can.interfaces.socketcand.socketcand").setLevel(logging.ERROR)


class BusError(Error):
    """A bus that cannot be opened (one-line message)."""


def parse_bus_url(url: str) -> dict[str, object]:
    """python-can keyword arguments for ``url`` (see the module text). Raises BusError."""
    parts = urllib.parse.urlsplit(url)
    scheme = parts.scheme.lower()
    if scheme == "socketcand":
        try:
            port = parts.port or DEFAULT_SOCKETCAND_PORT
        except ValueError as exc:
            raise BusError(f"bad port in {url!r}") from exc
        host = parts.hostname or "127.0.0.1"
        channel = parts.path.strip("/") or "can0"
        if "/" in channel or len(channel) > 16:
            raise BusError(f"bad channel {channel!r} in {url!r}")
        return {"interface": "socketcand", "host": host, "port": port, "channel": channel}
    if scheme in ("socketcan", "virtual"):
        channel = (parts.netloc + parts.path).strip("/")
        if not channel:
            raise BusError(f"no channel in {url!r}")
        return {"interface": scheme, "channel": channel}
    raise BusError(f"unknown bus URL {url!r}: use socketcand://HOST:PORT/CHANNEL, "
                   "socketcan://IFACE or virtual://CHANNEL")


def open_bus(*, iface: str | None = None, url: str | None = None,
             timeout: float = 3.0) -> can.BusABC:
    """Open the bus named by ``iface`` (SocketCAN) or ``url``. Raises BusError."""
    if (iface is None) == (url is None):
        raise BusError("name a bus: --iface IFACE or --bus URL")
    config = ({"interface": "socketcan", "channel": iface} if iface is not None
              else parse_bus_url(url or ""))
    if config["interface"] == "socketcand":
        return _open_socketcand(str(config["host"]), int(str(config["port"])),
                                str(config["channel"]), timeout)
    try:
        return can.Bus(**config)
    except (OSError, can.CanError, ValueError) as exc:
        where = iface if iface is not None else url
        raise BusError(f"cannot open {where}: {_reason(exc)}") from exc


def _reason(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


def _open_socketcand(host: str, port: int, channel: str, timeout: float) -> can.BusABC:
    where = f"socketcand://{host}:{port}/{channel}"
    # python-can retries a refused connection for 10 s and waits for the greeting without a
    # limit: check the server first, and bound every socket operation of the handshake.
    try:
        with socket.create_connection((host, port), timeout=timeout):
            pass
    except OSError as exc:
        raise BusError(f"cannot connect to {where}: {_reason(exc)}") from exc
    previous = socket.getdefaulttimeout()
    socket.setdefaulttimeout(timeout)
    try:
        return can.Bus(interface="socketcand", host=host, port=port, channel=channel)
    except (OSError, can.CanError, TimeoutError) as exc:
        raise BusError(f"cannot open {where}: {_reason(exc)}") from exc
    finally:
        socket.setdefaulttimeout(previous)


def connection_lost(bus: can.BusABC) -> bool:
    """True when ``bus`` is a socketcand connection the server has closed.

    python-can's socketcand client does not report a closed connection (its receive just
    returns nothing, at once, forever): peek at its socket.
    """
    sock = getattr(bus, "_SocketCanDaemonBus__socket", None)
    if not isinstance(sock, socket.socket):
        return False
    try:
        readable, _, _ = select.select([sock], [], [], 0)
        return bool(readable) and sock.recv(1, socket.MSG_PEEK) == b""
    except (BlockingIOError, InterruptedError, TimeoutError):
        return False
    except (OSError, ValueError):  # reset, or closed here
        return True
