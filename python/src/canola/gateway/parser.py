# SPDX-License-Identifier: Apache-2.0
"""The CiA 309-3 command line parser: one line of text -> one typed request.

Pure: no I/O, no state, no dependence on the network. :func:`parse_line` returns a
:class:`~canola.gateway.requests.Request` (``None`` for an empty or comment-only line) or
raises :class:`ParseError` with the CiA 309-3 error code to answer and the sequence
number, when the line had a readable one. A fuzz target drives it with arbitrary text:
it must never raise anything else.

Syntax (words are case-insensitive, numbers decimal, ``0x`` hexadecimal or ``0`` octal)::

    [<seq>] [[<net>] <node>] r[ead] <index> <sub> [<type>]
    [<seq>] [[<net>] <node>] w[rite] <index> <sub> <type> <value>
    [<seq>] [[<net>] <node>] start | stop | preop[erational] | reset node | reset comm[unication]
    [<seq>] [[<net>] <node>] enable heartbeat <ms> | disable heartbeat
    [<seq>] [[<net>] <node>] enable guarding <guard ms> <factor> | disable guarding
    [<seq>] [<net>] set network|node|sdo_timeout|sdo_block|heartbeat|id|events <value>
    [<seq>] [<net>] set command_timeout|command_size <value>
    [<seq>] [<net>] set rpdo <num> <cob-id> event|rtr|sync<n> <n> [<index> <sub>] <type>...
    [<seq>] [<net>] set tpdo[x] <num> <cob-id> <trans> [<inhibit>] [<event>|<sync>] <n> ...
    [<seq>] [<net>] r[ead] p[do] <num> | w[rite] p[do] <num> <n> <value>...
    [<seq>] [<net>] init <bit timing> | boot_up_indication Enable|Disable
    [<seq>] [<net>] lss_<command> <args>...
    [<seq>] info version | help [datatype|lss]
    [<seq>] auth <token>                                  (canola: docs/security.md)

A ``#`` outside double quotes, at the start or after a blank, starts a comment.
"""

from __future__ import annotations

import re

from canola.gateway.codes import GatewayError
from canola.gateway.formats import TYPES, parse_int, parse_value
from canola.gateway.requests import (
    Auth,
    BootUpIndication,
    DisableGuarding,
    DisableHeartbeat,
    EnableGuarding,
    EnableHeartbeat,
    Help,
    InfoVersion,
    Init,
    Lss,
    Nmt,
    PdoRead,
    PdoWrite,
    Request,
    SdoRead,
    SdoWrite,
    Set,
    SetRpdo,
    SetTpdo,
)

__all__ = ["LSS_COMMANDS", "SET_NAMES", "ParseError", "parse_line", "read_seq"]

#: ``set <name> <value>`` names and the values each takes (outside: ERROR:101).
SET_NAMES: dict[str, tuple[int, int]] = {
    "network": (0, 0xFFFF),
    "node": (1, 127),
    "sdo_timeout": (1, 0xFFFFFFFF),
    "sdo_block": (0, 1),
    "heartbeat": (0, 0xFFFF),
    "id": (0, 0xFF),
    "command_timeout": (0, 0xFFFFFFFF),
    "command_size": (0, 0xFFFFFFFF),
    "events": (0, 1),
}

#: The LSS commands of CiA 309-3 (and CANopenNode's non-standard ones).
LSS_COMMANDS = frozenset({
    "lss_switch_glob", "lss_switch_sel", "lss_set_node", "lss_conf_bitrate",
    "lss_activate_bitrate", "lss_store", "lss_inquire_addr", "lss_get_node",
    "lss_identity", "lss_ident_nonconf", "lss_allnodes", "_lss_fastscan", "_lss_slowscan",
})

_NODE_LEVEL = frozenset({"r", "read", "w", "write", "start", "stop", "preop",
                         "preoperational", "reset", "enable", "disable"})
_NET_LEVEL = frozenset({"set", "init", "boot_up_indication"}) | LSS_COMMANDS
_GLOBAL = frozenset({"info", "help", "auth"})
_NOT_SUPPORTED = frozenset({"led", "log"})

_SEQ_RE = re.compile(r"\s*\[\s*([0-9]{1,10})\s*\]")
# What comes before a comment: words (a '#' inside or at the end of one is text), blanks
# not followed by '#', and double-quoted runs. Possessive everywhere: no backtracking, so
# the match is linear in the line's length whatever the line.
_BEFORE_COMMENT = re.compile(r'(?:[^"\s#]++|\s++(?!#)|(?<=\S)#|"[^"]*+"?)*+')
_WORD = re.compile(r"\s*+(\S++)")

#: The most arguments an LSS command takes (lss_allnodes with its scan types).
_LSS_ARGS_MAX = 11


class ParseError(Exception):
    """A line that gets ``ERROR:<code>``; ``seq`` is None when the line had none."""

    def __init__(self, code: GatewayError, seq: int | None, detail: str) -> None:
        self.code = code
        self.seq = seq
        self.detail = detail
        super().__init__(f"{detail} (error {int(code)})")


def read_seq(text: str) -> int | None:
    """The sequence number at the start of ``text``, if it has a valid one."""
    m = _SEQ_RE.match(text)
    if m is None:
        return None
    seq = int(m.group(1))
    return seq if seq <= 0xFFFFFFFF else None


def _strip_comment(line: str) -> str:
    """``line`` without its comment: a ``#`` outside double quotes, at the start of the line
    or after a blank, to the end."""
    if "#" not in line:
        return line
    m = _BEFORE_COMMENT.match(line)
    assert m is not None  # the pattern matches the empty string
    return line[:m.end()]


class _Cursor:
    """The whitespace-separated words of a line, read from a position: each word is
    looked at once, so reading a line costs time linear in its length."""

    def __init__(self, text: str, pos: int, seq: int) -> None:
        self.text = text
        self.pos = pos
        self.seq = seq
        self._next: re.Match[str] | None = None

    def fail(self, detail: str, code: GatewayError = GatewayError.SYNTAX) -> ParseError:
        return ParseError(code, self.seq, detail)

    def _match(self) -> re.Match[str] | None:
        if self._next is None or self._next.start() != self.pos:
            self._next = _WORD.match(self.text, self.pos)
        return self._next

    def peek(self) -> str | None:
        m = self._match()
        return m.group(1) if m else None

    def word(self, what: str) -> str:
        m = self._match()
        if m is None:
            raise self.fail(f"expected {what}")
        self.pos = m.end()
        return m.group(1)

    def number(self, what: str, limit: int, low: int = 0) -> int:
        text = self.word(what)
        try:
            value = parse_int(text)
        except ValueError:
            raise self.fail(f"expected {what}, got {text[:40]!r}") from None
        if not low <= value <= limit:
            raise self.fail(f"{what} {value} is out of range {low}..{limit}")
        return value

    def rest(self) -> str:
        text, self.pos = self.text[self.pos:].strip(), len(self.text)
        return text

    def end(self) -> None:
        if self.peek() is not None:
            raise self.fail(f"unexpected {self.text[self.pos:].strip()[:40]!r} at the end of "
                            "the request")


def _is_number(word: str | None) -> bool:
    if word is None:
        return False
    try:
        parse_int(word)
    except ValueError:
        return False
    return True


def parse_line(line: str) -> Request | None:
    """Parse one request line (without or with its CR LF)."""
    text = _strip_comment(line.replace("\0", " ")).strip()
    if not text:
        return None
    m = _SEQ_RE.match(text)
    if m is None:
        raise ParseError(GatewayError.SYNTAX, None, "a request starts with [<sequence>]")
    seq = int(m.group(1))
    if seq > 0xFFFFFFFF:
        raise ParseError(GatewayError.SYNTAX, None, "sequence number out of range")
    cur = _Cursor(text, m.end(), seq)
    numbers: list[int] = []
    while _is_number(cur.peek()):
        if len(numbers) == 2:
            raise cur.fail("more than two numbers before the command")
        numbers.append(cur.number("network or node", 0xFFFF))
    raw = cur.word("a command")
    command = raw.lower()
    net: int | None = None
    node: int | None = None
    if command in _NODE_LEVEL and not (command in ("r", "read", "w", "write") and
                                       (cur.peek() or "").lower() in ("p", "pdo")):
        if len(numbers) == 2:
            net, node = numbers
        elif numbers:
            node = numbers[0]
        if node is not None and node > 0xFF:
            raise cur.fail(f"node {node} is out of range", GatewayError.UNSUPPORTED_NODE)
    elif command in _NET_LEVEL or command in ("r", "read", "w", "write"):
        if len(numbers) > 1:
            raise cur.fail("a network command takes only a network number")
        net = numbers[0] if numbers else None
    elif command in _GLOBAL:
        if numbers:
            raise cur.fail("this command takes no network or node")
    elif command in _NOT_SUPPORTED:
        raise cur.fail(f"{raw!r} is not supported", GatewayError.REQUEST_NOT_SUPPORTED)
    else:
        raise cur.fail(f"unknown command {raw!r}", GatewayError.REQUEST_NOT_SUPPORTED)
    return _command(cur, command, net, node)


def _command(cur: _Cursor, command: str, net: int | None, node: int | None) -> Request:
    seq = cur.seq
    if command in ("r", "read"):
        if (cur.peek() or "").lower() in ("p", "pdo"):
            cur.word("pdo")
            num = _pdo_number(cur)
            cur.end()
            return PdoRead(seq, net, None, num=num)
        index = cur.number("object index", 0xFFFF)
        sub = cur.number("sub-index", 0xFF)
        type_name = None
        if cur.peek() is not None:
            type_name = _type(cur)
        cur.end()
        return SdoRead(seq, net, node, index=index, sub=sub, type=type_name)
    if command in ("w", "write"):
        if (cur.peek() or "").lower() in ("p", "pdo"):
            cur.word("pdo")
            num = _pdo_number(cur)
            count = cur.number("number of values", 64)
            values = tuple(cur.number("value", 0xFFFFFFFFFFFFFFFF) for _ in range(count))
            cur.end()
            return PdoWrite(seq, net, None, num=num, values=values)
        index = cur.number("object index", 0xFFFF)
        sub = cur.number("sub-index", 0xFF)
        type_name = _type(cur)
        text = cur.rest()
        if not text:
            raise cur.fail("expected a value")
        try:
            data = parse_value(type_name, text)
        except ValueError as exc:
            raise cur.fail(str(exc)) from None
        return SdoWrite(seq, net, node, index=index, sub=sub, type=type_name, data=data)
    if command in ("start", "stop", "preop", "preoperational"):
        cur.end()
        nmt = "preop" if command.startswith("preop") else command
        return Nmt(seq, net, node, command=nmt)  # type: ignore[arg-type]
    if command == "reset":
        what = cur.word("'node' or 'comm[unication]'").lower()
        cur.end()
        if what == "node":
            return Nmt(seq, net, node, command="reset_node")
        if what in ("comm", "communication"):
            return Nmt(seq, net, node, command="reset_comm")
        raise cur.fail("expected 'node' or 'comm[unication]' after 'reset'")
    if command in ("enable", "disable"):
        what = cur.word("'heartbeat' or 'guarding'").lower()
        if what == "heartbeat":
            if command == "disable":
                cur.end()
                return DisableHeartbeat(seq, net, node)
            ms = cur.number("heartbeat time", 0xFFFF)
            cur.end()
            return EnableHeartbeat(seq, net, node, ms=ms)
        if what == "guarding":
            if command == "disable":
                cur.end()
                return DisableGuarding(seq, net, node)
            guard = cur.number("guard time", 0xFFFF)
            factor = cur.number("life time factor", 0xFF)
            cur.end()
            return EnableGuarding(seq, net, node, guard_ms=guard, factor=factor)
        raise cur.fail(f"expected 'heartbeat' or 'guarding' after {command!r}")
    if command == "set":
        return _set(cur, net)
    if command == "init":
        bit_timing = cur.number("bit timing index", 9)
        cur.end()
        return Init(seq, net, None, bit_timing=bit_timing)
    if command == "boot_up_indication":
        what = cur.word("'Enable' or 'Disable'").lower()
        cur.end()
        if what not in ("enable", "disable"):
            raise cur.fail("expected 'Enable' or 'Disable'")
        return BootUpIndication(seq, net, None, enable=what == "enable")
    if command == "info":
        what = cur.word("'version'").lower()
        cur.end()
        if what != "version":
            raise cur.fail("expected 'version' after 'info'")
        return InfoVersion(seq)
    if command == "auth":
        token = cur.word("a token")
        cur.end()
        return Auth(seq, token=token)
    if command == "help":
        topic = (cur.peek() or "").lower()
        if topic:
            cur.word("topic")
        cur.end()
        if topic not in ("", "datatype", "lss"):
            raise cur.fail("help topics: datatype, lss")
        return Help(seq, topic=topic)
    assert command in LSS_COMMANDS
    args: list[int] = []
    while cur.peek() is not None:
        if len(args) == _LSS_ARGS_MAX:
            raise cur.fail(f"more than {_LSS_ARGS_MAX} arguments")
        args.append(cur.number("LSS argument", 0xFFFFFFFF))
    return Lss(seq, net, None, command=command, args=tuple(args))


def _type(cur: _Cursor) -> str:
    name = cur.word("a data type").lower()
    if name not in TYPES:
        raise cur.fail(f"unknown data type {name!r}")
    return name


def _pdo_number(cur: _Cursor) -> int:
    num = cur.number("PDO number", 512)
    if num == 0:
        raise cur.fail("PDO numbers are 1..512")
    return num


def _set(cur: _Cursor, net: int | None) -> Request:
    seq = cur.seq
    what = cur.word("what to set").lower()
    if what == "rpdo":
        num, cob_id, trans = _pdo_comm(cur)
        mapping = _mapping(cur)
        return SetRpdo(seq, net, None, num=num, cob_id=cob_id, transmission=trans,
                       mapping=mapping)
    if what in ("tpdo", "tpdox"):
        extended = what == "tpdox"
        if (cur.peek() or "").lower() == "x":
            cur.word("x")
            extended = True
        num, cob_id, trans = _pdo_comm(cur)
        inhibit = event = sync = 0
        if extended and trans >= 0xFE:
            inhibit = cur.number("inhibit time", 0xFFFF)
        if extended and trans >= 0xFD:
            event = cur.number("event timer", 0xFFFF)
        elif extended and trans <= 240:
            sync = cur.number("SYNC start value", 0xFF)
        mapping = _mapping(cur)
        return SetTpdo(seq, net, None, num=num, cob_id=cob_id, transmission=trans,
                       inhibit=inhibit, event=event, sync=sync, mapping=mapping)
    if what not in SET_NAMES:
        raise cur.fail(f"cannot set {what!r}", GatewayError.REQUEST_NOT_SUPPORTED)
    low, high = SET_NAMES[what]
    value = cur.number(what, high, low)
    cur.end()
    return Set(seq, net, None, what=what, value=value)


def _pdo_comm(cur: _Cursor) -> tuple[int, int, int]:
    num = _pdo_number(cur)
    cob_id = cur.number("COB-ID", 0xFFFFFFFF)
    word = cur.word("transmission type").lower()
    if word == "event":
        trans = 0xFF
    elif word == "rtr":
        trans = 0xFD
    elif word.startswith("sync") and _is_number(word[4:]):
        trans = parse_int(word[4:])
        if not 0 <= trans <= 240:
            raise cur.fail("SYNC period is 0..240")
    else:
        raise cur.fail("expected 'event', 'rtr' or 'sync<0..240>'")
    return num, cob_id, trans


def _mapping(cur: _Cursor) -> tuple[int, ...]:
    count = cur.number("number of mapped objects", 64)
    out = []
    for _ in range(count):
        index = sub = 0
        if _is_number(cur.peek()):
            index = cur.number("object index", 0xFFFF)
            sub = cur.number("sub-index", 0xFF)
        spec = TYPES.get(cur.word("a data type").lower())
        if spec is None or spec.size == 0 or spec.name == "hex":
            raise cur.fail("only basic types can be mapped to PDOs")
        bits = 1 if spec.kind == "bool" else spec.size * 8
        out.append(((index or spec.code) << 16) | (sub << 8) | bits)
    cur.end()
    return tuple(out)
