# SPDX-License-Identifier: Apache-2.0
"""Opening python-can buses from what a user types: ``--iface IFACE`` or ``--bus URL``,
else the default bus of the environment.

URLs:

- ``socketcand://HOST:PORT/CHANNEL``: a socketcand server (``canola bus serve`` or the real
  daemon); PORT defaults to 29536; the CHANNEL must be given.
- ``socketcan://IFACE``: SocketCAN, the same as ``--iface IFACE``.
- ``virtual://CHANNEL``: python-can's in-process virtual bus (tests).
- ``slcan://HOST:PORT``: an SLCAN (Lawicel) adapter behind a TCP port: canola's firmware
  images in QEMU (``-serial tcp:``), a serial server; ``slcan:///dev/ttyACM0``: one on a
  serial device. python-can's ``slcan`` interface (pyserial). One client at a time: join it
  to the hub with ``canola bus bridge`` to share it.

Without ``--iface``/``--bus`` the bus is the default one (:func:`default_bus`): the URL in
the environment variable ``CANOLA_BUS``, else python-can's own configuration (its
variables ``CAN_INTERFACE``, ``CAN_CHANNEL``, ``CAN_CONFIG`` and its configuration files
``~/can.conf``, ``/etc/can.conf``, ``~/.can``, ``~/.canrc``, as ``can.util.load_config``
reads them).

A socketcand server that asks for a token (``canola bus serve --token``) gets the one in
the environment variable ``CANOLA_TOKEN`` (:mod:`canola.access`).

Failures are :class:`BusError` with a one-line message; nothing waits longer than
``timeout`` seconds for a server that does not answer.
"""

from __future__ import annotations

import os
import select
import socket
import urllib.parse
from typing import Any

import can

from canola.access import token_from
from canola.bus.socketcand_bus import SocketcandBus
from canola.errors import Error

__all__ = ["BUS_ENV", "BusError", "NoBusError", "connection_lost", "default_bus", "open_bus",
           "parse_bus_url"]

#: The environment variable that names the default bus by URL.
BUS_ENV = "CANOLA_BUS"

DEFAULT_SOCKETCAND_PORT = 29536


class BusError(Error):
    """A bus that cannot be opened (one-line message)."""


class NoBusError(BusError):
    """No bus named: no ``--iface``/``--bus``, no ``CANOLA_BUS``, no python-can
    configuration."""


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
        channel = parts.path.strip("/")
        if not channel:
            raise BusError(f"no channel in {url!r}: socketcand://HOST:PORT/CHANNEL")
        if "/" in channel or len(channel) > 16:
            raise BusError(f"bad channel {channel!r} in {url!r}")
        return {"interface": "socketcand", "host": host, "port": port, "channel": channel}
    if scheme == "slcan":
        if parts.netloc:
            try:
                tcp_port = parts.port
            except ValueError as exc:
                raise BusError(f"bad port in {url!r}") from exc
            if tcp_port is None or not parts.hostname:
                raise BusError(f"no host and port in {url!r}: slcan://HOST:PORT")
            channel = f"socket://{parts.hostname}:{tcp_port}"
        elif parts.path:
            channel = parts.path
        else:
            raise BusError(f"no device in {url!r}: slcan://HOST:PORT or slcan:///dev/DEVICE")
        return {"interface": "slcan", "channel": channel, "sleep_after_open": 0}
    if scheme in ("socketcan", "virtual"):
        channel = (parts.netloc + parts.path).strip("/")
        if not channel:
            raise BusError(f"no channel in {url!r}")
        return {"interface": scheme, "channel": channel}
    raise BusError(f"unknown bus URL {url!r}: use socketcand://HOST:PORT/CHANNEL, "
                   "socketcan://IFACE, slcan://HOST:PORT or virtual://CHANNEL")


def default_bus() -> tuple[dict[str, object], str]:
    """The default bus: python-can keyword arguments and where they came from (for
    messages). ``CANOLA_BUS`` first, then python-can's configuration. Raises BusError when
    neither names a bus, or names one without a channel."""
    url = os.environ.get(BUS_ENV, "").strip()
    if url:
        try:
            return parse_bus_url(url), f"{BUS_ENV}={url}"
        except BusError as exc:
            raise BusError(f"{BUS_ENV}: {exc}") from None
    try:
        config = dict(can.util.load_config())
    except can.CanInterfaceNotImplementedError as exc:
        if '"None"' not in str(exc):  # python-can calls no interface at all unknown too
            raise BusError(f"python-can's configuration: {_reason(exc)}") from None
        config = {}
    except (ValueError, TypeError) as exc:  # CAN_CONFIG not JSON, a bad port, ...
        raise BusError(f"python-can's configuration: {_reason(exc)}") from None
    interface = config.get("interface")
    if not interface:
        raise NoBusError(f"no bus: give --iface IFACE or --bus URL, or set {BUS_ENV}=URL "
                       "(e.g. socketcand://127.0.0.1:29536/can0) or python-can's "
                       "CAN_INTERFACE and CAN_CHANNEL")
    if config.get("channel") in (None, ""):
        raise BusError(f"python-can's configuration names interface {interface!r} "
                       "but no channel (CAN_CHANNEL)")
    return ({key: value for key, value in config.items() if value is not None},
            f"python-can's configuration ({interface} {config['channel']})")


def open_bus(*, iface: str | None = None, url: str | None = None,
             timeout: float = 3.0) -> can.BusABC:
    """Open the bus named by ``iface`` (SocketCAN) or ``url``, else the
    :func:`default_bus`. Raises BusError."""
    if iface is not None and url is not None:
        raise BusError("name one bus: --iface IFACE or --bus URL")
    if iface is not None:
        config: dict[str, Any] = {"interface": "socketcan", "channel": iface}
        where = iface
    elif url is not None:
        config, where = parse_bus_url(url), url
    else:
        config, where = default_bus()
    if config["interface"] == "socketcand":
        return _open_socketcand(str(config.get("host", "127.0.0.1")),
                                int(str(config.get("port", DEFAULT_SOCKETCAND_PORT))),
                                str(config["channel"]), timeout)
    try:
        return can.Bus(**config)
    except (OSError, can.CanError, ValueError, TypeError, ImportError) as exc:
        raise BusError(f"cannot open {where}: {_reason(exc)}") from exc


def _reason(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


def _open_socketcand(host: str, port: int, channel: str, timeout: float) -> can.BusABC:
    where = f"socketcand://{host}:{port}/{channel}"
    try:
        token = token_from(None)
    except ValueError as exc:
        raise BusError(str(exc)) from None
    try:
        return SocketcandBus(host, port, channel, timeout, token=token)
    except OSError as exc:
        raise BusError(f"cannot connect to {where}: {_reason(exc)}") from exc
    except can.CanError as exc:
        raise BusError(f"cannot open {where}: {_reason(exc)}") from exc


def connection_lost(bus: can.BusABC) -> bool:
    """True when ``bus`` is a socketcand connection the server has closed.

    Receives just return nothing once the server is gone: canola's client says so
    (:class:`SocketcandBus`); for python-can's, peek at its socket.
    """
    if isinstance(bus, SocketcandBus):
        return bus.lost
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
