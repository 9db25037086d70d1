#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The file-level call graph of the core, read from its object files.

A file calls another when its object file has an undefined symbol the other defines (a call,
or a function or data address taken: both are a dependency). The largest group of files that
reach each other through such calls (the largest strongly connected component) is the knot
the core's structure should keep small: docs/architecture.md names the one it allows.

    tools/core_graph.py build/libcanola.a            the largest group, its files and links
    tools/core_graph.py --edges build/libcanola.a    every link of it, with the symbols
    tools/core_graph.py --max-files 8 build/libcanola.a   exit 1 when the group is larger
    tools/core_graph.py --headers src --max-header-lines 200 ...   and when a header of src/ is

Arguments are object files or static libraries (nm reads both). Only the standard library
and nm (binutils) are needed.
"""
import argparse
import os
import re
import subprocess
import sys
from collections import defaultdict

# nm -A -P: "lib.a[node.c.o]: symbol T value size" or "node.c.o: symbol U"
LINE = re.compile(r"^(?P<file>.+?): (?P<sym>\S+) (?P<type>[A-Za-z?])")
MEMBER = re.compile(r"\[(?P<member>[^\]]+)\]$")


def unit_name(path):
    """node.c.o, lib.a[node.c.o], node.o -> node.c"""
    m = MEMBER.search(path)
    name = os.path.basename(m.group("member") if m else path)
    for suffix in (".o", ".obj"):
        if name.endswith(suffix):
            name = name[: -len(suffix)]
    return name if name.endswith(".c") else name + ".c"


def read_symbols(paths, nm):
    defined = {}
    undefined = defaultdict(set)
    units = set()
    out = subprocess.run([nm, "-A", "-P", *paths], capture_output=True, text=True, check=True)
    for line in out.stdout.splitlines():
        m = LINE.match(line)
        if not m:
            continue
        unit = unit_name(m.group("file"))
        units.add(unit)
        kind = m.group("type")
        if kind == "U":
            undefined[unit].add(m.group("sym"))
        elif kind.isupper():  # global definitions only: statics do not link across files
            defined[m.group("sym")] = unit
    return units, defined, undefined


def call_graph(units, defined, undefined):
    """edges[a][b] = the symbols of b that a uses"""
    edges = {u: defaultdict(set) for u in units}
    for unit, syms in undefined.items():
        for sym in syms:
            target = defined.get(sym)
            if target is not None and target != unit:
                edges[unit][target].add(sym)
    return edges


def strongly_connected(edges):
    """Tarjan's algorithm (iterative): the components, largest first."""
    index = {}
    low = {}
    stack = []
    on_stack = set()
    components = []
    counter = 0
    for root in sorted(edges):
        if root in index:
            continue
        work = [(root, iter(sorted(edges[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            advanced = False
            for child in children:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(edges[child]))))
                    advanced = True
                    break
                if child in on_stack:
                    low[node] = min(low[node], index[child])
            if advanced:
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    component.append(w)
                    if w == node:
                        break
                components.append(sorted(component))
    components.sort(key=lambda c: (-len(c), c))
    return components


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("objects", nargs="+", help="object files or static libraries")
    ap.add_argument("--nm", default="nm", help="the nm to use (default: nm)")
    ap.add_argument("--edges", action="store_true", help="list the group's links and symbols")
    ap.add_argument("--max-files", type=int, help="fail (exit 1) above this many files")
    ap.add_argument("--headers", help="a folder whose headers (*.h) --max-header-lines checks")
    ap.add_argument("--max-header-lines", type=int, default=200,
                    help="fail (exit 1) when a header of --headers is longer (default 200)")
    args = ap.parse_args()

    units, defined, undefined = read_symbols(args.objects, args.nm)
    if not units:
        print("core_graph: no object files read", file=sys.stderr)
        return 2
    edges = call_graph(units, defined, undefined)
    largest = strongly_connected(edges)[0]
    members = set(largest)
    links = [(a, b) for a in largest for b in sorted(edges[a]) if b in members]
    total = sum(len(edges[a]) for a in units)
    print(f"largest group of files that call each other: {len(largest)} files, "
          f"{len(links)} links between them ({len(units)} files, {total} links in all)")
    print("  " + " ".join(largest))
    if args.edges:
        for a, b in links:
            print(f"  {a} -> {b}: {' '.join(sorted(edges[a][b]))}")
    failed = False
    if args.max_files is not None and len(largest) > args.max_files:
        print(f"core_graph: the group has more than {args.max_files} files", file=sys.stderr)
        failed = True
    if args.headers:
        for name in sorted(os.listdir(args.headers)):
            if name.endswith(".h"):
                with open(os.path.join(args.headers, name)) as f:
                    lines = sum(1 for _ in f)
                if lines > args.max_header_lines:
                    print(f"core_graph: {name} has {lines} lines (more than "
                          f"{args.max_header_lines})", file=sys.stderr)
                    failed = True
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
