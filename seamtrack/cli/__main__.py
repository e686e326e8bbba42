"""``python -m seamtrack.cli``: the ``seamtrack`` command."""

import sys

from seamtrack.cli.main import main

sys.exit(main())
