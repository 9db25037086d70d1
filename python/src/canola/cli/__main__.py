"""``python -m canola.cli``: the ``canola`` command."""

import sys

from canola.cli import main

sys.exit(main())
