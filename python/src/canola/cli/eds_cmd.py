# SPDX-License-Identifier: Apache-2.0
"""``canola eds``: check, show, make a DCF from, and compare EDS/DCF files (the library
behind it: :mod:`canola.formats.edstools`).

    canola eds check FILE... [--strict]          CiA 306 problems, file:line: [section] key:
    canola eds show FILE [INDEX[-LAST]] [--name TEXT]              the dictionary as a table
    canola eds dcf EDS --node-id N [--set INDEX:SUB=VALUE]... -o FILE         a DCF from it
    canola eds diff A B | canola eds diff A --node N [--bus URL]  what differs (B: a device)
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from canola.cli.common import (
    CliError,
    Parser,
    UsageError,
    add_bus_options,
    add_master_options,
    emit_json,
    int_in_range,
    master_from_args,
    node_id,
)
from canola.errors import SdoAbort
from canola.files import FileError, write_file
from canola.formats import eds
from canola.formats.edstools.check import check_file
from canola.formats.edstools.dcf import DcfValueError, make_dcf, parse_setting
from canola.formats.edstools.diff import Difference, diff, diff_live
from canola.formats.edstools.table import format_rows, rows


def _index_range(text: str) -> tuple[int, int]:
    """``INDEX`` or ``FIRST-LAST`` (hex, with or without 0x)."""
    first_text, dash, last_text = text.partition("-")
    try:
        first = int(first_text.removeprefix("0x").removeprefix("0X"), 16)
        last = int(last_text.removeprefix("0x").removeprefix("0X"), 16) if dash else first
    except ValueError:
        first, last = 1, 0
    if not 0 <= first <= last <= 0xFFFF:
        raise argparse.ArgumentTypeError(
            f"bad index {text!r}: INDEX or FIRST-LAST in hex, e.g. 0x1018 or 0x1600-0x17FF")
    return first, last


def _setting(text: str) -> tuple[int, int, str]:
    try:
        return parse_setting(text)
    except DcfValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _baudrate(text: str) -> int:
    return int_in_range(text, 10, 1000, "bit rate", "kbit/s")


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    p = subs.add_parser("eds", help="check, show, make a DCF from, compare EDS/DCF files",
                        description="Work with CiA 306 files (EDS, DCF) without a bus, or "
                                    "compare one with a device's values.")
    eds_subs = p.add_subparsers(dest="eds_command", metavar="SUBCOMMAND", parser_class=Parser)
    eds_subs.required = True

    c = eds_subs.add_parser(
        "check", help="list every deviation from CiA 306 (a linter)",
        description="Print each problem of each file as FILE:LINE: [SECTION] KEY: "
                    "error|warning: MESSAGE. An error is what the parser, canola odgen or "
                    "canola device refuses; a "
                    "warning a deviation it reads past; then a count on stderr. A clean "
                    "file prints nothing. Exit code 0 without errors, 1 with errors.")
    c.add_argument("files", nargs="+", metavar="FILE", help="EDS or DCF files")
    c.add_argument("--strict", action="store_true", help="every warning is an error")
    c.set_defaults(func=run_check)

    s = eds_subs.add_parser("show", help="the dictionary as a table",
                            description="One row per object, and per sub-object: index, "
                                        "sub-index, name, data type, access, default, "
                                        "value (DCF) and PDO-mappable.")
    s.add_argument("file", metavar="FILE", help="EDS or DCF file")
    s.add_argument("indices", nargs="?", type=_index_range, metavar="INDEX[-LAST]",
                   help="only this object, or the objects FIRST-LAST (hex)")
    s.add_argument("--name", metavar="TEXT",
                   help="only entries whose name (or object's name) contains TEXT")
    s.add_argument("--json", action="store_true", help="one JSON object per row")
    s.set_defaults(func=run_show)

    d = eds_subs.add_parser("dcf", help="a DCF from an EDS, a node-ID and values",
                            description="Write the DCF of node --node-id: NodeID in "
                                        "[DeviceComissioning], each --set value as the "
                                        "entry's ParameterValue (checked against its data "
                                        "type, access and limits).")
    d.add_argument("file", metavar="EDS", help="the device's EDS")
    d.add_argument("--node-id", type=node_id, required=True, metavar="N",
                   help="the node-ID of the DCF (1..127)")
    d.add_argument("--set", dest="settings", type=_setting, action="append", default=[],
                   metavar="INDEX:SUB=VALUE", help="a value of the configuration "
                   "(repeatable), e.g. 0x1017:0=1000")
    d.add_argument("--node-name", metavar="NAME", help="NodeName of [DeviceComissioning]")
    d.add_argument("--baudrate", type=_baudrate, metavar="KBIT",
                   help="Baudrate of [DeviceComissioning] (kbit/s)")
    d.add_argument("-o", "--output", required=True, metavar="FILE", help="the DCF (- for "
                   "stdout)")
    d.set_defaults(func=run_dcf)

    f = eds_subs.add_parser("diff", help="what differs between two dictionaries, or a "
                                         "dictionary and a device",
                            description="List the objects and entries only in A or B, and "
                                        "the entries whose name, type, access, PDO mapping, "
                                        "default or value differ. With --node, B is the "
                                        "device: every readable entry of A with a value is "
                                        "read by SDO and compared.")
    f.add_argument("a", metavar="A", help="EDS or DCF")
    f.add_argument("b", nargs="?", metavar="B", help="EDS or DCF (without --node)")
    f.add_argument("--node", type=node_id, metavar="N", help="compare with node N's values")
    add_bus_options(f)
    add_master_options(f)
    f.add_argument("--json", action="store_true", help="one JSON object per difference")
    f.add_argument("--exit-code", action="store_true",
                   help="exit code 1 when there are differences")
    f.set_defaults(func=run_diff)


def run_check(args: argparse.Namespace) -> int:
    errors = warnings = 0
    for path in args.files:
        for finding in check_file(path, strict=args.strict):
            print(finding)
            errors += finding.error
            warnings += not finding.error
    if errors or warnings:  # a clean check says nothing
        files = len(args.files)
        print(f"canola eds check: {files} file{'s' * (files != 1)}, {errors} error"
              f"{'s' * (errors != 1)}, {warnings} warning{'s' * (warnings != 1)}",
              file=sys.stderr)
    return 1 if errors else 0


def _parse(path: str, node: int | None = None) -> eds.ObjectDictionary:
    return eds.parse(Path(path), node_id=node)


def run_show(args: argparse.Namespace) -> int:
    first, last = args.indices or (0, 0xFFFF)
    table = rows(_parse(args.file), first=first, last=last, name=args.name)
    if args.json:
        for row in table:
            emit_json(row.as_dict())
    elif table:
        print(format_rows(table))
    else:
        raise CliError(f"no entry of {args.file} matches")
    return 0


def run_dcf(args: argparse.Namespace) -> int:
    settings = {(index, sub): value for index, sub, value in args.settings}
    try:
        dcf = make_dcf(_parse(args.file, args.node_id), args.node_id, settings,
                       node_name=args.node_name, baudrate=args.baudrate)
    except DcfValueError as exc:
        raise CliError(f"canola eds dcf: error: {exc}", 2) from None
    text = eds.write(dcf, dcf=True)
    if args.output == "-":
        sys.stdout.write(text)
        return 0
    try:
        write_file(args.output, text)
    except FileError as exc:
        raise CliError(str(exc)) from None
    return 0


def run_diff(args: argparse.Namespace) -> int:
    live = args.node is not None
    if live == (args.b is not None):
        raise UsageError("canola eds diff: error: give B, or --node N (see canola eds diff "
                         "--help)")
    if not live and (args.bus is not None or args.iface is not None):
        raise UsageError("canola eds diff: error: --bus/--iface only with --node")
    a = _parse(args.a, args.node)
    differences = _diff_device(a, args) if live else diff(a, _parse(args.b))
    _print_differences(differences, args.json)
    return 1 if args.exit_code and differences else 0


def _diff_device(a: eds.ObjectDictionary, args: argparse.Namespace) -> list[Difference]:
    with master_from_args(args) as master:
        client = master.sdo(args.node)
        try:
            return diff_live(a, client.upload)
        except SdoAbort:  # diff_live lets only the time-out through
            raise CliError(f"no response from node {args.node} (SDO time-out "
                           f"{args.sdo_timeout} ms)") from None


def _print_differences(differences: list[Difference], as_json: bool) -> None:
    for d in differences:
        if as_json:
            emit_json(d.as_dict())
        else:
            print(d)
