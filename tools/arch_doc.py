#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Check that docs/architecture.md tells the truth about the core.

    tools/arch_doc.py docs/architecture.md build/libcanola.a

In the sections up to the Python package's (the names of "Adding a service"'s example
service left out):
- every file the page names (name.c, name.h, canola/name.h) exists, and every file of
  src/ is named in the layer diagram;
- every identifier it quotes in backticks (co_*, k_*, CO_*, and the members after -> or .)
  occurs in the sources, and where the page says where one lives ("`x` (file.c", "file.c's
  `x`") that file has it;
- the largest group of files that call each other (tools/core_graph.py, read from the
  library) is the one the page names;
- a family the page says is layered one way ("a.c > b.c > c.c": each calls only those after
  it) has no call from a later file to an earlier one.
Prints every finding; exit 1 when there is one.
"""
import argparse
import os
import re
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import core_graph  # noqa: E402  (the call graph: the same reading as the core_structure test)

ROOT = os.path.dirname(HERE)
SOURCE_DIRS = [os.path.join(ROOT, "src"), os.path.join(ROOT, "include", "canola")]
FILE = re.compile(r"\b((?:canola/|src/)?[a-z][a-z0-9_]*\.[ch])\b")
QUOTED = re.compile(r"`([^`]+)`")
IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
C_NAME = re.compile(r"^(co_|k_|CO_|[A-Z][A-Z0-9_]{3,}$)")
LIVES_IN = [re.compile(r"`([A-Za-z_][A-Za-z0-9_]*)[^`]*`[^`.;]{0,40}?\(([a-z][a-z0-9_]*\.[ch])"),
            re.compile(r"\b([a-z][a-z0-9_]*\.[ch])'s `([A-Za-z_][A-Za-z0-9_]*)")]
CHAIN = re.compile(r"\b[a-z][a-z0-9_]*\.c(?:\s*>\s*[a-z][a-z0-9_]*\.c)+")
GROUP = re.compile(r"The largest group of\s+files that call each other is [^:]*:\s*"
                   r"((?:[a-z][a-z0-9_]*\.c(?:,\s*)?)+)")
EXAMPLE = "srdo"  # the service "Adding a service" adds: its files and names do not exist yet


def sources():
    """{file name: text} of src/ and include/canola/."""
    out = {}
    for d in SOURCE_DIRS:
        for name in sorted(os.listdir(d)):
            if name.endswith((".c", ".h", ".inc")):
                with open(os.path.join(d, name), encoding="utf-8") as f:
                    out[name] = f.read()
    return out


def the_map(text):
    """The page up to the Python package's part (what it claims about the core), without
    the example service's names."""
    end = text.find("## The Python package")
    text = text if end < 0 else text[:end]
    return re.sub(r"`[^`]*" + EXAMPLE + r"[^`]*`|\S*" + EXAMPLE + r"\S*", "", text,
                  flags=re.IGNORECASE)


def repository_files():
    """The base names of the repository's files (tests, tools, ports as well as the core)."""
    names = set()
    for _top, dirs, files in os.walk(ROOT):
        dirs[:] = [d for d in dirs if not d.startswith((".", "build"))]
        names.update(files)
    return names


def check_files(page, texts, problems):
    everywhere = repository_files()
    for name in sorted(set(FILE.findall(page))):
        if os.path.basename(name) not in everywhere:
            problems.append(f"names {name}, which the repository does not have")
    diagram = page[page.find("```"):page.find("```", page.find("```") + 3)]
    src = [n for n in sorted(os.listdir(os.path.join(ROOT, "src"))) if n.endswith((".c", ".h"))]
    for name in src:
        if not re.search(r"\b" + re.escape(name) + r"\b", diagram):
            problems.append(f"src/{name} is in no layer of the diagram")


def check_names(page, texts, problems):
    corpus = "\n".join(texts.values())
    words = set(IDENT.findall(corpus))
    for quoted in sorted(set(QUOTED.findall(page))):
        names = IDENT.findall(quoted)
        if not names or not C_NAME.match(names[0]):
            continue  # prose, a frame, a command: not a name of the core
        for name in names:
            if name not in words and not name.isdigit():
                problems.append(f"quotes `{quoted}`: {name} is nowhere in the sources")
    for pattern in LIVES_IN:
        for m in pattern.finditer(page):
            name, where = (m.group(1), m.group(2)) if pattern is LIVES_IN[0] else \
                          (m.group(2), m.group(1))
            if where in texts and not re.search(r"\b" + re.escape(name) + r"\b", texts[where]):
                problems.append(f"says `{name}` is in {where}: it is not")


def check_graph(page, library, problems):
    units, defined, undefined = core_graph.read_symbols([library], "nm")
    edges = core_graph.call_graph(units, defined, undefined)
    groups = core_graph.strongly_connected(edges)
    m = GROUP.search(page)
    if not m:
        problems.append("names no largest group of files that call each other")
    else:
        named = set(re.findall(r"[a-z][a-z0-9_]*\.c", m.group(1)))
        largest = set(groups[0]) if groups else set()
        if named != largest:
            problems.append(f"names the largest group {sorted(named)}; it is {sorted(largest)}")
    for chain in sorted(set(CHAIN.findall(page))):
        order = [f.strip() for f in chain.split(">")]
        for i, later in enumerate(order):
            for earlier in order[:i]:
                if earlier in edges.get(later, {}):
                    syms = " ".join(sorted(edges[later][earlier]))
                    problems.append(f"says {chain}, but {later} calls {earlier} ({syms})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("page")
    ap.add_argument("library", help="the core's library or objects (for the call graph)")
    args = ap.parse_args()
    with open(args.page, encoding="utf-8") as f:
        page = the_map(f.read())
    texts = sources()
    problems = []
    check_files(page, texts, problems)
    check_names(page, texts, problems)
    check_graph(page, args.library, problems)
    for p in problems:
        print(f"{args.page}: {p}")
    if not problems:
        print(f"{args.page}: files, names, the largest group and the one-way families hold")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
