"""Issue 27, the last new-user try, at 80 x 24 in one console run: Scope's ``o`` field is
labelled with what to type; the Vibration ``:`` line shows a ``:`` prompt and its hint
dim and italic (never like a typed command); a key pressed right after an F-key goes to
the screen that F-key shows, though that screen is still being built."""

from __future__ import annotations

import asyncio

from textual import events
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.command_line import CommandLine

from .conftest import wait_for
from .test_camera_layout import screen_lines


def _row_segments(app, widget):
    """(text, style) of the segments the screen shows on ``widget``'s first row."""
    r = widget.region
    strip = app.screen._compositor.render_strips()[r.y]
    out, x = [], 0
    for seg in strip:
        if x + len(seg.text) > r.x and x < r.right:
            out.append((seg.text, seg.style))
        x += len(seg.text)
    return out


def test_labelled_field_prompted_line_and_keys_after_a_switch(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scope")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await wait_for(pilot, lambda: app.focused is not None, 10, "scope focused")
            await pilot.press("o")
            await wait_for(pilot, lambda: isinstance(app.focused, Input), 10, "the field")
            await pilot.pause(0.2)
            shown = " ".join(screen_lines(app))
            assert "recording: a .h5 file's path" in shown, shown
            await pilot.press("escape")
            # F3 and : in one write: the : goes to Vibration (built on first use)
            app.post_message(events.Key("f3", None))  # queued together, as under load
            app.post_message(events.Key("colon", ":"))
            await wait_for(pilot, lambda: isinstance(app.focused, CommandLine), 10, ": line")
            line = app.focused
            app.focused.value = ""
            await pilot.press("escape")
            await wait_for(pilot, lambda: not isinstance(app.focused, CommandLine), 10, "left")
            await pilot.pause(0.2)
            segs = _row_segments(app, line.parent)
            text = "".join(t for t, _ in segs)
            assert text.startswith(": ") and "51 52" in text, text
            hint = [s for t, s in segs if "51 52" in t]
            assert hint and all(s.italic for s in hint), segs

    asyncio.run(scenario())
