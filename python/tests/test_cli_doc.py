# SPDX-License-Identifier: Apache-2.0
"""docs/cli.md lists every command of ``canola`` with the arguments its parser takes, no
more and no fewer, each with its help text: the page's tables are what cli_doc.py makes
from the parsers (``python tests/cli_doc.py`` writes them anew after a change)."""

from __future__ import annotations

import difflib

from cli_doc import PAGE, commands, listed, render


def test_every_command_has_a_table() -> None:
    page = PAGE.read_text(encoding="utf-8")
    assert sorted(listed(page)) == sorted(commands())


def test_the_tables_are_the_parsers() -> None:
    page = PAGE.read_text(encoding="utf-8")
    made = render(page)
    diff = "".join(difflib.unified_diff(page.splitlines(True), made.splitlines(True),
                                        "docs/cli.md", "from the parsers"))
    assert made == page, f"run `python tests/cli_doc.py` in python/:\n{diff}"


def test_a_section_without_a_table_gets_one() -> None:
    page = "### `canola nmt`\n\nProse.\n\n### `canola sync`\n\nMore.\n"
    made = render(page)
    assert "<!-- arguments: canola nmt -->\n| argument | what it is |" in made
    assert "<!-- arguments: canola sync -->\n| argument | what it is |" in made
    assert made.index("Prose.") < made.index("canola nmt -->") < made.index("### `canola sync`")
    assert render(made) == made
