"""``canola sdo``: read, write, upload to a file, download from a file (SDO client).

    canola sdo read NODE 0x1018:1 [TYPE]        TYPE as in CiA 309-3: u8..u64, i8..i64,
    canola sdo write NODE 0x1017:0 u16 1000     r32, r64, b, vs, os, us, d, t, td
    canola sdo upload NODE 0x2000:0 FILE        block transfer, progress bar
    canola sdo download NODE 0x2000:0 FILE
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
from collections.abc import Iterator

from canola import values
from canola.cli.common import (
    CliError,
    Parser,
    add_announce_option,
    add_bus_options,
    emit_json,
    master_from_args,
    node_id,
    object_address,
    positive_ms,
)
from canola.cli.progress import SdoProgress
from canola.decode import format_value
from canola.errors import SdoAbort
from canola.master import SdoTimeout


def _type(text: str) -> int:
    try:
        return values.parse_type(text)
    except values.ValueFormatError:
        raise argparse.ArgumentTypeError(
            f"unknown type {text!r}: u8..u64, i8..i64, r32, r64, b, vs, os, us, d, t, td"
        ) from None


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    p = subs.add_parser("sdo", help="SDO client: read, write, upload, download",
                        description="Access a node's object dictionary over SDO.")
    sdo_subs = p.add_subparsers(dest="sdo_command", metavar="SUBCOMMAND", parser_class=Parser)
    sdo_subs.required = True

    def common(sp: argparse.ArgumentParser) -> None:
        sp.add_argument("node", type=node_id, metavar="NODE", help="node-ID 1..127")
        sp.add_argument("address", type=object_address, metavar="INDEX:SUB",
                        help="object, e.g. 0x1018:1")
        add_bus_options(sp)
        sp.add_argument("--timeout", type=positive_ms, default=1000, metavar="MS",
                        help="SDO time-out (default 1000 ms)")
        sp.add_argument("--master-id", type=node_id, default=127, metavar="N",
                        help="node-ID the client uses (default 127)")
        add_announce_option(sp)

    r = sdo_subs.add_parser("read", help="read a value",
                            description="Read an object. Without TYPE the bytes are shown "
                                        "as a little-endian number or text.")
    common(r)
    r.add_argument("type", type=_type, nargs="?", metavar="TYPE", help="CiA 309-3 type name")
    r.add_argument("--json", action="store_true", help="print a JSON object")
    r.set_defaults(func=run_read)

    w = sdo_subs.add_parser("write", help="write a value",
                            description="Write an object: TYPE (CiA 309-3 name) and VALUE "
                                        "(integers decimal or 0x-hex, os/d as hex digits).")
    common(w)
    w.add_argument("type", type=_type, metavar="TYPE")
    w.add_argument("value", metavar="VALUE")
    w.add_argument("--json", action="store_true", help="print a JSON object")
    w.set_defaults(func=run_write)

    for name, func, what in (("upload", run_upload, "read an object into FILE"),
                             ("download", run_download, "write FILE into an object")):
        f = sdo_subs.add_parser(name, help=what,
                                description=f"{what[0].upper()}{what[1:]} (block transfer; "
                                            "--no-block for segmented).")
        common(f)
        f.add_argument("file", metavar="FILE")
        f.add_argument("--no-block", action="store_true", help="segmented transfer")
        f.add_argument("--progress", action="store_true",
                       help="draw the progress bar even when stderr is not a terminal")
        f.add_argument("--max-size", type=int, default=1 << 20, metavar="BYTES",
                       help="largest upload accepted (default 1 MiB)")
        f.add_argument("--json", action="store_true", help="print a JSON summary")
        f.set_defaults(func=func)


def _where(args: argparse.Namespace) -> str:
    index, sub = args.address
    return f"node {args.node} 0x{index:04X}:{sub:02X}"


@contextlib.contextmanager
def _sdo_errors(args: argparse.Namespace) -> Iterator[None]:
    try:
        yield
    except SdoTimeout:
        raise CliError(f"no response from node {args.node} (SDO time-out {args.timeout} ms)"
                       ) from None
    except SdoAbort as exc:
        raise CliError(f"{_where(args)}: SDO abort 0x{exc.code:08X}: {exc.text}") from None


def run_read(args: argparse.Namespace) -> int:
    index, sub = args.address
    with master_from_args(args, sdo_timeout_ms=args.timeout) as master, _sdo_errors(args):
        data = master.sdo(args.node).upload(index, sub, timeout=args.timeout / 1000)
    result: dict[str, object] = {"node": args.node, "index": index, "sub": sub,
                                 "raw": data.hex()}
    if args.type is not None:
        try:
            value = values.decode(args.type, data)
        except values.ValueFormatError as exc:
            raise CliError(f"{_where(args)}: {exc}") from None
        text = values.to_text(args.type, value)
        result["type"] = values.type_name(args.type, short=True)
        result["value"] = value if isinstance(value, bool | int | float | str) else text
    else:
        text = format_value(data) if data else "(empty)"
    if args.json:
        emit_json(result)
    else:
        print(text)
    return 0


def run_write(args: argparse.Namespace) -> int:
    index, sub = args.address
    try:
        data = values.encode(args.type, values.from_text(args.type, args.value))
    except values.ValueFormatError as exc:
        raise CliError(f"canola sdo write: error: {exc}", 2) from None
    with master_from_args(args, sdo_timeout_ms=args.timeout) as master, _sdo_errors(args):
        master.sdo(args.node).download(index, sub, data, timeout=args.timeout / 1000)
    if args.json:
        emit_json({"node": args.node, "index": index, "sub": sub, "raw": data.hex()})
    return 0


def run_upload(args: argparse.Namespace) -> int:
    index, sub = args.address
    if args.max_size < 1:
        raise CliError(f"canola sdo upload: error: bad --max-size {args.max_size}", 2)
    progress = SdoProgress(upload=True, total=None,
                           enabled=args.progress or sys.stderr.isatty())
    with master_from_args(args, sdo_timeout_ms=args.timeout) as master, _sdo_errors(args):
        master.on_frame(progress.frame, cob_id=0x580 + args.node)
        data = master.sdo(args.node).upload(index, sub, block=not args.no_block,
                                            max_size=args.max_size)
    progress.finish()
    tmp = f"{args.file}.part"
    try:
        with open(tmp, "wb") as out:
            out.write(data)
        os.replace(tmp, args.file)
    except OSError as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise CliError(f"cannot write {args.file}: {exc.strerror or exc}") from None
    if args.json:
        emit_json({"node": args.node, "index": index, "sub": sub, "bytes": len(data)})
    return 0


def run_download(args: argparse.Namespace) -> int:
    index, sub = args.address
    try:
        with open(args.file, "rb") as src:
            data = src.read()
    except OSError as exc:
        raise CliError(f"cannot read {args.file}: {exc.strerror or exc}") from None
    progress = SdoProgress(upload=False, total=len(data),
                           enabled=args.progress or sys.stderr.isatty())
    with master_from_args(args, sdo_timeout_ms=args.timeout) as master, _sdo_errors(args):
        master.on_frame(progress.frame, cob_id=0x580 + args.node)
        master.sdo(args.node).download(index, sub, data, block=not args.no_block)
    progress.finish()
    if args.json:
        emit_json({"node": args.node, "index": index, "sub": sub, "bytes": len(data)})
    return 0
