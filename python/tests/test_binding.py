# SPDX-License-Identifier: Apache-2.0
"""The binding boundary: one typed door to the compiled module."""

from __future__ import annotations

import ast
import gc
from pathlib import Path

import can
import pytest

import canola
from canola import Device, _build_core
from canola._c import lib
from canola.core import SimBus
from canola.errors import Error
from canola.formats import eds

PACKAGE = Path(canola.__file__).parent
SAMPLE = Path(__file__).parent / "golden" / "sample.eds"


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


def _live_after_gc() -> int:
    gc.collect()
    return int(lib.canola_py_live_allocs())


def test_a_node_the_bus_object_has_no_room_for_leaks_nothing() -> None:
    """A python-can bus object holds 128 canola nodes: the 129th is refused with a clear
    error, and what its creation allocated in C is freed (the glue's live-block count)."""
    bus = can.Bus(interface="virtual", channel="binding-full", receive_own_messages=False)
    try:
        model = eds.parse(SAMPLE)
        nodes = [Device(model, n % 127 + 1, bus) for n in range(128)]
        before = _live_after_gc()
        for _ in range(3):
            with pytest.raises(Error, match="at most 128 canola nodes"):
                Device(model, 5, bus)
        assert _live_after_gc() == before
        del nodes
    finally:
        bus.shutdown()


def test_a_simulated_bus_and_its_nodes_leave_nothing_behind() -> None:
    model = eds.parse(SAMPLE)
    before = _live_after_gc()
    for _ in range(3):
        bus = SimBus()
        device = Device(model, 2, bus)
        device.start()
        bus.run_for(1000)
        del bus, device
    assert _live_after_gc() == before
