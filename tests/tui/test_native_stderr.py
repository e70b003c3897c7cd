"""What native code writes to file descriptor 2 (OpenCV, PortAudio, libusb) never lands
on the console's screen: while the console runs it goes to the log and the log view
(ctrl+l); the screen is drawn on a copy of the terminal; fd 2 comes back on exit."""

from __future__ import annotations

import asyncio
import ctypes
import logging
import os

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.logs import LogScreen, NativeStderr, ViewHandler, on_terminal

from .conftest import wait_for

OPENCV = b"[ WARN:0@4.102] global cap_v4l.cpp:914 open VIDEOIO(V4L2:/dev/video0): can't open camera by index\n"


def test_native_writes_go_to_the_log_and_fd2_comes_back(capfd, caplog):
    caplog.set_level(logging.INFO, logger="haptable.native")
    before = os.fstat(2)
    native = NativeStderr()
    terminal = native.start()
    try:
        os.write(2, OPENCV)
        libc = ctypes.CDLL(None)  # C's own stdio, as a driver writes it
        libc.dprintf(2, b"ALSA lib pcm.c:2664: Unknown PCM cards.pcm.rear\n")
        os.write(2, b"no newline at the end")
        terminal.write("the screen\n")
        terminal.flush()
    finally:
        native.stop()
    after = os.fstat(2)
    assert (after.st_dev, after.st_ino) == (before.st_dev, before.st_ino)
    err = capfd.readouterr().err
    assert err == "the screen\n"  # what was drawn reached the terminal, nothing else
    got = [r.getMessage() for r in caplog.records if r.name == "haptable.native"]
    assert got[0].startswith("[ WARN:0@4.102] global cap_v4l.cpp:914") and "ctrl+l" in got[0]
    assert got[1:] == ["ALSA lib pcm.c:2664: Unknown PCM cards.pcm.rear", "no newline at the end"]
    assert [r.levelno for r in caplog.records if r.name == "haptable.native"] == [
        logging.WARNING,
        logging.INFO,
        logging.INFO,
    ]
    os.write(2, b"after\n")  # fd 2 is the terminal again
    assert capfd.readouterr().err == "after\n"


def test_the_driver_draws_on_the_terminal_copy(tmp_path):
    class Driver:
        def __init__(self, app):
            self._file = "sys.__stderr__"

    with open(tmp_path / "t", "w") as terminal:
        assert on_terminal(Driver, terminal)(None)._file is terminal


def test_the_log_view_shows_records_and_driver_lines_as_written(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        handler = ViewHandler(app)
        logging.getLogger().addHandler(handler)
        try:
            async with app.run_test(size=(120, 30)) as pilot:
                logging.getLogger("haptable.native").warning("[ WARN:0] [audio] gone")
                await pilot.press("ctrl+l")
                await wait_for(pilot, lambda: isinstance(app.screen, LogScreen), 5, "log")
                logging.getLogger("haptable.test").warning("[relays] serial = 'Z' later")
                await pilot.pause(0.2)
                text = "\n".join(strip.text for strip in app.screen.query_one("RichLog").lines)
                assert "haptable.native: [ WARN:0] [audio] gone" in text
                assert "haptable.test: [relays] serial = 'Z' later" in text
                await pilot.press("escape")
                assert not isinstance(app.screen, LogScreen)
        finally:
            logging.getLogger().removeHandler(handler)

    asyncio.run(scenario())


def test_a_handler_writing_to_fd2_does_not_feed_back(capfd):
    """A library's StreamHandler on stderr writes each native line it is given back into
    fd 2: the line is logged once, not forever."""
    import sys
    import time

    native = NativeStderr()
    native.start()
    echo = logging.StreamHandler(sys.__stderr__)  # fd 2: the pipe now
    echo.setFormatter(logging.Formatter("%(levelname)s %(name)s: %(message)s"))
    native.log.addHandler(echo)
    try:
        os.write(2, b"libusb: error [udev_hotplug_event] ignoring udev action\n")
        time.sleep(0.5)
    finally:
        native.log.removeHandler(echo)
        native.stop()
    assert native.lines == 1 and native.echoes >= 1
    capfd.readouterr()


def test_a_child_holding_the_pipe_does_not_hold_the_console_at_quit(caplog):
    """A process the console started inherits fd 2 (the pipe) and may outlive it (the
    multiprocessing resource tracker does): stopping logs what was written and ends the
    pump without waiting for that process; the console quits at once."""
    import subprocess
    import sys

    caplog.set_level(logging.INFO, logger="haptable.native")
    native = NativeStderr()
    native.start()
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        os.write(2, b"a driver's line\n")
        native.stop(timeout_s=10.0)
        pump = native._thread
        assert pump is not None and not pump.is_alive(), "the pump waited for the child"
    finally:
        child.kill()
        child.wait()
    got = [r.getMessage() for r in caplog.records if r.name == "haptable.native"]
    assert got and got[0].startswith("a driver's line")


def test_a_long_log_line_wraps_at_80_columns(plugins):
    """A driver's long message is read whole in the log view at 80 x 24: it wraps
    instead of running off the right edge."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        handler = ViewHandler(app)
        logging.getLogger().addHandler(handler)
        tail = "the end of a long message"
        try:
            async with app.run_test(size=(80, 24)) as pilot:
                logging.getLogger("haptable.native").warning("x" * 120 + " " + tail)
                await pilot.press("ctrl+l")
                await wait_for(pilot, lambda: isinstance(app.screen, LogScreen), 5, "log")
                await pilot.pause(0.3)
                strips = [s.text for s in app.screen.query_one("RichLog").lines]
                assert all(len(t.rstrip()) <= 80 for t in strips), strips
                assert tail in " ".join(t.strip() for t in strips), strips
        finally:
            logging.getLogger().removeHandler(handler)

    asyncio.run(scenario())
