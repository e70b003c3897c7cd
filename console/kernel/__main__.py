"""``python -m console.kernel``: a table's outputs process (``console.kernel.server``)."""

import os
import sys

from console.kernel.server import main

if __name__ == "__main__":
    code = main()
    sys.stderr.flush()
    os._exit(code)  # daemon threads sit in blocking calls: leave without finalising them
