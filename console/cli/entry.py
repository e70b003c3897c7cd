"""The ``haptable`` command's entry point: `haptable estop` and `haptable reset` run with
the standard library only (``console.kernel.shell``), before anything heavy is imported;
every other command goes to ``console.cli.main``. Every command survives a closed
stdout (`haptable estop | head -1`): what it prints after its reader went goes nowhere,
the command does its work and exits with its usual code, quietly (``PipeSafe``)."""

from __future__ import annotations

import os
import sys
from collections.abc import Iterable
from typing import BinaryIO, TextIO

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


class PipeSafe:
    """A stdout whose reader may go away (a pipe to ``head``): once a write or a flush
    finds it gone (``BrokenPipeError``), the stream's file is pointed at the null device
    and everything after goes there; the command carries on (an e-stop still latches)."""

    def __init__(self, stream: TextIO) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            self._gone()
            return len(text)

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError:
            self._gone()

    def _gone(self) -> None:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, self._stream.fileno())  # the buffered rest flushes into nothing
        os.close(null)

    # what the commands ask of stdout besides (``print``'s ``file`` a stream as any)
    def writelines(self, lines: Iterable[str]) -> None:
        for line in lines:
            self.write(line)

    def isatty(self) -> bool:
        return self._stream.isatty()

    def fileno(self) -> int:
        return self._stream.fileno()

    def writable(self) -> bool:
        return True

    @property
    def encoding(self) -> str:
        return self._stream.encoding

    @property
    def errors(self) -> str | None:
        return self._stream.errors

    @property
    def buffer(self) -> BinaryIO:
        return self._stream.buffer  # bytes written there: the command's own to guard


def main(argv: list[str] | None = None) -> int:
    """Run the command; stdout is a pipe (not the console's terminal): ``PipeSafe``."""
    if sys.stdout is not None and not sys.stdout.isatty():
        sys.stdout = PipeSafe(sys.stdout)  # type: ignore[assignment]
    try:
        return _main(argv)
    finally:
        if isinstance(sys.stdout, PipeSafe):
            sys.stdout.flush()  # a reader gone shows here, not as Python exits


def _main(argv: list[str] | None) -> int:
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
