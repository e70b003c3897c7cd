"""The Vibration screen, a third new-user try at 80x24 (issue 27): a failed command keeps
the line open with its text (the keys typed next are the line's, never the grid's that
play); ctrl+u clears the line, escape goes back to the grid; a play that fails in its
worker says so on the status line; an e-stop stops a measurement at once and the line
says so; the ``:`` hint and the help name the commands alike."""

from __future__ import annotations

import asyncio
import re

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.command_line import CommandLine

from .conftest import wait_for, words_on
from .test_screens import _load_map, _ready


def _status(app) -> str:
    return words_on(app, "#vib-status")


def test_a_failed_command_keeps_the_line_open_and_ctrl_u_clears_it(plugins, map_file):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = await _load_map(app, pilot, map_file)
            line = app.query_one("#vib-cmd", CommandLine)
            await wait_for(pilot, lambda: line.value == "", 30, "the load's line cleared")
            await pilot.press("colon", *"hand 99 upward", "enter")
            await wait_for(pilot, lambda: "hand POINT" in _status(app), 30, "refused")
            assert app.focused is line and line.value == "hand 99 upward"
            played = len(app.session.played)
            await pilot.press("w", "d")  # typed on the line, not the grid's hand keys
            assert line.value == "hand 99 upwardwd"
            assert len(app.session.played) == played
            await pilot.press("left", "ctrl+u")  # the whole line, wherever the cursor
            assert line.value == ""
            await pilot.press(*"51", "enter")  # a success gives the keys back to the grid
            await wait_for(pilot, lambda: app.focused is pane.focus_target, 30, "the grid")
            assert line.value == ""
            await pilot.press("colon", "x", "escape")  # escape leaves the line too
            await wait_for(pilot, lambda: app.focused is pane.focus_target, 30, "the grid")
            assert line.value == "x"

    asyncio.run(scenario())


def test_a_play_that_fails_in_its_worker_says_so(plugins, map_file):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = await _load_map(app, pilot, map_file)

            def broken(n):
                raise RuntimeError("effect broke")

            pane.session.point_plan = broken
            pane.move_cursor(51)
            await pilot.press("enter")
            await wait_for(pilot, lambda: "effect broke" in _status(app), 30, "the failure")
            assert "point 51" in _status(app)
            assert app.is_running

    asyncio.run(scenario())


def test_a_play_does_not_write_over_an_error_said_after_it_was_asked(plugins, map_file):
    """A play's "asking"/"played" replaces only its own line: an error said while its
    plan was being made stays."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = await _load_map(app, pilot, map_file)
            import threading

            go = threading.Event()
            real = pane.session.point_plan

            def slow(n):
                go.wait(30)
                return real(n)

            pane.session.point_plan = slow
            pane.move_cursor(51)
            await pilot.press("enter")
            await pilot.press("colon", *"hand 1", "enter")
            await wait_for(pilot, lambda: "hand POINT" in _status(app), 30, "the error")
            go.set()
            await wait_for(pilot, lambda: len(app.session.played) == 1, 30, "played")
            await wait_for(pilot, lambda: pane._now_playing is None, 30, "ended")
            await pilot.pause(0.2)
            assert "hand POINT" in _status(app)

    asyncio.run(scenario())


def test_an_estop_stops_a_measurement_at_once_and_says_so(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = app.pane("vibration")
            await pilot.press("m")
            await wait_for(pilot, lambda: "step" in _status(app), 30, "measuring")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: "e-stop" in _status(app), 30, "stopped")
            assert "measurement stopped by the e-stop" in _status(app)
            assert "ctrl+r" in _status(app)
            await wait_for(
                pilot,
                lambda: not any(w.group == "vib-long" and w.is_running for w in app.workers),
                30,
                "the measurement's worker ended",
            )
            await pilot.pause(0.3)
            assert "measurement stopped by the e-stop" in _status(app)
            assert pane.query_one("#vib-progress").display is False
            await pilot.press("ctrl+r")  # the line drops the reset it no longer needs
            await wait_for(pilot, lambda: "ctrl+r" not in _status(app), 30, "after the reset")
            assert "measurement stopped by the e-stop" in _status(app)

    asyncio.run(scenario())


def test_the_hint_and_the_help_name_the_commands_alike(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            hint = app.query_one("#vib-cmd", CommandLine).placeholder
            help_text = " ".join(app.pane("vibration").HELP_TEXT.split())
            assert hint in help_text  # the same names, in the same words
            for head in ("measure", "import", "load", "tables", "cancel", "hand"):
                assert head in re.findall(r"[a-z]+", hint), head
            assert len(hint) <= 80

    asyncio.run(scenario())
