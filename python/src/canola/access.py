# SPDX-License-Identifier: Apache-2.0
"""Who may connect to canola's servers (the socketcand hub, the CiA 309-3 gateway).

The rule (docs/security.md): a server listens on loopback unless told otherwise, and it
listens on any other address only with a token, which every client sends before anything
else (the hub: ``< auth TOKEN >`` after ``< hi >``; the gateway: the line
``[seq] auth TOKEN``). On loopback the token is optional: without one, everyone on this
machine may connect, as before; with one, every client must prove it there too.

The token comes from an option (``--token``) or the environment variable
:data:`TOKEN_ENV`; clients (canola's socketcand client, canola-node) read the same
variable. It is a shared secret, not encryption: the token and all traffic cross the
network in clear text, so across a network one does not trust, the connection goes
through an SSH tunnel, a VPN or TLS.
"""

from __future__ import annotations

import hmac
import ipaddress
import os
import re
import socket

__all__ = ["TOKEN_ENV", "exposed_addresses", "same_token", "token_from", "unguarded"]

#: The environment variable that holds the token, for servers and clients alike.
TOKEN_ENV = "CANOLA_TOKEN"

#: 16..64 characters that need no quoting in either protocol (base64, hex, URL-safe).
_TOKEN = re.compile(r"[A-Za-z0-9._~+/=-]{16,64}")


def check_token(token: str, where: str = "the token") -> str:
    """``token`` when it is one (16..64 of ``A-Z a-z 0-9 . _ ~ + / = -``); ValueError with
    a one-line reason otherwise."""
    if not _TOKEN.fullmatch(token):
        raise ValueError(f"{where} must be 16..64 characters of A-Z a-z 0-9 . _ ~ + / = - "
                         "(e.g. python3 -c 'import secrets; print(secrets.token_urlsafe(24))')")
    return token


def token_from(option: str | None) -> str | None:
    """The token of an option, else of :data:`TOKEN_ENV`, else None (an empty one is
    none). ValueError for one that is not a token."""
    if option:
        return check_token(option, "--token")
    env = os.environ.get(TOKEN_ENV, "").strip()
    return check_token(env, TOKEN_ENV) if env else None


def same_token(given: str, token: str) -> bool:
    """Whether ``given`` is ``token`` (in time that does not depend on where they differ)."""
    return hmac.compare_digest(given.encode("utf-8", "replace"), token.encode("utf-8"))


def exposed_addresses(host: str, port: int = 0) -> list[str]:
    """The addresses a server listening on ``host`` would take that are not loopback:
    ``0.0.0.0`` and ``::`` (every address), a LAN address, a name that resolves to one.
    A name that does not resolve gives [] (the listen itself then fails). ``host`` must
    not be empty (that is every address too: ValueError)."""
    if not host:
        raise ValueError("an empty host means every address: give one (127.0.0.1: this "
                         "machine only)")
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM,
                                   flags=socket.AI_PASSIVE)
    except (OSError, UnicodeError):
        return []
    exposed: list[str] = []
    for *_, sockaddr in infos:
        address = str(sockaddr[0])
        try:
            loopback = ipaddress.ip_address(address.split("%", 1)[0]).is_loopback
        except ValueError:
            loopback = False
        if not loopback and address not in exposed:
            exposed.append(address)
    return exposed


def unguarded(host: str, token: str | None, option: str = "--host") -> str | None:
    """Why listening on ``host`` without ``token`` is refused (one line), or None when it
    is allowed: loopback, or a token set."""
    if token is not None:
        return None
    exposed = exposed_addresses(host)
    if not exposed:
        return None
    return (f"{option} {host} listens on {', '.join(exposed)}, which is not loopback: "
            f"set a token (--token or {TOKEN_ENV}) that every client must send first, or "
            "listen on 127.0.0.1 and reach it through an SSH tunnel (docs/security.md)")
