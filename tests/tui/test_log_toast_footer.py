"""The log (ctrl+l) at 80 x 24 and 120 x 40: a notification takes the top row as on every
screen, never the log's first line (its key and its file: a new operator's try found a
toast over it), and the footer shows, as on every screen, with the log's own key
(`esc close`) and E-STOP."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.logs import LogScreen

from .conftest import wait_for


def _rows(app) -> list[str]:
    return [s.text for s in app.screen._compositor.render_strips()]


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_a_toast_leaves_the_logs_first_line_and_the_footer_shows(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=size, notifications=True) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await pilot.press("ctrl+l")
            await wait_for(pilot, lambda: isinstance(app.screen, LogScreen), 10, "the log")
            await pilot.pause(0.3)
            app.notify("a toast from elsewhere while the log is open", timeout=30)
            await wait_for(
                pilot, lambda: any("a toast from" in r for r in _rows(app)), 10, "the toast"
            )
            rows = _rows(app)
            assert any("escape closes" in r for r in rows), rows[:4]
            assert not any("escape closes" in r and "a toast" in r for r in rows), rows[:4]
            footer = rows[-1]
            assert "close" in footer and "E-STOP" in footer, rows[-3:]

    asyncio.run(scenario())
