"""``python -m casa_core.cli``: the ``casa`` command."""

import sys

from casa_core.cli import main

sys.exit(main())
