"""placeholder"""

from __future__ import annotations

import argparse

from canola.cli.common import Parser


def register(subs: argparse._SubParsersAction[Parser]) -> None:
    del subs
