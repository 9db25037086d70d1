# SPDX-License-Identifier: Apache-2.0
"""Tests of canola.odgen: golden files, C compilation and linking, the corpus, the CLI.

The golden files are tests/golden/sample.h and sample.c, generated from tests/golden/sample.eds
(written for these tests). After an intended change of the generator, rewrite them with

    CANOLA_UPDATE_GOLDEN=1 python -m pytest tests/test_odgen.py

and review the diff. The C tests use $CC (default ``cc``) and are skipped without a compiler.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from canola import EdsError
from canola.formats import eds, odgen

HERE = Path(__file__).resolve().parent
GOLDEN = HERE / "golden"
SAMPLE = GOLDEN / "sample.eds"
REPO = HERE.parents[1]
INCLUDE = REPO / "include"
CORE_SOURCES = sorted((REPO / "src").glob("*.c"))
CORPUS = REPO / ".." / "shared" / "eds-corpus"
WARNINGS = ["-std=c11", "-Wall", "-Wextra", "-Wconversion", "-Wshadow", "-Werror", "-pedantic"]


def compiler() -> str:
    cc = os.environ.get("CC", "cc")
    if shutil.which(cc) is None:
        pytest.skip(f"no C compiler ({cc})")
    return cc


def generate_sample(out: Path, **options: int) -> tuple[Path, Path]:
    return odgen.generate_files(SAMPLE, "sample", out, odgen.GenerateOptions(**options))


def compile_c(cc: str, source: Path, out_dir: Path,
              flags: tuple[str, ...] = ()) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [cc, *WARNINGS, *flags, f"-I{INCLUDE}", f"-I{source.parent}", "-c", str(source), "-o",
         str(out_dir / (source.stem + ".o"))],
        capture_output=True, text=True, check=False)


# --- golden files and reproducibility ---------------------------------------------------


def test_sample_matches_golden_files(tmp_path: Path) -> None:
    header, code = generate_sample(tmp_path)
    if os.environ.get("CANOLA_UPDATE_GOLDEN") == "1":
        shutil.copyfile(header, GOLDEN / "sample.h")
        shutil.copyfile(code, GOLDEN / "sample.c")
    assert header.read_bytes() == (GOLDEN / "sample.h").read_bytes()
    assert code.read_bytes() == (GOLDEN / "sample.c").read_bytes()


def test_generation_is_reproducible(tmp_path: Path) -> None:
    first = generate_sample(tmp_path / "a")
    second = generate_sample(tmp_path / "b")
    for a, b in zip(first, second, strict=True):
        assert a.read_bytes() == b.read_bytes()
    od = eds.parse(SAMPLE)
    assert odgen.generate(od, "sample") == odgen.generate(eds.parse(SAMPLE), "sample")


def test_entries_sorted_with_attributes() -> None:
    _, code = odgen.generate(eds.parse(SAMPLE), "sample")
    compact, general = code.split("#else /* the general form */")
    for table in (compact, general):  # both forms: one row per entry, in order
        rows = [line for line in table.splitlines() if line.startswith("    {.index = ")]
        keys = [(int(r.split(".index = ")[1].split(",")[0], 16), int(r.split(".sub = ")[1]
                 .split(",")[0])) for r in rows]
        assert keys == sorted(keys)
        assert len(keys) == len(set(keys))
    # the compact form: each entry names a row (type, attributes, side), each row once
    shared = re.findall(r"^    (\{\.type = .*\}),$", compact.split("k_rows[] = {")[1],
                        re.MULTILINE)
    assert len(shared) == len(set(shared)) < len(keys)
    compact_rows = dict(zip(keys, [shared[int(r.split(".row = ")[1].split(",")[0])]
                                   for r in compact.splitlines()
                                   if r.startswith("    {.index = ")], strict=True))
    assert ".side = 1}" in compact_rows[(0x2001, 0)]  # the first of the distinct limits
    assert ".side = 0}" in compact_rows[(0x1000, 0)]  # no limits, a fixed size
    assert compact_rows[(0x1000, 0)].startswith("{.type = CO_TYPE_UNSIGNED32, .attr = CO_OD_RO,")
    assert ", .side = 1}" in compact_rows[(0x1008, 0)]  # the first string's capacity
    assert "/* 0x1014 sub 0 */ 0x20, 0x80," in compact  # $NODEID+0x80: 0x80, 1 byte, next
    by_key = dict(zip(keys, rows, strict=True))
    assert ".attr = CO_OD_RW | CO_OD_NODEID," in by_key[(0x1014, 0)]
    assert ".attr = CO_OD_RWW | CO_OD_RPDO | CO_OD_NODEID," in by_key[(0x2300, 1)]
    assert ".attr = CO_OD_RWR | CO_OD_TPDO," in by_key[(0x2004, 0)]
    assert ".attr = CO_OD_WO | CO_OD_RPDO," in by_key[(0x2009, 0)]
    assert ".attr = CO_OD_CO," in by_key[(0x1008, 0)]
    assert ".limits = &k_limits_2001_00," in by_key[(0x2001, 0)]
    assert ".cob_id_emcy = 0x80u," in code  # $NODEID+0x80 stored without the node-ID
    assert (0x2200, 0) not in by_key  # DOMAIN left out by default


def test_image_records_skip_entries_and_name_far_ones() -> None:
    """The power-on values' records (co_od_tables_t.defaults): a head byte of the entries
    skipped (31: the position follows) and the length (7: the length follows)."""
    objects = "".join(f"[{0x2000 + i:04X}]\nParameterName=V{i}\nObjectType=0x7\n"
                      f"DataType=0x0007\nAccessType=rw\nDefaultValue={value}\n\n"
                      for i, value in enumerate([0] * 40 + [0x1234, 7]))
    text = objects + ("[3000]\nParameterName=S\nObjectType=0x7\nDataType=0x0009\n"
                      "AccessType=rw\nDefaultValue=abcdefgh\n")
    _, code = odgen.generate(eds.parse(HEADER + text, filename="far.eds"), "far")
    assert "/* 0x2028 sub 0 */ 0x5F, 0x28, 0x00, 0x34, 0x12," in code  # position 40 follows
    assert "/* 0x2029 sub 0 */ 0x20, 0x07," in code  # the next entry: none skipped
    assert ("/* 0x3000 sub 0 */ 0xE0, 0x08, 0x00, 0x61, 0x62, 0x63, 0x64, 0x65, 0x66, 0x67, "
            "0x68,") in code  # 8 bytes: the length follows


# --- C: compile, link, run ---------------------------------------------------------------


# The generated code compiles in both forms of the dictionary (canola/od.h), the compact one
# also with the look-up hash (CO_CONFIG_OD_HASH, by default the general form's alone).
FORMS = [(), ("-DCO_CONFIG_OD_COMPACT=1",), ("-DCO_CONFIG_OD_COMPACT=1", "-DCO_CONFIG_OD_HASH=1")]


@pytest.mark.parametrize("form", FORMS)
def test_sample_compiles_with_strict_warnings(tmp_path: Path, form: tuple[str, ...]) -> None:
    cc = compiler()
    _, code = generate_sample(tmp_path, domain_size=32)
    result = compile_c(cc, code, tmp_path, form)
    assert result.returncode == 0, result.stderr


@pytest.mark.parametrize("form", FORMS)
def test_values_struct_has_no_padding_between_members(tmp_path: Path,
                                                      form: tuple[str, ...]) -> None:
    """Members ordered by alignment: the compiler pads none (-Wpadded), at most a nested
    struct's tail up to its own alignment."""
    cc = compiler()
    _, code = generate_sample(tmp_path, domain_size=32)
    result = compile_c(cc, code, tmp_path, ("-Wpadded", "-Wno-error", *form))
    assert result.returncode == 0, result.stderr
    ours = [line for line in result.stderr.splitlines()
            if "sample.h" in line and "-Wpadded" in line]
    assert ours, "the sample's records end in tail padding: -Wpadded should say so"
    # GCC and clang: "... to align 'member'" before a member, "... alignment boundary" after
    # the last
    assert not [line for line in ours if re.search(r"to align\b", line)], ours


TEST_MAIN = r"""
#include "sample.h"

#include <string.h>

static int check(uint16_t index, uint8_t sub, uint64_t expected)
{
    uint64_t v = 0;
    return co_od_get_uint(&sample_od, index, sub, &v) == CO_OK && v == expected;
}

int main(void)
{
    uint32_t bad = 0;
    if (co_od_validate(&sample_od, &bad) != CO_OK) {
        return 10;
    }
    co_od_reset(&sample_od, 0x0000, 0xFFFF, 5);
    if (!check(0x1000, 0, 0x191u) || !check(0x1017, 0, 1000u) || !check(0x1018, 1, 0xCA0u)) {
        return 11;
    }
    if (!check(0x1014, 0, 0x85u) || !check(0x1800, 1, 0x185u) || !check(0x200C, 0, 5u)) {
        return 12; /* $NODEID defaults plus the node-ID */
    }
    if (!check(0x2001, 0, (uint64_t)(int64_t)-5) || !check(0x2002, 0, (uint64_t)(int64_t)-2) ||
        !check(0x2003, 0, (uint64_t)(int64_t)-8388608) ||
        !check(0x2008, 0, (uint64_t)INT64_MIN) || !check(0x2300, 1, 105u)) {
        return 13;
    }
    if (!check(0x200B, 0, 0xFFFFFFu) || !check(0x200E, 0, 0x123456789ABCu) ||
        !check(0x2010, 0, UINT64_MAX) || !check(0x2000, 0, 1u) || !check(0x2100, 3, 0x7FFFu)) {
        return 14;
    }
    if (strcmp(sample_values.manufacturer_device_name, "canola sample") != 0 ||
        sample_values.temperature_degc != 21.5f || sample_values.key_bytes[2] != 0xABu) {
        return 15;
    }
    const co_od_entry_t *e = co_od_find(&sample_od, 0x2001, 0, NULL);
    uint8_t high = 101;
    uint8_t ok = 100;
    if (e == NULL || co_od_check(&sample_od, e, &high, 1) != CO_ABORT_VALUE_HIGH ||
        co_od_check(&sample_od, e, &ok, 1) != CO_ABORT_NONE) {
        return 16;
    }
    uint8_t log[4] = {1, 2, 3, 4};
    e = co_od_find(&sample_od, 0x2200, 0, NULL);
    if (e == NULL || co_od_write(&sample_od, e, log, 4) != CO_ABORT_NONE ||
        sample_values.log_data.len != 4) {
        return 17;
    }
#if CO_CONFIG_OD_HASH
    /* The generated hash is the one the core builds (same function, same order). */
    static uint16_t slots[1u << 16];
    co_od_t rebuilt = sample_od;
    if (sample_od.hash == NULL ||
        co_od_hash_build(&rebuilt, slots, co_od_hash_bits(sample_od.count)) != CO_OK ||
        rebuilt.hash_mask != sample_od.hash_mask ||
        memcmp(slots, sample_od.hash, sizeof slots[0] * (sample_od.hash_mask + 1u)) != 0) {
        return 18;
    }
#else
    /* A core that reads no hash: the dictionary has none. */
    if (sample_od.hash != NULL) {
        return 19;
    }
#endif
#if !CO_CONFIG_OD_COMPACT
    if (sample_od.keys == NULL) {
        return 19; /* the general form's dense keys */
    }
#endif
#if CO_CONFIG_OD_COMPACT
    /* The compact form: entries of 6 bytes, values at offsets into sample_values, type and
     * attributes from a shared row, sizes from the type or the side table, the power-on
     * values' image. */
    if (sizeof(co_od_entry_t) != 6u || sample_od.tables == NULL ||
        sample_od.tables->defaults == NULL) {
        return 20;
    }
    e = co_od_find(&sample_od, 0x1008, 0, NULL);
    if (e == NULL || co_od_value(&sample_od, e) != (void *)sample_values.manufacturer_device_name ||
        co_od_size(&sample_od, e) != sizeof sample_values.manufacturer_device_name) {
        return 21;
    }
    e = co_od_find(&sample_od, 0x1017, 0, NULL);
    if (e == NULL || co_od_value(&sample_od, e) != (void *)&sample_values.producer_heartbeat_time ||
        co_od_size(&sample_od, e) != 2u || co_od_type(&sample_od, e) != CO_TYPE_UNSIGNED16 ||
        co_od_attr(&sample_od, e) != CO_OD_RW) {
        return 22;
    }
#endif
    return 0;
}
"""


# -O0 and -Os (a build for size: the inlining choices of build.h), each in every form of
# the dictionary (canola/od.h).
@pytest.mark.parametrize("form", FORMS)
@pytest.mark.parametrize("optimise", ["-O0", "-Os"])
@pytest.mark.slow
def test_sample_links_with_the_core_and_runs(tmp_path: Path, optimise: str,
                                             form: tuple[str, ...]) -> None:
    cc = compiler()
    if not CORE_SOURCES:
        pytest.skip("no core sources")
    _, code = generate_sample(tmp_path, domain_size=32)
    main_c = tmp_path / "main.c"
    main_c.write_text(TEST_MAIN)
    objects = []
    for src in CORE_SOURCES:  # the core's own warnings are the C build's business
        obj = tmp_path / f"core_{src.stem}.o"
        result = subprocess.run([cc, "-std=c11", optimise, *form, f"-I{INCLUDE}", "-c", str(src),
                                 "-o", str(obj)], capture_output=True, text=True, check=False)
        assert result.returncode == 0, f"core source {src.name}: {result.stderr[:300]}"
        objects.append(str(obj))
    for src in (code, main_c):
        result = compile_c(cc, src, tmp_path, (optimise, *form))
        assert result.returncode == 0, result.stderr
        objects.append(str(tmp_path / (src.stem + ".o")))
    exe = tmp_path / "sample_test"
    result = subprocess.run([cc, *objects, "-o", str(exe)], capture_output=True, text=True,
                            check=False)
    assert result.returncode == 0, result.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, check=False, timeout=300)
    assert run.returncode == 0, f"test program failed with {run.returncode}"


# A core that does not validate its dictionary (CO_CONFIG_OD_VALIDATE 0, the size profiles)
# refuses a generated one using a feature it leaves out when compiling it instead.
@pytest.mark.parametrize("left_out", [
    ("-DCO_CONFIG_OD_LIMITS=0", "-DCO_CONFIG_REAL_LIMITS=0"), ("-DCO_CONFIG_REAL_LIMITS=0",),
    ("-DCO_CONFIG_OD_DOMAIN=0",), ("-DCO_CONFIG_OD_64BIT=0",)])
@pytest.mark.parametrize("form", FORMS)
def test_unvalidated_core_refuses_left_out_features_when_compiling(
        tmp_path: Path, left_out: tuple[str, ...], form: tuple[str, ...]) -> None:
    cc = compiler()
    _, code = generate_sample(tmp_path, domain_size=32)
    trusted = ("-DCO_CONFIG_OD_VALIDATE=0", *form)
    assert compile_c(cc, code, tmp_path, trusted).returncode == 0
    result = compile_c(cc, code, tmp_path, (*trusted, *left_out))
    assert result.returncode != 0
    assert f"({left_out[0][2:-2]} 0)" in result.stderr, result.stderr
    validated = compile_c(cc, code, tmp_path, (*form, *left_out))  # co_od_validate refuses it
    assert validated.returncode == 0, validated.stderr


def test_unvalidated_core_refuses_unicode_strings_when_compiling(tmp_path: Path) -> None:
    text = HEADER + ("[2000]\nParameterName=U\nObjectType=0x7\nDataType=0x000B\n"
                     "AccessType=rw\nDefaultValue=ab\n")
    source = tmp_path / "u.eds"
    source.write_text(text)
    _, code = odgen.generate_files(source, "u", tmp_path)
    cc = compiler()
    flags = ("-DCO_CONFIG_OD_VALIDATE=0", "-DCO_CONFIG_OD_COMPACT=1")
    assert compile_c(cc, code, tmp_path, flags).returncode == 0
    result = compile_c(cc, code, tmp_path, (*flags, "-DCO_CONFIG_OD_UNICODE=0"))
    assert "(CO_CONFIG_OD_UNICODE 0)" in result.stderr, result.stderr


# A configuration whose node would refuse the dictionary at start (co_node_init:
# CO_ERR_CONFIG) is refused when compiling it: here more heartbeat consumer entries (0x1016)
# than CO_HB_CONSUMERS_MAX (issue 30: the default set's 4 against its profile's 8).
def test_too_few_heartbeat_consumers_refused_when_compiling(tmp_path: Path) -> None:
    subs = "".join(f"[1016sub{i}]\nParameterName=C{i}\nObjectType=0x7\nDataType=0x0007\n"
                   f"AccessType=rw\nDefaultValue=0\n\n" for i in range(1, 4))
    text = HEADER + ("[1016]\nParameterName=Consumers\nObjectType=0x8\nSubNumber=4\n\n"
                     "[1016sub0]\nParameterName=N\nObjectType=0x7\nDataType=0x0005\n"
                     "AccessType=ro\nDefaultValue=3\n\n" + subs)
    source = tmp_path / "hb.eds"
    source.write_text(text)
    _, code = odgen.generate_files(source, "hb", tmp_path)
    cc = compiler()
    for allowed, ok in (("3", True), ("127", True), ("0", True), ("2", False)):
        result = compile_c(cc, code, tmp_path, (f"-DCO_HB_CONSUMERS_MAX={allowed}",))
        assert (result.returncode == 0) == ok, (allowed, result.stderr)
        if not ok:
            assert "0x1016 has 3 heartbeat consumer entries" in result.stderr, result.stderr


# --- errors -------------------------------------------------------------------------------

HEADER = """[FileInfo]
FileName=bad.eds
EDSVersion=4.0

[DeviceInfo]
VendorNumber=1

"""


def bad_var(data_type: str, default: str, access: str = "rw") -> str:
    return HEADER + (f"[2000]\nParameterName=X\nObjectType=0x7\nDataType={data_type}\n"
                     f"AccessType={access}\nDefaultValue={default}\nPDOMapping=0\n")


@pytest.mark.parametrize(("text", "reason"), [
    (bad_var("0x0007", "0x100000000"), "outside the range of UNSIGNED32"),
    (bad_var("0x0002", "abc"), "not a number of type INTEGER8"),
    (bad_var("0x0020", "0"), "not supported by the canola core"),
    (bad_var("0x0007", "0", access="rx"), "AccessType"),
    (bad_var("0x0008", "$NODEID+1"), "$NODEID is not supported"),
    (bad_var("0x000A", "0x123"), "not pairs of hex digits"),
    (bad_var("0x0001", "2"), "outside the range of BOOLEAN"),
])
def test_bad_values_raise_eds_error_with_place(text: str, reason: str) -> None:
    od = eds.parse(text, filename="bad.eds")
    with pytest.raises(EdsError) as info:
        odgen.generate(od, "bad")
    assert info.value.file == "bad.eds"
    assert info.value.line == 8
    assert info.value.section == "2000"
    assert reason in str(info.value)
    assert str(info.value).startswith("bad.eds:8: [2000]")


# --- command line ---------------------------------------------------------------------


def run_cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "canola.odgen", *args], capture_output=True,
                          text=True, check=False, cwd=HERE)


def test_cli_writes_files(tmp_path: Path) -> None:
    result = run_cli(str(SAMPLE), "--name", "sample", "--out-dir", str(tmp_path))
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "sample.h").read_bytes() == (GOLDEN / "sample.h").read_bytes()
    result = run_cli(str(SAMPLE), "--name", "dev", "--out-dir", str(tmp_path), "--node-id",
                     "0x10")
    assert result.returncode == 0, result.stderr
    assert "#define DEV_NODE_ID 16u" in (tmp_path / "dev.h").read_text()


@pytest.mark.parametrize("args", [
    ["--name", "sample"],
    ["--name", "1bad", "--out-dir", "x"],
    ["--name", "ok", "--out-dir", "x", "--node-id", "128"],
    ["--name", "ok", "--out-dir", "x", "--node-id", "abc"],
    ["--name", "ok", "--out-dir", "x", "--bogus"],
])
def test_cli_bad_arguments_exit_2_with_one_line(args: list[str]) -> None:
    result = run_cli(str(SAMPLE), *args)
    assert result.returncode == 2
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert "error:" in result.stderr


def test_cli_eds_error_exits_1(tmp_path: Path) -> None:
    bad = tmp_path / "bad.eds"
    bad.write_text(bad_var("0x0007", "-1"))
    result = run_cli(str(bad), "--name", "bad", "--out-dir", str(tmp_path))
    assert result.returncode == 1
    assert result.stderr.startswith(f"{bad}:8: [2000]"), result.stderr
    assert "Traceback" not in result.stderr


def run_canola(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "canola.cli", *args], capture_output=True,
                          text=True, check=False, cwd=HERE)


def test_canola_odgen_command_names_files_after_the_input(tmp_path: Path) -> None:
    result = run_canola("odgen", str(SAMPLE), "-o", str(tmp_path))
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "sample.c").read_bytes() == (GOLDEN / "sample.c").read_bytes()


@pytest.mark.parametrize("args", [["odgen"], ["odgen", str(SAMPLE)], ["frobnicate"], []])
def test_canola_command_bad_arguments_exit_2_with_one_line(args: list[str]) -> None:
    result = run_canola(*args)
    assert result.returncode == 2
    out = (result.stderr or result.stdout).strip()
    assert len(out.splitlines()) == 1, out


def test_generated_header_refuses_another_dictionary_format(tmp_path: Path) -> None:
    cc = compiler()
    generate_sample(tmp_path)
    probe = tmp_path / "probe.c"
    probe.write_text('#include "sample.h"\n')
    ok = compile_c(cc, probe, tmp_path)
    assert ok.returncode == 0, ok.stderr
    other = subprocess.run(
        [cc, *WARNINGS, "-DCO_OD_FORMAT=1", f"-I{INCLUDE}", f"-I{tmp_path}", "-c", str(probe),
         "-o", str(tmp_path / "probe2.o")], capture_output=True, text=True, check=False)
    assert other.returncode != 0
    assert "regenerate it with the odgen of this canola" in other.stderr


# --- corpus of real files ---------------------------------------------------------------


def corpus_files() -> list[Path]:
    if not CORPUS.is_dir():
        return []
    return sorted(p for p in CORPUS.iterdir() if p.suffix.lower() in (".eds", ".dcf"))


@pytest.mark.slow
def test_corpus_generates_and_compiles_or_fails_with_place(tmp_path: Path) -> None:
    files = corpus_files()
    if not files:
        pytest.skip(f"no corpus at {CORPUS}")
    cc = compiler()
    compiled: list[str] = []
    refused: list[str] = []
    for n, path in enumerate(files):
        try:
            od = eds.parse(path)
        except EdsError:
            continue  # canola.eds itself refuses it (tested in test_eds.py)
        out = tmp_path / f"f{n}"
        try:
            header, code = odgen.generate(od, "od", odgen.GenerateOptions(domain_size=16))
        except EdsError as exc:
            assert str(exc).startswith(f"{path}:"), str(exc)
            assert exc.line is not None, str(exc)
            refused.append(f"{path.name}: {exc.reason}")
            continue
        out.mkdir()
        (out / "od.h").write_text(header)
        (out / "od.c").write_text(code)
        for form in FORMS:  # (a master's 0x1016 has up to 127 entries: a node that takes them)
            result = compile_c(cc, out / "od.c", out, (*form, "-DCO_HB_CONSUMERS_MAX=127"))
            assert result.returncode == 0, f"{path.name} {form}:\n{result.stderr[:2000]}"
        compiled.append(path.name)
    print(f"\nodgen corpus: {len(compiled)} generated and compiled, {len(refused)} refused")
    for line in refused:
        print("  refused", line)
    assert compiled


def _validating_main(names: list[str]) -> str:
    """A program that runs co_od_validate over each generated dictionary, then resets it."""
    lines = [f'#include "{n}.h"' for n in names] + ["", "#include <stdio.h>", "",
                                                  "int main(void)", "{", "    uint32_t bad = 0;"]
    for n in names:
        lines += [f"    if (co_od_validate(&{n}_od, &bad) != CO_OK) {{",
                  f'        printf("{n}: entry %u refused\\n", (unsigned)bad);',
                  "        return 1;", "    }",
                  f"    co_od_reset(&{n}_od, 0x0000, 0xFFFF, 1);"]
    return "\n".join([*lines, "    return 0;", "}", ""])


@pytest.mark.slow
def test_every_generated_dictionary_passes_co_od_validate(tmp_path: Path) -> None:
    """A core built for size trusts its dictionary (CO_CONFIG_OD_VALIDATE 0): whatever the
    generator writes must pass co_od_validate of a core that checks, in both forms, as a
    build for size and with the look-up tables: the sample, the size rows' EDS and every
    file of the corpus the generator takes."""
    cc = compiler()
    if not CORE_SOURCES:
        pytest.skip("no core sources")
    sources = [(SAMPLE, odgen.GenerateOptions(domain_size=32)),
               (BENCH_EDS, odgen.GenerateOptions())]
    sources += [(p, odgen.GenerateOptions(domain_size=16)) for p in corpus_files()]
    names = []
    for n, (path, options) in enumerate(sources):
        try:
            header, code = odgen.generate(eds.parse(path), f"d{n}", options)
        except EdsError:
            continue  # refused with its place (test_corpus_generates_...)
        (tmp_path / f"d{n}.h").write_text(header)
        (tmp_path / f"d{n}.c").write_text(code)
        names.append(f"d{n}")
    main_c = tmp_path / "main.c"
    main_c.write_text(_validating_main(names))
    for form in FORMS:
        for optimise in ("-O0", "-Os"):
            # (a master's 0x1016 has up to 127 entries: a node that takes them)
            flags = (optimise, *form, "-DCO_HB_CONSUMERS_MAX=127")
            build = tmp_path / ("build" + "".join(flags))
            build.mkdir()
            objects = []
            for src in [*CORE_SOURCES, *(tmp_path / f"{n}.c" for n in names), main_c]:
                result = subprocess.run([cc, "-std=c11", *flags, f"-I{INCLUDE}", f"-I{tmp_path}",
                                         "-c", str(src), "-o", str(build / f"{src.stem}.o")],
                                        capture_output=True, text=True, check=False)
                assert result.returncode == 0, f"{src.name} {flags}: {result.stderr[:500]}"
                objects.append(str(build / f"{src.stem}.o"))
            exe = build / "validate"
            result = subprocess.run([cc, *objects, "-o", str(exe)], capture_output=True,
                                    text=True, check=False)
            assert result.returncode == 0, result.stderr
            run = subprocess.run([str(exe)], capture_output=True, text=True, check=False,
                                 timeout=300)
            assert run.returncode == 0, f"{flags}: {run.stdout}"
    assert len(names) > 2 or not corpus_files()


# --- the size rows' dictionary (bench/run) ------------------------------------------------

BENCH_EDS = REPO / "bench" / "ds301_objects.eds"
CANOPENNODE_PROFILE = REPO / ".." / "shared" / "reference" / "footprint" / "DS301_profile.eds"


def test_bench_eds_and_size_firmware_compile_cleanly(tmp_path: Path) -> None:
    """bench/run links bench/size_firmware.c with the dictionary of bench/ds301_objects.eds
    (for Cortex-M, where it does not ask for warnings): both are clean C."""
    assert eds.parse(BENCH_EDS).warnings == []
    cc = compiler()
    _, code = odgen.generate_files(BENCH_EDS, "ds301", tmp_path)
    firmware = REPO / "bench" / "size_firmware.c"
    for form in FORMS:
        for source, flags in ((code, ()), (firmware, (f"-I{tmp_path}", f"-I{REPO / 'src'}"))):
            r = compile_c(cc, source, tmp_path, (*flags, *form))
            assert r.returncode == 0, f"{source.name} {form}:\n{r.stderr}"


def test_bench_eds_gives_the_dictionary_of_canopennodes_profile() -> None:
    """The size rows count the dictionary of CANopenNode's example profile; where it is absent
    they use bench/ds301_objects.eds, which must give the same generated code."""
    if not CANOPENNODE_PROFILE.is_file():
        pytest.skip(f"no CANopenNode profile at {CANOPENNODE_PROFILE}")
    ours = odgen.generate(eds.parse(BENCH_EDS), "ds301")
    theirs = odgen.generate(eds.parse(CANOPENNODE_PROFILE), "ds301")
    for a, b in zip(ours, theirs, strict=True):
        assert a.split("\n", 1)[1] == b.split("\n", 1)[1]  # line 1 names the EDS file
