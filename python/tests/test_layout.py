# SPDX-License-Identifier: Apache-2.0
"""The parts built on a node never reach into it: no ``master._x`` / ``device._x`` /
``_owner._x`` anywhere in the package, and the engine (``._engine``) is used only by the
modules that make up the node (_engine.py, _nodebase.py, _channels.py). A part is handed
what it needs (SdoChannels, LocalOd(engine, types), the Lss, the manager), and a user of a
node locks it through the public NodeBase.locked()."""

from __future__ import annotations

import re
from pathlib import Path

PACKAGE = Path(__file__).parent.parent / "src" / "canola"
NODE_MODULES = {"_engine.py", "_nodebase.py", "_channels.py"}
REACH_IN = re.compile(r"\b(master|device|_owner)\._[a-z]")
ENGINE = re.compile(r"(?<!canola)\._engine\b")  # canola._engine: the module's name


def _offences(pattern: re.Pattern[str], skip: set[str]) -> list[str]:
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.name in skip and path.parent == PACKAGE:
            continue
        for number, line in enumerate(path.read_text().splitlines(), 1):
            if pattern.search(line):
                found.append(f"{path.relative_to(PACKAGE)}:{number}: {line.strip()}")
    return found


def test_no_part_reaches_into_a_node() -> None:
    assert _offences(REACH_IN, set()) == []


def test_the_engine_stays_inside_the_node() -> None:
    assert _offences(ENGINE, NODE_MODULES) == []


def test_the_patterns_catch_what_they_are_for() -> None:
    assert REACH_IN.search("with self.master._engine.locked() as node:")
    assert REACH_IN.search("self._owner._types.get(key)")
    assert ENGINE.search("engine = device._engine")
    assert not ENGINE.search("from canola._engine import Frame")


def test_the_binding_uses_the_public_c_api() -> None:
    """port/python includes canola's public headers only, never the core's own (src/)."""
    port = PACKAGE.parent.parent.parent / "port" / "python"
    core_headers = {p.name for p in (port.parent.parent / "src").glob("*.h")}
    for path in sorted(port.glob("*.[ch]")):
        included = re.findall(r'#include "([^"]+)"', path.read_text())
        assert not core_headers & set(included), path.name
