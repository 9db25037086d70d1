"""The binding boundary: one typed door to the compiled module."""

from __future__ import annotations

import ast
from pathlib import Path

import canola
from canola import _build_core

PACKAGE = Path(canola.__file__).parent


def test_only_the_door_imports_the_compiled_module() -> None:
    importers: set[str] = set()
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            names = ([node.module or ""] if isinstance(node, ast.ImportFrom)
                     else [a.name for a in node.names] if isinstance(node, ast.Import) else [])
            if any(n == "canola._core" or n.startswith("canola._core.") for n in names):
                importers.add(path.relative_to(PACKAGE).as_posix())
    assert importers == {"_c.py"}


def test_the_typed_view_is_the_cdef() -> None:
    # _core.pyi is what mypy checks the calls into C against: it must say what the CDEF says
    assert (PACKAGE / "_core.pyi").read_text() == _build_core.stub_text()
    assert "    def co_node_poll(self, a0: CData, a1: int, /) -> int: ..." in \
        _build_core.stub_text()
