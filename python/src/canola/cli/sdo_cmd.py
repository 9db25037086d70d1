# SPDX-License-Identifier: Apache-2.0
"""``canola sdo``: read, write, upload to a file, download from a file (SDO client).

    canola sdo read NODE 0x1018:1 [TYPE]        TYPE as in CiA 309-3: u8..u64, i8..i64,
    canola sdo write NODE 0x1017:0 u16 1000     r32, r64, b, vs, os, us, d, t, td
    canola sdo upload NODE 0x2000:0 FILE        block transfer, progress bar
    canola sdo download NODE 0x2000:0 FILE

With ``--eds FILE`` (or ``--dcf``, or ``--eds N=FILE``) an entry may be named as
python-canopen names it (``"Producer heartbeat time"``, ``"Identity object.Vendor-ID"``)
and its type comes from the file: ``canola sdo write 5 "Producer heartbeat time" 1000``.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
from collections.abc import Iterator

from canola.cli.common import (
    CliError,
    Parser,
    UsageError,
    add_announce_option,
    add_bus_options,
    add_dictionary_options,
    add_group,
    dictionaries_from_args,
    emit_json,
    master_from_args,
    node_id,
    positive_ms,
)
from canola.cli.progress import SdoProgress
from canola.errors import SdoAbort
from canola.files import FileError, write_file
from canola.formats import values
from canola.formats.eds import Variable
from canola.master import SdoTimeout
from canola.odnames import EntryError, entry_name, find_entry, parse_address, value_text


def _type(text: str) -> int:
    try:
        return values.parse_type(text)
    except values.ValueFormatError:
        raise argparse.ArgumentTypeError(
            f"unknown type {text!r}: u8..u64, i8..i64, r32, r64, b, vs, os, us, d, t, td"
        ) from None


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    sdo_subs = add_group(subs, "sdo", "SDO client: read, write, upload, download",
                         "Access a node's object dictionary over SDO.")

    def common(sp: argparse.ArgumentParser) -> None:
        sp.add_argument("node", type=node_id, metavar="NODE", help="node-ID 1..127")
        sp.add_argument("entry", metavar="ENTRY",
                        help="INDEX:SUB, e.g. 0x1018:1, or with --eds a name, e.g. "
                             "'Identity object.Vendor-ID'")
        add_bus_options(sp)
        add_dictionary_options(sp)
        sp.add_argument("--timeout", type=positive_ms, default=1000, metavar="MS",
                        help="SDO time-out (default 1000 ms)")
        sp.add_argument("--master-id", type=node_id, default=127, metavar="N",
                        help="node-ID the client uses (default 127)")
        add_announce_option(sp)

    r = sdo_subs.add_parser("read", help="read a value",
                            description="Read an object. Its type is TYPE, else the one the "
                                        "EDS gives; without either the bytes are shown as a "
                                        "little-endian number or text.")
    common(r)
    r.add_argument("type", type=_type, nargs="?", metavar="TYPE", help="CiA 309-3 type name")
    r.add_argument("--json", action="store_true", help="print a JSON object")
    r.set_defaults(func=run_read)

    w = sdo_subs.add_parser("write", help="write a value",
                            description="Write an object: TYPE (CiA 309-3 name; with --eds "
                                        "the EDS gives it) and VALUE (integers decimal or "
                                        "0x-hex, os/d as hex digits).")
    common(w)
    w.add_argument("type_value", nargs="+", metavar="[TYPE] VALUE",
                   help="the value, after its CiA 309-3 type unless the EDS gives it")
    w.add_argument("--json", action="store_true", help="print a JSON object")
    w.set_defaults(func=run_write)

    for name, func, what in (("upload", run_upload, "read an object into FILE"),
                             ("download", run_download, "write FILE into an object")):
        f = sdo_subs.add_parser(name, help=what,
                                description=f"{what[0].upper()}{what[1:]} (block transfer; "
                                            "--no-block for segmented).")
        common(f)
        f.add_argument("file", metavar="FILE", help="the file read from or written to")
        f.add_argument("--no-block", action="store_true", help="segmented transfer")
        f.add_argument("--progress", action="store_true",
                       help="draw the progress bar even when stderr is not a terminal")
        f.add_argument("--max-size", type=int, default=1 << 20, metavar="BYTES",
                       help="largest upload accepted (default 1 MiB)")
        f.add_argument("--json", action="store_true", help="print a JSON summary")
        f.set_defaults(func=func)


class _Target:
    """The entry a command names: its address, and its EDS entry when a file gives one."""

    def __init__(self, args: argparse.Namespace) -> None:
        self.node: int = args.node
        od = dictionaries_from_args(args).get(self.node)
        address = parse_address(args.entry)
        self.var: Variable | None = None
        if od is not None:
            try:
                self.var = find_entry(od, args.entry)
            except EntryError as exc:
                if address is None:
                    raise UsageError(f"canola sdo: error: {exc}") from None
        elif address is None:
            raise UsageError(f"canola sdo: error: bad object {args.entry!r}: INDEX:SUB, e.g. "
                             "0x1018:1 (entry names need --eds FILE)")
        if self.var is not None:
            self.index, self.sub = self.var.index, self.var.subindex
            self.name = entry_name(od, self.index, self.sub) if od is not None else None
        else:
            assert address is not None
            (self.index, self.sub), self.name = address, None

    @property
    def where(self) -> str:
        named = f" ({self.name})" if self.name else ""
        return f"node {self.node} 0x{self.index:04X}:{self.sub:02X}{named}"

    def data_type(self, given: int | None) -> int | None:
        """``given``, else the EDS's type of the entry."""
        return given if given is not None else None if self.var is None else self.var.data_type

    def json(self) -> dict[str, object]:
        out: dict[str, object] = {"node": self.node, "index": self.index, "sub": self.sub}
        if self.name:
            out["name"] = self.name
        return out


@contextlib.contextmanager
def sdo_errors(node: int, timeout_ms: int, where: str | None = None) -> Iterator[None]:
    """An SDO time-out or abort of a transfer with ``node`` as a one-line CliError; an
    abort says ``where`` (default: the node)."""
    try:
        yield
    except SdoTimeout as exc:
        took = f", after {exc.after_s:.2f} s" if exc.after_s is not None else ""
        raise CliError(f"no response from node {node} (SDO time-out {timeout_ms} ms{took})"
                       ) from None
    except SdoAbort as exc:
        at = where or f"node {node}"
        who = ""
        if exc.by_server is not None and exc.after_s is not None:
            sender = f"node {exc.node}" if exc.by_server else "the master"
            who = f" (sent by {sender} after {exc.after_s:.2f} s)"
        raise CliError(f"{at}: SDO abort 0x{exc.code:08X}: {exc.text}{who}") from None


def _sdo_errors(args: argparse.Namespace,
                target: _Target) -> contextlib.AbstractContextManager[None]:
    return sdo_errors(args.node, args.timeout, target.where)


def run_read(args: argparse.Namespace) -> int:
    target = _Target(args)
    with master_from_args(args, sdo_timeout_ms=args.timeout) as master, \
            _sdo_errors(args, target):
        data = master.sdo(args.node).upload(target.index, target.sub,
                                            timeout=args.timeout / 1000)
    result = {**target.json(), "raw": data.hex()}
    code = target.data_type(args.type)
    if code is not None and code in values.CIA309_NAMES.values():
        try:
            value = values.decode(code, data)
        except values.ValueFormatError as exc:
            raise CliError(f"{target.where}: {exc}") from None
        text = values.to_text(code, value)
        result["type"] = values.type_name(code, short=True)
        result["value"] = value if isinstance(value, bool | int | float | str) else text
    else:
        text = value_text(None, data)
    if args.json:
        emit_json(result)
    else:
        print(text)
    return 0


def _write_type_and_value(args: argparse.Namespace, target: _Target) -> tuple[int, str]:
    given = args.type_value
    if len(given) > 2:
        raise UsageError(f"canola sdo write: error: too many arguments {given[2:]!r}: "
                         "[TYPE] VALUE")
    code = _type(given[0]) if len(given) == 2 else target.data_type(None)
    if code is None or code not in values.CIA309_NAMES.values():
        raise UsageError("canola sdo write: error: give TYPE VALUE (with --eds FILE the EDS "
                         "gives the type)" if code is None else
                         f"canola sdo write: error: {target.where} has data type 0x{code:04X}: "
                         "give TYPE VALUE")
    return code, given[-1]


def run_write(args: argparse.Namespace) -> int:
    target = _Target(args)
    try:
        code, text = _write_type_and_value(args, target)
    except argparse.ArgumentTypeError as exc:
        raise UsageError(f"canola sdo write: error: {exc}") from None
    try:
        data = values.encode(code, values.from_text(code, text))
    except values.ValueFormatError as exc:
        raise CliError(f"canola sdo write: error: {exc}", 2) from None
    with master_from_args(args, sdo_timeout_ms=args.timeout) as master, \
            _sdo_errors(args, target):
        master.sdo(args.node).download(target.index, target.sub, data,
                                       timeout=args.timeout / 1000)
    if args.json:
        emit_json({**target.json(), "raw": data.hex()})
    return 0


def run_upload(args: argparse.Namespace) -> int:
    target = _Target(args)
    index, sub = target.index, target.sub
    if args.max_size < 1:
        raise CliError(f"canola sdo upload: error: bad --max-size {args.max_size}", 2)
    progress = SdoProgress(upload=True, total=None,
                           enabled=args.progress or sys.stderr.isatty())
    with master_from_args(args, sdo_timeout_ms=args.timeout) as master, \
            _sdo_errors(args, target):
        master.on_frame(progress.frame, cob_id=0x580 + args.node)
        data = master.sdo(args.node).upload(index, sub, block=not args.no_block,
                                            max_size=args.max_size)
    progress.finish()
    try:
        write_file(args.file, data)
    except FileError as exc:
        raise CliError(str(exc)) from None
    if args.json:
        emit_json({**target.json(), "bytes": len(data)})
    return 0


def run_download(args: argparse.Namespace) -> int:
    target = _Target(args)
    index, sub = target.index, target.sub
    try:
        with open(args.file, "rb") as src:
            data = src.read()
    except OSError as exc:
        raise CliError(f"cannot read {args.file}: {exc.strerror or exc}") from None
    progress = SdoProgress(upload=False, total=len(data),
                           enabled=args.progress or sys.stderr.isatty())
    with master_from_args(args, sdo_timeout_ms=args.timeout) as master, \
            _sdo_errors(args, target):
        master.on_frame(progress.frame, cob_id=0x580 + args.node)
        master.sdo(args.node).download(index, sub, data, block=not args.no_block)
    progress.finish()
    if args.json:
        emit_json({**target.json(), "bytes": len(data)})
    return 0
