"""The ``haptable`` command's entry point: `haptable estop` and `haptable reset` run with
the standard library only (``console.kernel.shell``), before anything heavy is imported;
every other command goes to ``console.cli.main``."""

from __future__ import annotations

import sys

#: options that may come before the command
_GLOBAL = {"-p": 1, "--profile": 1, "-v": 0, "--verbose": 0}


def _command(argv: list[str]) -> str | None:
    i = 0
    while i < len(argv):
        a = argv[i]
        if a in _GLOBAL:
            i += 1 + _GLOBAL[a]
        elif a.startswith("--profile="):
            i += 1
        else:
            return a
    return None


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if _command(argv) in ("estop", "reset"):
        # lazy: the estop path stays standard-library only
        from console.kernel.shell import main as shell_main

        return shell_main(argv)
    # lazy: the estop path stays standard-library only
    from console.cli.main import main as cli_main

    return cli_main(argv)


if __name__ == "__main__":
    sys.exit(main())
