# SPDX-License-Identifier: Apache-2.0
"""``canola gateway``: the CiA 309-3 ASCII gateway (see :mod:`canola.gateway.cli`)."""

from __future__ import annotations

import argparse

from canola.cli.common import Parser
from canola.gateway import cli as gateway_cli


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    p = subs.add_parser(
        "gateway", help="CiA 309-3 ASCII gateway on TCP, a Unix socket or stdio",
        description="A master node that takes CiA 309-3 text commands (cocomm's syntax) "
                    "from several clients at once: SDO, NMT, PDO, heartbeat and EMCY "
                    "events. Listens on the loopback address unless told otherwise.")
    gateway_cli.add_arguments(p)
    p.set_defaults(func=gateway_cli.run)
