# SPDX-License-Identifier: Apache-2.0
"""``canola flash NODE FILE``: program download (CiA 302-3) with a progress bar."""

from __future__ import annotations

import argparse
import sys
from typing import TextIO

from canola.cli.common import (
    CliError,
    Parser,
    add_bus_options,
    add_master_options,
    emit_json,
    int_in_range,
    master_from_args,
    node_id,
)
from canola.cli.progress import ProgressLine, bar_text


class ProgressBar(ProgressLine):
    """``[#####     ]  52.0% 53248/102400 B 11.2 kB/s`` on one line of ``stream``, drawn
    at most ten times a second (and at the end)."""

    def __init__(self, total: int, *, enabled: bool, stream: TextIO | None = None) -> None:
        super().__init__(enabled=enabled, stream=stream)
        self.total = total

    def update(self, done: int, total: int) -> None:
        self.done, self.total = done, total
        self._draw(force=done >= total)

    def finish(self) -> None:
        self._end()

    def _text(self, rate: float) -> str:
        return bar_text(self.done, self.total, rate)


def _ident(text: str) -> int:
    try:
        value = int(text, 16)
    except ValueError:
        value = -1
    if not 0 <= value <= 0xFFFFFFFF:
        raise argparse.ArgumentTypeError(f"bad identification {text!r}: 32-bit hex")
    return value


def _program(text: str) -> int:
    return int_in_range(text, 1, 254, "program number")


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    p = subs.add_parser(
        "flash", help="download a program to a node (CiA 302-3)",
        description="Stop the node's program, clear it, download FILE to 0x1F50 by SDO block "
                    "transfer, start it and read its software identification (0x1F56).")
    p.add_argument("node", type=node_id, metavar="NODE", help="node-ID 1..127")
    p.add_argument("file", metavar="FILE", help="the program image")
    add_bus_options(p)
    add_master_options(p)
    p.add_argument("--program", type=_program, default=1, metavar="N",
                   help="program number: sub-index of 0x1F50/0x1F51 (default 1)")
    p.add_argument("--no-clear", action="store_true", help="do not clear before the download")
    p.add_argument("--ident", type=_ident, metavar="HEX",
                   help="fail unless 0x1F56 reads this after the start")
    p.add_argument("--progress", action="store_true",
                   help="draw the progress bar even when stderr is not a terminal")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from canola.flash import FlashError  # noqa: PLC0415 -- on first use

    try:
        with open(args.file, "rb") as src:
            image = src.read()
    except OSError as exc:
        raise CliError(f"cannot read {args.file}: {exc.strerror or exc}") from None
    if not image:
        raise CliError(f"{args.file} is empty")
    bar = ProgressBar(len(image), enabled=args.progress or sys.stderr.isatty())
    with master_from_args(args) as master:
        try:
            result = master.flash(args.node, image, progress=bar.update,
                                  program=args.program, clear=not args.no_clear,
                                  ident=args.ident)
        except FlashError as exc:
            bar.finish()
            raise CliError(str(exc)) from None
    bar.finish()
    if args.json:
        emit_json({"node": args.node, "bytes": result.bytes, "ident": result.ident})
    else:
        print(f"node {args.node}: {result.bytes} bytes, program started, "
              f"identification 0x{result.ident:08X}")
    return 0
