"""ctrl+p's palette: the footer under it shows the palette's keys and E-STOP, not the
screen's below (a new operator's try on Relays: ``⏎ toggle 1-8 toggle`` showed while
the palette took every key), and Textual's "Maximize" (a widget over the whole terminal,
the safety bar hidden) is not offered."""

from __future__ import annotations

import asyncio

import pytest
from textual.command import CommandList

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines


def _listed(app) -> list[str]:
    found = app.screen.query(CommandList)
    if not found:
        return []
    return [str(o.prompt).split("\n")[0] for o in found.first().options]


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_the_palette_footer_is_its_own_and_maximize_is_gone(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await wait_for(pilot, lambda: "toggle" in screen_lines(app)[-1], 10, "relays keys")
            await pilot.press("ctrl+p")
            await wait_for(pilot, lambda: type(app.screen).__name__ == "SafetyPalette", 10)
            await wait_for(pilot, lambda: "esc" in screen_lines(app)[-1], 10, "its footer")
            footer = screen_lines(app)[-1]
            assert "toggle" not in footer and "E-STOP" in footer, footer
            assert "? help" not in footer and "f1-f10" not in footer, footer  # typed / not here
            assert "E-STOP" in screen_lines(app)[-2]  # the safety bar above it
            await wait_for(pilot, lambda: len(_listed(app)) > 5, 10, "the commands listed")
            listed = _listed(app)
            assert not any(t.startswith(("Maximize", "Minimize")) for t in listed), listed
            assert any(t.startswith("Keys") for t in listed), listed
            await pilot.press("ctrl+e")  # the footer's promise holds in the palette
            await wait_for(pilot, lambda: app.session.outputs.estopped, 10, "e-stopped")
            await pilot.press("escape")
            await wait_for(pilot, lambda: "toggle" in screen_lines(app)[-1], 10, "keys back")

    asyncio.run(scenario())
