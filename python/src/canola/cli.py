"""The ``canola`` command: one sub-command per module.

    canola odgen DEVICE.eds -o DIR [--name NAME] [--node-id N]   C object dictionary

A bad argument gets a one-line explanation and exit code 2; a broken input file its
diagnostic (file:line: [section] key: ...) and exit code 1.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

from canola import odgen

USAGE = "usage: canola odgen DEVICE.eds -o DIR [--name NAME] [--node-id N]"


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if not args or args[0] in ("-h", "--help"):
        print(USAGE)
        return 0 if args else 2
    command, rest = args[0], args[1:]
    if command == "odgen":
        return odgen.main(rest, prog="canola odgen")
    print(f"canola: unknown command {command!r} ({USAGE})", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main())
