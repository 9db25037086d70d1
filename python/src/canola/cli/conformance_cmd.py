# SPDX-License-Identifier: Apache-2.0
"""``canola conformance``: the CiA 301 test suite (canola.conformance) against a node."""

from __future__ import annotations

import argparse
import os
import sys

from canola.cli.common import (
    CliError,
    Parser,
    UsageError,
    add_bus_options,
    bus_from_args,
    int_in_range,
    node_id,
)
from canola.conformance.options import Options
from canola.conformance.registry import GROUPS
from canola.errors import Error
from canola.files import FileError, write_file
from canola.formats import eds


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not 0.05 <= value <= 60:
        raise argparse.ArgumentTypeError(f"bad time {text!r}: 0.05..60 s")
    return value


def _percent(text: str) -> int:
    return int_in_range(text, 1, 100, "tolerance", "%")


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    p = subs.add_parser(
        "conformance", help="CiA 301 conformance checks against a node and its EDS",
        description="Check a CANopen node against CiA 301 and its own EDS: the dictionary, "
                    "SDO, NMT and error control, PDO, SYNC, EMCY, TIME. Non-destructive: "
                    "values are written back, nothing is saved, the NMT state is restored "
                    "(reset node and reset communication are sent). Exit code 0 when no "
                    "check fails.",
        epilog=f"Groups: {', '.join(GROUPS)}. --list shows every check and its clause.")
    p.add_argument("--node-id", type=node_id, metavar="N", help="the node to check (1..127)")
    p.add_argument("--eds", metavar="FILE", help="the node's EDS (or DCF)")
    add_bus_options(p)
    p.add_argument("--only", nargs="+", action="extend", metavar="GROUP",
                   help="run only these groups or checks (e.g. --only sdo pdo.remap)")
    p.add_argument("--list", action="store_true", help="list the checks and exit")
    p.add_argument("--destructive", action="store_true",
                   help="also run the checks that save and restore stored parameters "
                        "(0x1010/0x1011): the node's stored values are lost")
    p.add_argument("--markdown", metavar="FILE", help="write the report as Markdown")
    p.add_argument("--junit", metavar="FILE", help="write the report as JUnit XML")
    p.add_argument("--timeout", type=_seconds, default=Options.timeout, metavar="S",
                   help=f"how long an answer may take (default {Options.timeout:g} s)")
    p.add_argument("--tolerance", type=_percent, default=round(Options.tolerance * 100),
                   metavar="PCT", help="how far a measured period may be off (default "
                                       f"{Options.tolerance * 100:g} %%)")
    p.add_argument("--master-id", type=node_id, default=None, metavar="N",
                   help="node-ID of the tester (default 127, or 126 for node 127)")
    p.set_defaults(func=run_command)


def run_command(args: argparse.Namespace) -> int:
    from canola.conformance import (  # noqa: PLC0415 -- the suite loads when it runs
        Interrupted,
        LiveProgress,
        check_list,
        junit,
        markdown,
        run,
        select,
        verdict,
    )

    try:
        checks = select(args.only or ())
    except Error as exc:
        raise UsageError(f"canola conformance: error: {exc}") from None
    if args.list:
        sys.stdout.write(check_list(checks))
        return 0
    missing = [flag for flag, value in (("--node-id", args.node_id), ("--eds", args.eds))
               if value is None]
    if missing:
        raise UsageError(f"canola conformance: error: missing {', '.join(missing)} "
                         "(see canola conformance --help)")
    if not os.path.isfile(args.eds):
        raise CliError(f"cannot read {args.eds}: no such file")
    model = eds.parse(args.eds, node_id=args.node_id)  # a broken EDS: said before the bus
    options = Options(timeout=args.timeout, tolerance=args.tolerance / 100,
                      destructive=args.destructive)
    bus = bus_from_args(args)
    try:
        report = run(bus, args.node_id, model, only=args.only or (), options=options,
                     master_id=args.master_id, progress=LiveProgress(sys.stdout))
    except Interrupted as stop:  # Ctrl-C: the report of what ran, then exit 130
        report = stop.report
    finally:
        bus.shutdown()
    for path, text in ((args.markdown, markdown), (args.junit, junit)):
        if path is not None:
            try:
                write_file(path, text(report))
            except FileError as exc:
                raise CliError(str(exc)) from None
    print(f"node {report.node_id}: {verdict(report)} ({report.totals})")
    if report.interrupted:
        print(report.notes[-1])
        return 130
    return 0 if report.passed else 1
