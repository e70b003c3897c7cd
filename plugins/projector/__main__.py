"""``python -m plugins.projector``: the projector process as the console supervises it."""

import sys

from plugins.projector.cli import main

sys.exit(main())
