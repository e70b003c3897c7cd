"""The real ``haptable`` command in a pseudo-terminal that answers like a Sixel terminal:
the console asks before its screen opens and the Camera screen then writes Sixel images;
with ``--image halfblock`` it asks nothing and draws characters."""

from __future__ import annotations

import contextlib
import os
import re
import select
import shutil
import signal
import sys
import time
from pathlib import Path

import pytest

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(sys.platform == "win32", reason="needs a POSIX pseudo-terminal"),
]

DA1 = b"\x1b[c"  # "what are you?": a Sixel terminal lists 4 in its answer
F2 = b"\x1bOQ"
SIXEL = re.compile(rb"\x1bP[0-9;]*q")


def _haptable() -> str:
    cand = Path(sys.executable).parent / "haptable"
    return str(cand) if cand.is_file() else (shutil.which("haptable") or "haptable")


def _run(
    *args: str, answer_sixel: bool, expect_sixel: bool | None = None, timeout_s: float = 40.0
) -> tuple[bytes, bytes]:
    """Start the console in a 100 x 30 pty (10 x 20 px cells), open the Camera screen,
    wait for its view's title (and a sixel image when ``expect_sixel``: by default when
    the terminal answers that it speaks sixel); (what it wrote before F2, after F2)."""
    if expect_sixel is None:
        expect_sixel = answer_sixel
    import fcntl
    import pty
    import struct
    import termios

    pid, fd = pty.fork()
    if pid == 0:  # the console
        os.environ["TERM"] = "xterm-256color"
        for k in ("COLUMNS", "LINES"):
            os.environ.pop(k, None)
        try:
            os.execv(_haptable(), [_haptable(), *args])
        finally:
            os._exit(127)  # never back into pytest
    fcntl.ioctl(fd, termios.TIOCSWINSZ, struct.pack("HHHH", 30, 100, 1000, 600))
    before, after = b"", b""
    sent_at = None  # when F2 was last pressed (again every 2 s: a key sent while the
    # console was still starting can be lost, as a person would press it again)
    t_end = time.monotonic() + timeout_s
    try:
        while time.monotonic() < t_end:
            if select.select([fd], [], [], 0.05)[0]:
                try:
                    chunk = os.read(fd, 65536)
                except OSError:
                    break
                if sent_at is None:
                    before += chunk
                    if DA1 in chunk and answer_sixel:
                        os.write(fd, b"\x1b[?62;4;22c")
                else:
                    after += chunk
                    if b"IR 640x480" in after and (not expect_sixel or SIXEL.search(after)):
                        break
            shown = b"Camera" in before and b"Devices" in before
            again = sent_at is None or time.monotonic() - sent_at > 2.0
            if shown and again and b"IR 640x480" not in after:
                os.write(fd, F2)
                sent_at = time.monotonic()
        return before, after
    finally:
        os.write(fd, b"q")
        time.sleep(1.0)
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGTERM)
        os.waitpid(pid, 0)
        os.close(fd)


def test_a_sixel_terminal_gets_the_ir_view_as_sixel_images():
    before, after = _run(answer_sixel=True)
    assert before.count(DA1) == 1  # asked once, before the screen opened
    assert b"IR 640x480 via sixel" in after
    assert SIXEL.search(after)


def test_halfblock_asks_the_terminal_nothing_and_draws_characters():
    # the terminal speaks sixel, but half-block is forced: no image to wait for
    before, after = _run("console", "--image", "halfblock", answer_sixel=True, expect_sixel=False)
    assert DA1 not in before and b"\x1b_G" not in before
    assert b"IR 640x480 as half-block" in after
    assert not SIXEL.search(after)
