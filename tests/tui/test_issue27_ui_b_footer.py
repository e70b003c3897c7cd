"""Issue 27 (ui b), at 80 x 24 in one console run: the focused Signals library shows its
own keys (Enter loads, Delete removes) first in the footer, and Scope's ``o`` field shows
its whole hint, which says where the console writes a recording (Studies' "record
trials"), not a command-line switch, with its keys (Enter, Esc) in view."""

from __future__ import annotations

import asyncio

from textual.widgets import Footer, Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines, text_in


def _footer(app) -> str:
    return text_in(app, app.screen.query(Footer).first())


def test_library_keys_first_in_the_footer_and_scope_field_whole(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.query("#sig-library"), 20, "signals built")
            lib = app.query_one("#sig-library")
            await wait_for(pilot, lambda: lib.option_count > 0, 10, "library listed")

            def library_keys() -> bool:  # the screen's first focus may come after ours
                if app.focused is not lib:
                    lib.focus()
                return "load" in _footer(app)

            await wait_for(pilot, library_keys, 30, "library keys")
            footer = _footer(app)
            # the list's own keys come first, before the screen's (ctrl+o play)
            assert footer.index("load") < footer.index("remove") < footer.index("play"), footer
            assert footer.split()[0] in ("⏎", "enter"), footer
            await pilot.press("f9")
            await wait_for(pilot, lambda: app.query("#scope-head"), 20, "scope")
            scope = app.query_one("#scope-head").parent
            scope.focus()
            await pilot.press("o")
            box = app.query_one("#scope-recording", Input)
            await wait_for(pilot, lambda: box.region.height > 0, 10, "o field shown")
            await pilot.pause(0.1)
            shown = text_in(app, box)
            assert "record trials)" in shown, shown  # the hint whole, its end in view
            assert "--" not in shown, shown  # no command-line switch inside the console
            assert "Enter opens" in shown and "Esc back" in shown, shown
            assert any("recording: a .h5 file" in line for line in screen_lines(app))

    asyncio.run(scenario())
