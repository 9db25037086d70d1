# SPDX-License-Identifier: Apache-2.0
"""``canola.odgen`` and ``python -m canola.odgen``, as the docs name them:
:mod:`canola.formats.odgen` (C object dictionaries from an EDS/DCF) under its first name.
Nothing lives here."""

from canola.formats.odgen import *  # noqa: F403
from canola.formats.odgen import main

if __name__ == "__main__":
    raise SystemExit(main())
