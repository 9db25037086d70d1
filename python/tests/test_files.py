# SPDX-License-Identifier: Apache-2.0
"""The files the tools read and write (canola.files): a symlink planted where a tool writes
does not redirect the write; what is not a regular file, or is larger than 64 MiB, is refused
with one line before it is read; a file of repeated keys costs memory in proportion to its
size."""

from __future__ import annotations

import os
import stat
import threading
import tracemalloc
from pathlib import Path

import pytest
from cli_helpers import cli, one_line_error
from test_eds import make

from canola import EdsError
from canola.cli.device_cmd import _store_folder
from canola.files import EDS_MAX_BYTES, FileError, read_file, write_file
from canola.formats import eds

Capsys = pytest.CaptureFixture[str]
EDS = Path(__file__).parent / "data" / "cli_device.eds"


# ---- writing


def _plant(tmp_path: Path, name: str) -> Path:
    """A victim file and a symlink to it at ``name``: the write must not reach it."""
    victim = tmp_path / "victim"
    victim.write_text("precious\n")
    (tmp_path / name).symlink_to(victim)
    return victim


def test_a_symlink_at_the_old_temporary_name_is_not_followed(capsys: Capsys,
                                                             tmp_path: Path) -> None:
    victim = _plant(tmp_path, "out.dcf.part")
    out = tmp_path / "out.dcf"
    code, _, err = cli(capsys, "eds", "dcf", str(EDS), "--node-id", "5", "-o", str(out))
    assert (code, err) == (0, "")
    assert victim.read_text() == "precious\n"
    assert "[DeviceComissioning]" in out.read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.dcf", "out.dcf.part", "victim"]


def test_a_symlink_at_the_target_is_replaced_not_followed(capsys: Capsys,
                                                          tmp_path: Path) -> None:
    victim = _plant(tmp_path, "out.dcf")
    out = tmp_path / "out.dcf"
    code, _, err = cli(capsys, "eds", "dcf", str(EDS), "--node-id", "5", "-o", str(out))
    assert (code, err) == (0, "")
    assert victim.read_text() == "precious\n"
    assert not out.is_symlink() and "[DeviceComissioning]" in out.read_text()


def test_odgen_writes_through_the_same_door_and_says_what_it_wrote(capsys: Capsys,
                                                                   tmp_path: Path) -> None:
    victim = _plant(tmp_path, "dev.h")
    code, out, err = cli(capsys, "odgen", str(EDS), "--name", "dev", "-o", str(tmp_path))
    assert (code, err) == (0, "")
    assert out == f"canola odgen: wrote {tmp_path / 'dev.h'} and {tmp_path / 'dev.c'} " \
                  f"from {EDS}\n"
    assert victim.read_text() == "precious\n"
    assert "dev_od" in (tmp_path / "dev.h").read_text()


def test_write_file_keeps_the_mode_and_leaves_nothing_behind(tmp_path: Path) -> None:
    target = tmp_path / "f"
    target.write_text("old")
    target.chmod(0o640)
    write_file(target, "new")
    assert target.read_text() == "new" and stat.S_IMODE(target.stat().st_mode) == 0o640
    assert os.listdir(tmp_path) == ["f"]
    with pytest.raises(FileError, match=r"/nowhere/f: cannot write: No such file"):
        write_file(tmp_path / "nowhere" / "f", b"x")
    (tmp_path / "dir").mkdir()
    with pytest.raises(FileError, match="cannot write"):  # a folder at the target
        write_file(tmp_path / "dir", b"x")
    assert sorted(os.listdir(tmp_path)) == ["dir", "f"]


def test_the_cli_reports_a_failed_write_in_one_line(capsys: Capsys, tmp_path: Path) -> None:
    code, _, err = cli(capsys, "eds", "dcf", str(EDS), "--node-id", "5", "-o",
                       str(tmp_path / "no" / "x.dcf"))
    assert code == 1 and "x.dcf: cannot write: No such file or directory" in err
    one_line_error(err)


# ---- reading


def _fifo(tmp_path: Path) -> Path:
    fifo = tmp_path / "pipe.eds"
    os.mkfifo(fifo)
    return fifo


@pytest.mark.parametrize(("make_path", "kind"), [
    (lambda tmp: Path("/dev/zero"), "a character device"),
    (lambda tmp: Path("/dev/urandom"), "a character device"),
    (_fifo, "a FIFO"),
    (lambda tmp: tmp, "a folder"),
], ids=["dev-zero", "dev-urandom", "fifo", "folder"])
def test_what_is_not_a_regular_file_is_refused_at_once(capsys: Capsys, tmp_path: Path,
                                                       make_path: object, kind: str) -> None:
    path = make_path(tmp_path)  # type: ignore[operator]
    done: list[BaseException] = []

    def parse() -> None:
        try:
            eds.parse(path)
        except BaseException as exc:  # handed to the test's thread
            done.append(exc)

    thread = threading.Thread(target=parse, daemon=True)
    thread.start()
    thread.join(30)  # a FIFO without a writer blocked the old reader for ever
    assert not thread.is_alive(), f"eds.parse({path}) still reading"
    assert isinstance(done[0], EdsError)
    assert str(done[0]) == f"{path}: not a regular file ({kind})"
    code, out, _ = cli(capsys, "eds", "check", str(path))
    assert code == 1 and out == f"{path}: error: not a regular file ({kind})\n"


def test_a_file_over_the_limit_is_refused_unread(tmp_path: Path) -> None:
    big = tmp_path / "big.eds"
    with open(big, "wb") as out:
        out.truncate(EDS_MAX_BYTES + 1)  # sparse: no disk, no time
    with pytest.raises(EdsError) as info:
        eds.parse(big)
    assert str(info.value) == f"{big}: larger than 64 MiB, the most canola reads"
    assert len(read_file(EDS, EDS_MAX_BYTES)) == EDS.stat().st_size
    with pytest.raises(EdsError, match="larger than 64 MiB"):
        eds.parse(b" " * (EDS_MAX_BYTES + 1))


@pytest.mark.slow
def test_memory_is_a_small_multiple_of_the_file(tmp_path: Path) -> None:
    """8 MB of one key repeated reached ~800 MB (every duplicate kept, and its warning);
    now duplicates beyond a few per section are counted."""
    text = make() + "[2000]\n" + "ParameterName=x\n" * (8_000_000 // 16)
    path = tmp_path / "dup.eds"
    path.write_text(text)
    tracemalloc.start()
    try:
        od = eds.parse(path)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert len(od.warnings) < 100
    assert any("more duplicate keys" in w.message for w in od.warnings)
    assert peak < 6 * len(text), f"peak {peak / 1e6:.0f} MB for {len(text) / 1e6:.0f} MB"


# ---- the tolerant reader: what real files do


def test_comments_after_values_and_headers_are_read_past_with_warnings() -> None:
    """kacanopen's 301.eds writes 'DataType=0x0007 # UNSIGNED32', 'AccessType=rw # ...' and
    '[1003sub01] # repeat until 1003subFE'."""
    text = make().replace("[1000]\nParameterName=Device type\nObjectType=0x7\n"
                          "DataType=0x0007\nAccessType=ro\n",
                          "[1000] # Category: Mandatory\nParameterName=Device type\n"
                          "ObjectType=0x7 # VAR\nDataType=0x0007 # UNSIGNED32\n"
                          "AccessType=ro # read only\n")
    od = eds.parse(text, filename="c.eds")
    var = od[0x1000].subs[0]
    assert (var.data_type, var.access_type, var.default) == (7, "ro", 0x20192)
    assert sorted((w.line, w.key, w.message) for w in od.warnings) == [
        (13, None, "comment after the section header ignored"),
        (15, "ObjectType", "'#' comment after a value"),
        (16, "DataType", "'#' comment after a value"),
        (17, "AccessType", "'#' comment after a value")]
    with pytest.raises(EdsError) as info:
        eds.parse(text, filename="c.eds", strict=True)
    assert len(info.value.problems) == 4


def test_text_after_a_section_header_that_is_no_comment_is_an_error() -> None:
    with pytest.raises(EdsError, match=r"t.eds:13: text after the section header: 'x'"):
        eds.parse(make().replace("[1000]\n", "[1000] x\n"), filename="t.eds")


CORPUS = Path(__file__).resolve().parents[2] / ".." / "shared" / "eds-corpus"


@pytest.mark.skipif(not CORPUS.is_dir(), reason=f"no EDS corpus at {CORPUS}")
def test_every_corpus_file_loads() -> None:
    """The two files refused before (kacanopen's 301.eds: '# comments' after values and
    headers; NEMA23_7_23_12.eds: [1008], [1009], [100A], [1017] twice) load with warnings
    naming file and line; strict mode still refuses them."""
    files = sorted(p for p in CORPUS.iterdir() if p.suffix.lower() in (".eds", ".dcf"))
    loaded = [eds.parse(p) for p in files]
    print(f"\n{len(loaded)} of {len(files)} corpus files load")
    for name, what in (("KITmedical__kacanopen__301.eds", "comment after"),
                       ("KITmedical__kacanopen__NEMA23_7_23_12.eds", "section [1008] again")):
        od = loaded[files.index(CORPUS / name)]
        found = [w for w in od.warnings if what in w.message]
        assert found and all(w.file == str(CORPUS / name) and w.line for w in found)
        with pytest.raises(EdsError):
            eds.parse(CORPUS / name, strict=True)


# ---- canola device --store DIR


def _device(capsys: Capsys, store: Path) -> tuple[int, str, str]:
    return cli(capsys, "device", "--eds", str(EDS), "--node-id", "5", "--bus",
               "virtual://store-test", "--store", str(store))


@pytest.mark.parametrize(("setup", "message"), [
    (lambda p: p.write_text("x"), "not a folder"),
    (lambda p: None, "no such folder (nor its parent {parent})"),
], ids=["a-file", "no-parent"])
def test_store_that_cannot_be_a_folder_is_refused_in_one_line(
        capsys: Capsys, tmp_path: Path, setup: object, message: str) -> None:
    store = tmp_path / "store" if "parent" not in message else tmp_path / "a" / "store"
    setup(store)  # type: ignore[operator]
    code, _, err = _device(capsys, store)
    assert code == 1 and err.endswith(
        f"--store {store}: {message.format(parent=store.parent)}\n"), err
    one_line_error(err)


def test_a_missing_store_folder_is_made_when_its_parent_exists(tmp_path: Path) -> None:
    """canola device --store /var/lib/drive works when /var/lib exists (the README's
    example runs as it is, the device making drive-store in the current folder)."""
    store = tmp_path / "drive"
    _store_folder(str(store))
    assert store.is_dir()
    _store_folder(str(store))  # there now: used as it is


def test_a_store_folder_without_permission_is_refused(capsys: Capsys, tmp_path: Path) -> None:
    """A folder this user may not write in: a 0500 folder, or for root (who may write in
    any folder of a normal file system) /proc/1, which nobody may write in."""
    store = tmp_path / "locked"
    store.mkdir(mode=0o500)
    if os.geteuid() == 0:
        store = Path("/proc/1")
    code, _, err = _device(capsys, store)
    assert code == 1 and err.endswith(
        f"--store {store}: no permission to read and write in the folder\n"), err
    one_line_error(err)
