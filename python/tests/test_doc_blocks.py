# SPDX-License-Identifier: Apache-2.0
"""The manual's blocks work as written: README.md, CONTRIBUTING.md and every page of docs/.

Each page is one session (docsession.py): its ``sh``, ``console`` and ``python`` blocks
run in their order in a folder of their own, against the software bus and devices the
page starts itself; what docsession.py says is run, is run, and what it says is checked,
is checked:

- ``sh`` and ``console`` blocks: every line is run or checked by its program's rule; a
  ``console`` block's shown output must appear in what the command printed, line by line
  in order (``...`` for any text), ports as the page shows them;
- ``python`` blocks: run as programs (docshim.py swaps a real interface for python-can's
  virtual bus); a ``text`` block right after one is its output, compared the same way;
- ``c`` blocks that start with ``#include`` (and are not marked ``not run``): compiled
  (``cc -fsyntax-only``, C11, every warning an error) against include/, port/linux/,
  examples/ (the example dictionary) and ``drive.h``, the dictionary ``canola odgen``
  makes of examples/eds/drive.eds; the other C blocks are fragments of a page's text and
  only read;
- ``yaml`` blocks: parsed; one with ``nodes`` is a network description and must be one
  :mod:`canola.boot_plan` accepts, the files it names found in ``examples/eds/``;
- ``cmake``, ``text`` and unmarked blocks are read, not run;
- an ``sh`` or ``python`` block the page marks ``<!-- not run: WHY -->`` (a reader's own
  device, a host elsewhere) is checked without running (``Session.check``, in ``make
  check``): its python compiles, its ``canola`` lines are ones the CLI's parser takes,
  its other lines pass the checking rules (make, cmake, cc, pip, the fuzzers).

A block of another language fails (``bash`` would be run by nobody), and so does a line no
rule knows, at once (``test_every_line_has_a_rule``, in ``make check``) rather than when
its page runs.
"""

from __future__ import annotations

import shutil
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml
from docblocks import ROOT, Block, blocks, page_name, pages
from docsession import RULES, Session

from canola import boot_plan
from canola.formats import odgen

LANGUAGES = {"sh", "console", "python", "c", "cmake", "yaml", "text", ""}
RUN = ("sh", "console", "python")


def _runnable_pages() -> list[Path]:
    return [p for p in pages() if any(b.lang in RUN for b in blocks(p))]


def _all_blocks() -> Iterator[Block]:
    for page in pages():
        yield from blocks(page)


def test_every_block_is_of_a_known_kind() -> None:
    odd = [f"{b.where}: ```{b.lang}" for b in _all_blocks() if b.lang not in LANGUAGES]
    assert odd == [], f"blocks of a kind no test knows ({sorted(LANGUAGES)}): {odd}"


def test_every_line_has_a_rule() -> None:
    unknown = []
    for block in _all_blocks():
        for step in block.steps:
            words = step.words()
            while words and "=" in words[0] and words[0].split("=")[0].isupper():
                words.pop(0)  # NAME=VALUE before the program
            program = words[0] if words else ""
            if program not in RULES and not program.startswith("build-fuzz/"):
                unknown.append(f"{block.where} line {step.line}: {step.command}")
    assert unknown == [], "lines no rule runs or checks (docsession.RULES):\n" + "\n".join(
        unknown)


def test_console_blocks_show_commands() -> None:
    """A console block is commands and what they print: one without a command shows
    nothing runnable (make it ``text``)."""
    empty = [b.where for b in _all_blocks() if b.lang == "console" and not b.steps]
    assert empty == []


@pytest.mark.parametrize("block", [b for b in _all_blocks()
                                   if b.not_run is not None and b.lang in RUN],
                         ids=lambda b: b.where)
def test_not_run_block_checks(block: Block, tmp_path: Path) -> None:
    Session(tmp_path).check(block)


def test_a_not_run_line_the_cli_refuses_fails(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text("<!-- not run: a device of yours -->\n```sh\n"
                    "canola sdo read 5 0x1018:1 --iface can0 --no-such-option\n```\n")
    (block,) = blocks(page)
    (tmp_path / "s").mkdir()
    with pytest.raises(AssertionError, match="refuses"):
        Session(tmp_path / "s").check(block)


@pytest.mark.slow
@pytest.mark.realtime  # processes: hubs, devices, the commands
@pytest.mark.parametrize("page", _runnable_pages(), ids=page_name)
def test_page_runs_as_written(page: Path, tmp_path: Path) -> None:
    session = Session(tmp_path)
    ran = []
    try:
        for block in blocks(page):
            if block.lang in RUN:
                session.run(block)
                ran.append(block.where)
    finally:
        session.close()
    assert ran, f"{page_name(page)}: nothing ran"


def _c_blocks() -> list[Block]:
    return [b for b in _all_blocks() if b.lang == "c" and b.text.startswith("#include")
            and b.not_run is None]


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")
@pytest.mark.parametrize("block", _c_blocks(), ids=lambda b: b.where)
def test_c_block_compiles(block: Block, tmp_path: Path) -> None:
    assert odgen.main([str(ROOT / "examples" / "eds" / "drive.eds"), "-o",
                       str(tmp_path / "od")]) == 0
    source = tmp_path / "block.c"
    source.write_text(block.text, encoding="utf-8")
    done = subprocess.run(["cc", "-std=c11", "-Wall", "-Wextra", "-Werror", "-fsyntax-only",
                           f"-I{ROOT / 'include'}", f"-I{ROOT / 'examples'}",
                           f"-I{ROOT / 'port' / 'linux'}", f"-I{tmp_path / 'od'}",
                           str(source)],
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, f"{block.where}:\n{done.stderr}"


def test_yaml_blocks_parse() -> None:
    checked = 0
    for block in _all_blocks():
        if block.lang != "yaml":
            continue
        data = yaml.safe_load(block.text)
        if isinstance(data, dict) and "nodes" in data:
            boot_plan.load_yaml(block.text, block.where, base=ROOT / "examples" / "eds")
        checked += 1
    assert checked, "no yaml block on any page"
