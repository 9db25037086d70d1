# SPDX-License-Identifier: Apache-2.0
"""The ``canola`` command: one sub-command group per module of this package.

    canola odgen DEVICE.eds -o DIR            C object dictionary from an EDS/DCF
    canola eds check|show|dcf|diff            check, show, configure, compare EDS/DCF files
    canola bus serve [--host H] [--port P]    software CAN bus (socketcand hub)
    canola nmt CMD NODE|all                   NMT commands
    canola sdo read|write|upload|download     SDO client
    canola pdo show|map NODE ...              a node's PDOs, read and configured by SDO
    canola sync PERIOD_MS                     produce SYNC
    canola time                               produce TIME
    canola scan                               which node-IDs answer
    canola dump [FILE]                        traffic decoded into CANopen meaning
    canola monitor                            live view of every node
    canola view                               live picture of the network in the browser
    canola device --eds FILE --node-id N      run a canola device
    canola demo                               the demo network (a master, three devices)
    canola gateway --iface IFACE [--listen W] CiA 309-3 ASCII gateway
    canola boot NETWORK.yaml|DCF...           boot a network (CiA 302-2 manager)
    canola flash NODE FILE                    program download (CiA 302-3)
    canola lss scan|set-id|inquire            layer setting services (CiA 305)
    canola conformance --node-id N --eds FILE CiA 301 checks of a node against its EDS

Every bus command takes ``--iface IFACE`` or ``--bus URL``; without them it uses the
default bus: the URL in ``CANOLA_BUS``, else python-can's configuration (``CAN_INTERFACE``,
``CAN_CHANNEL``, ``CAN_CONFIG``, ``~/.canrc``, ...). A bad argument is one line on
stderr and exit code 2; a failure (no answer, SDO abort, bus missing) one line and exit
code 1. Nothing waits without a time limit.
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Callable, Sequence

from canola import __version__
from canola.cli import (
    boot_cmd,
    bus_cmd,
    conformance_cmd,
    demo_cmd,
    device_cmd,
    dump_cmd,
    eds_cmd,
    flash_cmd,
    gateway_cmd,
    lss_cmd,
    monitor_cmd,
    nmt_cmd,
    pdo_cmd,
    scan_cmd,
    sdo_cmd,
    sync_cmd,
    view_cmd,
)
from canola.cli.common import CliError, Parser
from canola.errors import Error
from canola.formats import odgen

__all__ = ["build_parser", "main"]

_GROUPS: tuple[Callable[[argparse._SubParsersAction[Parser]], None], ...] = (
    bus_cmd.register, nmt_cmd.register, sdo_cmd.register, scan_cmd.register,
    dump_cmd.register, monitor_cmd.register, device_cmd.register, gateway_cmd.register,
    demo_cmd.register, boot_cmd.register, flash_cmd.register, lss_cmd.register,
    pdo_cmd.register, sync_cmd.register, eds_cmd.register, conformance_cmd.register,
    view_cmd.register,
)


def build_parser() -> Parser:
    parser = Parser(prog="canola", description="canola: CANopen tools.",
                    epilog="canola COMMAND --help tells more.")
    parser.add_argument("-v", "--verbose", action="count", default=0,
                        help="log more (repeat for debug)")
    parser.add_argument("--version", action="version", version=f"canola {__version__}")
    subs = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    subs.required = True
    subs.add_parser("odgen", help="C object dictionary from an EDS/DCF (canola odgen --help)",
                    add_help=False)
    for register in _GROUPS:
        register(subs)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args_list = list(sys.argv[1:] if argv is None else argv)
    if args_list and args_list[0] == "odgen":
        try:
            return odgen.main(args_list[1:], prog="canola odgen")
        except SystemExit as exc:
            return exc.code if isinstance(exc.code, int) else 1
    parser = build_parser()
    try:
        args = parser.parse_args(args_list)
        level = logging.WARNING - 10 * min(args.verbose, 2)
        logging.basicConfig(level=level, format="%(name)s: %(message)s")
        code: int = args.func(args)
        return code
    except SystemExit as exc:  # --help
        return exc.code if isinstance(exc.code, int) else 0
    except CliError as exc:
        print(_one_line(str(exc) if exc.code == 2 else f"canola: {exc}"), file=sys.stderr)
        return exc.code
    except Error as exc:
        print(_one_line(f"canola: {exc}"), file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        return 1


def _one_line(text: str) -> str:
    return " ".join(text.split())
