"""Issue 27, the last new-user try, at 80 x 24 in one console run: the Devices screen's
Up/Enter act on the sound-card list from the first key (no Tab first) and what Enter did
is said on a line in view; the Gestures panel (Camera ``g``) shows its own keys in the
footer from its first draw, not only after ``?``; ctrl+p's palette closes with Esc and
its "Keys" opens the console's help over the whole terminal (Textual's docked keys
panel squeezed the tab bar to ``Sc…`` and stayed on Esc), Esc closing it."""

from __future__ import annotations

import asyncio

from textual.widgets import Footer, Static

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines, text_in


def _footer(app) -> str:
    """What the screen's footer shows, as drawn."""
    found = app.screen.query(Footer)
    return text_in(app, found.first()) if found else ""


def _result(app) -> str:
    return " ".join(str(app.query_one("#devices-result", Static).render()).split())


def test_devices_list_takes_keys_at_once_and_gestures_footer_is_whole(plugins, monkeypatch):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            table = app.query_one("#audio-table")
            await wait_for(pilot, lambda: table.row_count > 1, 30, "sound cards listed")
            await wait_for(pilot, lambda: app.focused is not None, 10, "focus")
            await pilot.press("up", "enter")  # no Tab first
            await wait_for(
                pilot,
                lambda: "sound card" in _result(app) or "sounddevice" in _result(app),
                30,
                "enter said",
            )
            line = app.query_one("#devices-result")
            await wait_for(pilot, lambda: line.region.height > 0, 10, "the line laid out")
            assert app.screen.region.contains_region(line.region), line.region
            # the Gestures panel: its keys in the footer from the first draw, with no
            # later signal to draw them: as in tmux, where the terminal reports no focus
            # (Textual's footer then skips the binding updates), and its screen signalling
            # no change after the footer listened (its button took the focus in its
            # on_mount, before): only the footer's own first draw shows them
            app.app_focus = False
            with monkeypatch.context() as quiet:
                quiet.setattr(Footer, "bindings_changed", lambda self, screen: None)
                app.push_screen(plugins.of("panel")["gestures"].factory(app))
                await wait_for(pilot, lambda: type(app.screen).__name__ == "GesturesPanel")
                await wait_for(pilot, lambda: "E-STOP" in _footer(app), 10, "footer")
                await wait_for(pilot, lambda: "synthesize" in _footer(app), 3, "s in footer")
                footer = _footer(app)
                assert "train" in footer and "cancel" in footer, footer
            app.app_focus = True
            await pilot.press("escape")
            await wait_for(pilot, lambda: app.screen is app.base, 10, "panel closed")
            # ctrl+p: Esc closes the palette; its "Keys" is the console's help, over the
            # whole terminal (the tab bar keeps its titles), and Esc closes that too
            await pilot.press("ctrl+p")
            await wait_for(pilot, lambda: app.screen is not app.base, 10, "palette")
            await pilot.press("escape")
            await wait_for(pilot, lambda: app.screen is app.base, 10, "palette closed by Esc")
            await pilot.press("ctrl+p", *"keys")
            await wait_for(pilot, lambda: "Keys" in " ".join(screen_lines(app)), 10, "Keys")
            await pilot.press("enter")
            await wait_for(pilot, lambda: type(app.screen).__name__ == "HelpScreen", 10, "help")
            assert "This screen: Devices" in " ".join(screen_lines(app))
            await pilot.press("escape")
            await wait_for(pilot, lambda: app.screen is app.base, 10, "help closed by Esc")
            assert "Devices Camera" in screen_lines(app)[1], screen_lines(app)[1]

    asyncio.run(scenario())
