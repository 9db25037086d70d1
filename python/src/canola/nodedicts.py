# SPDX-License-Identifier: Apache-2.0
"""The dictionaries of the nodes on a bus, from ``--eds FILE`` (every node) and
``--eds N=FILE`` (node N) as the ``canola`` commands take them.

    dicts = NodeDictionaries(["drive.eds", "5=io.dcf"])
    dicts.get(5)    # io.dcf, its $NODEID evaluated for node 5
    dicts.get(7)    # drive.eds for node 7; None without a file for every node

Each file is read once per node (``$NODEID`` differs per node), when first needed; a file
that cannot be read raises :class:`~canola.errors.EdsError` naming file and line.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from canola.errors import Error
from canola.formats import eds

__all__ = ["NodeDictionaries", "parse_spec"]


def parse_spec(text: str) -> tuple[int | None, str]:
    """``FILE`` or ``N=FILE`` as (node-ID or None, file). Raises Error for a bad node-ID."""
    head, eq, tail = text.partition("=")
    if eq and head.strip().isdigit():
        node = int(head)
        if not 1 <= node <= 127 or not tail:
            raise Error(f"bad dictionary {text!r}: FILE or N=FILE with N 1..127")
        return node, tail
    return None, text


class NodeDictionaries:
    def __init__(self, specs: Iterable[str] = ()) -> None:
        self.every: str | None = None
        self.per_node: dict[int, str] = {}
        for spec in specs:
            node, file = parse_spec(spec)
            if node is None:
                if self.every is not None:
                    raise Error(f"two dictionaries for every node: {self.every} and {file} "
                                "(name a node: N=FILE)")
                self.every = file
            else:
                self.per_node[node] = file
        self._parsed: dict[int, eds.ObjectDictionary] = {}

    def __bool__(self) -> bool:
        return self.every is not None or bool(self.per_node)

    def file(self, node: int) -> str | None:
        """The file that describes ``node``, or None."""
        return self.per_node.get(node, self.every)

    def get(self, node: int) -> eds.ObjectDictionary | None:
        """The dictionary of ``node`` (parsed for its node-ID), or None."""
        if node not in self._parsed:
            file = self.file(node)
            if file is None:
                return None
            self._parsed[node] = eds.parse(Path(file), node_id=node)
        return self._parsed[node]

    def check(self) -> None:
        """Read every file now (for one node each), so that a bad one fails at the start."""
        for node in sorted(self.per_node):
            self.get(node)
        if self.every is not None:
            eds.parse(Path(self.every), node_id=1)
