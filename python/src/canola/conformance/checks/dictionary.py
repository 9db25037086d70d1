# SPDX-License-Identifier: Apache-2.0
"""Group ``dictionary``: the node's object dictionary against its EDS -- every entry there,
access types, value lengths, limits, missing objects and sub-indices, the values the EDS
fixes, the mandatory objects."""

from __future__ import annotations

from functools import partial
from itertools import chain

from canola import SdoAbort
from canola.conformance.context import Context, abort_text, outcome
from canola.conformance.entries import (
    VARIABLE_TYPES,
    describe,
    fixed_size,
    integer_range,
    plain_rw,
    value_text,
    variables,
)
from canola.conformance.rawsdo import NoAnswerError, SdoProtocolError, ValueTooLargeError
from canola.conformance.registry import check
from canola.formats import eds, values

_MANDATORY = ((0x1000, 0), (0x1001, 0), (0x1018, 0), (0x1018, 1))
_NOT_THERE = (0x06020000, 0x06090011)
_DOMAIN = 0x000F
_COMPOUND = (eds.ObjectType.ARRAY, eds.ObjectType.RECORD, eds.ObjectType.DEFSTRUCT)


def _probed(ctx: Context) -> list[eds.Variable]:
    """Readable, writable entries of fixed size whose write only stores a value."""
    return [v for v in variables(ctx.od) if plain_rw(v) and fixed_size(v) is not None]


@check("dictionary.mandatory", clause="CiA 301 §7.5.2.1, §7.5.2.2, §7.5.2.21",
       title="0x1000, 0x1001 and 0x1018 (sub 0, 1) are in the EDS and readable")
def mandatory(ctx: Context) -> None:
    for index, sub in _MANDATORY:
        if ctx.var(index, sub) is None:
            ctx.finding(f"EDS entry 0x{index:04X}:{sub}", "present (mandatory)", "missing")
        try:
            ctx.sdo.upload(index, sub)
        except (SdoAbort, NoAnswerError, SdoProtocolError) as exc:
            ctx.finding(f"read 0x{index:04X}:{sub}", "its value", outcome(exc))


#: CiA 301 §7.5.2.4: a read of 0x1003 above the number of errors is answered with an abort.
_NO_DATA = (0x08000024, 0x08000000)
_HISTORY_CLAUSE = "CiA 301 §7.5.2.4 (no error recorded there: no data)"


def _errors_recorded(ctx: Context) -> int:
    """0x1003:0, the number of errors the history holds (0 when it cannot be read)."""
    if ctx.var(0x1003, 0) is None:
        return 0
    try:
        return int.from_bytes(ctx.sdo.upload(0x1003, 0), "little")
    except (SdoAbort, NoAnswerError, SdoProtocolError):
        return 0  # this check reports the read of 0x1003:0


def _history_above_count(ctx: Context, var: eds.Variable, recorded: int) -> bool:
    """For a sub-index of 0x1003 above the ``recorded`` errors: expect the abort CiA 301
    prescribes (0x08000024, or 0x08000000), a finding otherwise; True when it was one."""
    if var.index != 0x1003 or not recorded < var.subindex:
        return False
    what = f"read {describe(var)} (0x1003:0 = {recorded})"
    expected = " or ".join(abort_text(c) for c in _NO_DATA)
    try:
        data = ctx.sdo.upload(var.index, var.subindex)
    except SdoAbort as exc:
        if exc.code not in _NO_DATA:
            ctx.finding(what, expected, outcome(exc), clause=_HISTORY_CLAUSE)
        return True
    except (NoAnswerError, SdoProtocolError) as exc:
        ctx.finding(what, expected, outcome(exc), clause=_HISTORY_CLAUSE)
        return True
    if var.subindex > _errors_recorded(ctx):  # not an error recorded meanwhile
        ctx.finding(what, expected, f"the value {value_text(var, data)}",
                    clause=_HISTORY_CLAUSE)
    return True


@check("dictionary.entries", clause="CiA 306 §4.5.2 (object descriptions), CiA 301 §7.5.2.4",
       title="every entry of the EDS exists; readable ones read with their type's length "
             "(0x1003 above its number of errors: no data, abort 0x08000024)")
def entries(ctx: Context) -> None:
    count = 0
    recorded = _errors_recorded(ctx)
    for var in variables(ctx.od):
        count += 1
        if _history_above_count(ctx, var, recorded):
            continue
        what = f"read {describe(var)}"
        try:
            data = ctx.sdo.upload(var.index, var.subindex)
        except SdoAbort as exc:
            domain_empty = var.data_type == _DOMAIN and exc.code not in _NOT_THERE
            # an empty string has no data to give: CiA 301's abort for that is 0x08000024
            string_empty = var.data_type in VARIABLE_TYPES and exc.code == _NO_DATA[0]
            if (var.access_type == "wo" and exc.code == 0x06010001) or domain_empty \
                    or string_empty:
                continue
            ctx.finding(what, _expected_read(var), outcome(exc))
            continue
        except ValueTooLargeError as exc:
            if var.data_type not in VARIABLE_TYPES:
                ctx.finding(what, "a value", outcome(exc))
            else:  # a value of its length may be that long: not read whole, not judged
                ctx.note(f"{describe(var)} not read whole: {exc}")
            continue
        except (NoAnswerError, SdoProtocolError) as exc:
            ctx.finding(what, "a value", outcome(exc))
            continue
        size = fixed_size(var)
        if var.access_type == "wo":
            ctx.finding(what, "abort 0x06010001 (write only)", f"the value {value_text(var, data)}")
        elif size is not None and len(data) != size:
            ctx.finding(what, f"{size} bytes", f"{len(data)} bytes [{data.hex(' ').upper()}]")
    ctx.note(f"{count} entries")


def _expected_read(var: eds.Variable) -> str:
    if var.access_type == "wo":
        return "abort 0x06010001 (write only)"
    if var.data_type in VARIABLE_TYPES:
        return f"a value (0 bytes, or {abort_text(_NO_DATA[0])}, when empty)"
    return "a value"


@check("dictionary.read_write_only", clause="CiA 301 §7.2.4.3.17, CiA 306 §4.5.2",
       title="a read of a write-only entry is aborted with 0x06010001")
def read_write_only(ctx: Context) -> None:
    targets = [v for v in variables(ctx.od) if v.access_type == "wo"]
    if not targets:
        ctx.skip("the EDS has no write-only entry")
    for var in targets:
        ctx.expect_abort(f"read {describe(var)}", (0x06010001,),
                         partial(ctx.sdo.upload, var.index, var.subindex))
    ctx.note(f"{len(targets)} entries")


@check("dictionary.write_read_only", clause="CiA 301 §7.2.4.3.17, CiA 306 §4.5.2",
       title="a write to a read-only or const entry is aborted with 0x06010002")
def write_read_only(ctx: Context) -> None:
    targets = [v for v in variables(ctx.od) if v.access_type in ("ro", "const")]
    if not targets:
        ctx.skip("the EDS has no read-only entry")
    for var in targets:
        try:
            data = ctx.sdo.upload(var.index, var.subindex)
        except (SdoAbort, NoAnswerError, SdoProtocolError):
            continue  # dictionary.entries reports it
        # the value it has: a wrongly accepted write changes nothing
        ctx.expect_abort(f"write its own value to {describe(var)}", (0x06010002,),
                         partial(ctx.sdo.download, var.index, var.subindex, data))
    ctx.note(f"{len(targets)} entries")


def _length_check(ctx: Context, *, longer: bool) -> None:
    targets = [v for v in _probed(ctx) if longer or (fixed_size(v) or 0) >= 2]
    if not targets:
        ctx.skip("the EDS has no readable and writable entry of fixed size"
                 + ("" if longer else " of 2 bytes or more"))
    codes = (0x06070012 if longer else 0x06070013, 0x06070010)
    for var in targets:
        try:
            original = ctx.sdo.upload(var.index, var.subindex)
        except (SdoAbort, NoAnswerError, SdoProtocolError):
            continue  # dictionary.entries reports it
        probe = original + b"\0" if longer else original[:-1]
        ctx.expect_abort(
            f"write {len(probe)} bytes to {describe(var)}", codes,
            partial(ctx.sdo.download, var.index, var.subindex, probe),
            restore=partial(ctx.sdo.download, var.index, var.subindex, original))
    ctx.note(f"{len(targets)} entries")


@check("dictionary.length_too_long", clause="CiA 301 §7.2.4.3.17",
       title="a value one byte too long is aborted with 0x06070012 (or 0x06070010)")
def length_too_long(ctx: Context) -> None:
    _length_check(ctx, longer=True)


@check("dictionary.length_too_short", clause="CiA 301 §7.2.4.3.17",
       title="a value one byte too short is aborted with 0x06070013 (or 0x06070010)")
def length_too_short(ctx: Context) -> None:
    _length_check(ctx, longer=False)


@check("dictionary.limits", clause="CiA 306 §4.5.2 (LowLimit, HighLimit), CiA 301 §7.2.4.3.17",
       title="values outside LowLimit/HighLimit are refused (0x06090032/31 or 0x06090030), "
             "the limits themselves accepted (entries from 0x2000)")
def limits(ctx: Context) -> None:
    tested = 0
    for var in _probed(ctx):
        span = integer_range(var)
        low, high = var.low, var.high
        if var.index < 0x2000 or span is None or not (isinstance(low, int)
                                                      or isinstance(high, int)):
            continue
        assert var.data_type is not None
        try:
            original = ctx.sdo.upload(var.index, var.subindex)
            now = values.decode(var.data_type, original)
        except (SdoAbort, NoAnswerError, SdoProtocolError, values.ValueFormatError):
            continue  # dictionary.entries reports it
        tested += 1
        assert isinstance(now, int)
        if (isinstance(low, int) and now < low) or (isinstance(high, int) and now > high):
            # its own value could not be written back: the entry is left as it is
            bounds = [f"{word} {bound}" for word, bound in (("LowLimit", low),
                                                            ("HighLimit", high))
                      if isinstance(bound, int)]
            ctx.finding(f"value of {describe(var)}", f"within {' .. '.join(bounds)}",
                        f"{now}")
            continue

        def put(value: int, var: eds.Variable = var) -> None:
            assert var.data_type is not None
            ctx.sdo.download(var.index, var.subindex, values.encode(var.data_type, value))

        def back(var: eds.Variable = var, original: bytes = original) -> None:
            ctx.sdo.download(var.index, var.subindex, original)

        for bound, step, code in ((low, -1, 0x06090032), (high, 1, 0x06090031)):
            if not isinstance(bound, int):
                continue
            outside = bound + step
            if span[0] <= outside <= span[1]:
                ctx.expect_abort(f"write {outside} to {describe(var)} (limit {bound})",
                                 (code, 0x06090030), partial(put, outside), restore=back)
            try:
                put(bound)
            except (SdoAbort, NoAnswerError, SdoProtocolError) as exc:
                ctx.finding(f"write the limit {bound} to {describe(var)}", "success",
                            outcome(exc))
        ctx.on_undo(f"write back {describe(var)}", back)
    if not tested:
        ctx.skip("the EDS gives no LowLimit/HighLimit for a writable integer entry from "
                 "0x2000")
    ctx.note(f"{tested} entries")


def _absent_index(od: eds.ObjectDictionary) -> int:
    """An index the EDS does not have (the manufacturer area from its top first)."""
    for index in chain(range(0x5FFF, 0x1FFF, -1), range(0x9FFF, 0x5FFF, -1)):
        if index not in od.objects:
            return index
    return next(i for i in range(0x1000, 0x10000) if i not in od.objects)


@check("dictionary.missing_object", clause="CiA 301 §7.2.4.3.17",
       title="a read and a write of an object the EDS does not have are aborted with "
             "0x06020000")
def missing_object(ctx: Context) -> None:
    index = _absent_index(ctx.od)
    ctx.expect_abort(f"read 0x{index:04X}:0 (not in the EDS)", (0x06020000,),
                     lambda: ctx.sdo.upload(index, 0))
    ctx.expect_abort(f"write 1 byte to 0x{index:04X}:0 (not in the EDS)", (0x06020000,),
                     lambda: ctx.sdo.download(index, 0, b"\x01"))
    ctx.note(f"index 0x{index:04X}")


@check("dictionary.missing_sub", clause="CiA 301 §7.2.4.3.17",
       title="a read of a sub-index beyond the EDS's (and of sub 1 of a VAR) is aborted "
             "with 0x06090011")
def missing_sub(ctx: Context) -> None:
    tested = 0
    for index in sorted(ctx.od.objects):
        obj = ctx.od.objects[index]
        compound = obj.object_type in _COMPOUND
        sub = max(obj.subs) + 1 if compound else 1
        if sub > 0xFF or not (compound or index == 0x1000):
            continue  # a VAR: 0x1000 stands for them all
        tested += 1
        ctx.expect_abort(f"read 0x{index:04X}:{sub} (beyond the EDS's sub-indices)",
                         (0x06090011,), partial(ctx.sdo.upload, index, sub))
    ctx.note(f"{tested} objects")


def _compare(ctx: Context, var: eds.Variable, expected: values.Value | None,
             source: str) -> bool:
    """Read ``var`` and compare it with ``expected`` (a finding when they differ); False
    when the EDS gives no value."""
    if expected is None or var.data_type is None:
        return False
    try:
        data = ctx.sdo.upload(var.index, var.subindex)
        got: values.Value = values.decode(var.data_type, data)
    except (SdoAbort, NoAnswerError, SdoProtocolError) as exc:
        ctx.finding(f"read {describe(var)}", f"{expected!r} ({source})", outcome(exc))
        return True
    except values.ValueFormatError as exc:
        ctx.finding(f"read {describe(var)}", f"{expected!r} ({source})", str(exc))
        return True
    if isinstance(got, str) and isinstance(expected, str):
        got, expected = got.rstrip("\0"), expected.rstrip("\0")
    if got != expected:
        shown = value_text(var, data)
        want = f"0x{expected:X}" if isinstance(expected, int) and expected >= 0 else repr(expected)
        ctx.finding(f"value of {describe(var)}", f"{want} ({source})", shown)
    return True


@check("dictionary.device_type", clause="CiA 301 §7.5.2.1",
       title="0x1000 (device type) has the EDS's DefaultValue")
def device_type(ctx: Context) -> None:
    var = ctx.need(0x1000, why="device type")
    if not _compare(ctx, var, var.default, "EDS DefaultValue"):
        ctx.skip("the EDS gives no DefaultValue for 0x1000")


def _device_info(od: eds.ObjectDictionary, key: str) -> int | None:
    for name, text in od.device_info.items():
        if name.lower() == key.lower():
            try:
                return int(text.strip(), 0)
            except ValueError:
                return None
    return None


@check("dictionary.identity", clause="CiA 301 §7.5.2.21, CiA 306 §4.4 (DeviceInfo)",
       title="0x1018 vendor-ID and product code are those the EDS gives")
def identity(ctx: Context) -> None:
    compared = 0
    for sub, key in ((1, "VendorNumber"), (2, "ProductNumber")):
        var = ctx.var(0x1018, sub)
        if var is None:
            continue
        given = _device_info(ctx.od, key)
        source = f"[DeviceInfo] {key}"
        if given is None:
            given, source = (var.default if isinstance(var.default, int) else None,
                             "EDS DefaultValue")
        compared += _compare(ctx, var, given, source)
    if not compared:
        ctx.skip("the EDS gives neither VendorNumber nor ProductNumber")


@check("dictionary.constants", clause="CiA 306 §4.5.2 (AccessType const, DefaultValue)",
       title="every const entry with a DefaultValue has that value")
def constants(ctx: Context) -> None:
    targets = [v for v in variables(ctx.od) if v.access_type == "const" and v.default is not None]
    if not targets:
        ctx.skip("the EDS has no const entry with a DefaultValue")
    for var in targets:
        _compare(ctx, var, var.default, "EDS DefaultValue")
    ctx.note(f"{len(targets)} entries")

