"""``python -m console.cli``: the ``haptable`` command."""

from console.cli.main import main

raise SystemExit(main())
