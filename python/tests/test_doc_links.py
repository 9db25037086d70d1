# SPDX-License-Identifier: Apache-2.0
"""The links between the manual's pages hold: every relative link of README.md,
CONTRIBUTING.md, CHANGELOG.md and docs/*.md names a file or folder
of the repository, and every ``#anchor`` (on its own page or another) is one GitHub
makes for a heading there. Links to other sites are not followed. Every page of docs/ is
reachable from the index (docs/index.md), and the index from the README."""

from __future__ import annotations

from pathlib import Path
from urllib.parse import unquote

import pytest
from docblocks import DOCS, ROOT, anchor, anchors, links, page_name, pages

LINKED_PAGES = [*pages(), ROOT / "CHANGELOG.md"]


def _broken(page: Path, root: Path = ROOT) -> list[str]:
    broken = []
    for line, target in links(page):
        if "://" in target or target.startswith("mailto:"):
            continue
        path, _, fragment = target.partition("#")
        dest = (page.parent / unquote(path)).resolve() if path else page
        where = f"{page.relative_to(root).as_posix()}:{line}: {target}"
        if not dest.exists():
            broken.append(f"{where}: no such file")
        elif not dest.is_relative_to(root):
            broken.append(f"{where}: outside the repository")
        elif fragment and dest.suffix == ".md" and fragment not in anchors(dest):
            broken.append(f"{where}: no heading of {dest.name} has that anchor")
    return broken


@pytest.mark.parametrize("page", LINKED_PAGES, ids=page_name)
def test_links_resolve(page: Path) -> None:
    assert _broken(page) == []


def test_the_index_reaches_every_page() -> None:
    index = DOCS / "index.md"
    linked = {(index.parent / t.partition("#")[0]).resolve() for _, t in links(index)}
    missing = [p.name for p in sorted(DOCS.glob("*.md")) if p != index and p not in linked]
    assert missing == [], f"docs/index.md links no {missing}"
    readme = {t.partition("#")[0] for _, t in links(ROOT / "README.md")}
    assert "docs/index.md" in readme


@pytest.mark.parametrize(("heading", "slug"), [
    ("The CiA 309-3 gateway's bounds (`canola gateway`)",
     "the-cia-309-3-gateways-bounds-canola-gateway"),
    ("What changed in the third size round (issue 21, 2026-12-02, third session)",
     "what-changed-in-the-third-size-round-issue-21-2026-12-02-third-session"),
    ("canola.Master where users are: >= 2x python-canopen's round trips, <= 0.5x its CPU "
     "(issue 31)",
     "canolamaster-where-users-are--2x-python-canopens-round-trips--05x-its-cpu-issue-31"),
    ("Python: `canola.Device` and [`canola.Master`](x.md)", "python-canoladevice-and-canolamaster"),
])
def test_anchors_as_github_makes_them(heading: str, slug: str) -> None:
    assert anchor(heading) == slug


def test_a_broken_link_is_found(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text("# Top\n\n[ok](#top) [gone](#nowhere) [file](missing.md) "
                    "`[code](nothing.md)`\n\n```\n[in a block](nothing.md)\n```\n")
    assert [t for _, t in links(page)] == ["#top", "#nowhere", "missing.md"]
    assert _broken(page, tmp_path) == [
        "page.md:3: #nowhere: no heading of page.md has that anchor",
        "page.md:3: missing.md: no such file"]
