"""The Devices screen at 80 x 24 (issue 27): its status line shows whole where it is seen
(the saved path too), and a long driver error stays within its column (ellipsized) with
the full text one key away (enter on the row) and in the console's log."""

from __future__ import annotations

import asyncio
import importlib.util
import logging
from pathlib import Path

from textual.widgets import DataTable

from console.config.plugins import load_plugins
from console.config.profile import overrides_path
from console.runtime.context import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


def _long_error_card():
    file = Path(__file__).parent / "card_plugins" / "long_error_card.py"
    spec = importlib.util.spec_from_file_location("haptable_test_long_error_card", file)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def screen_text(app) -> str:
    return "\n".join(strip.text for strip in app.screen._compositor.render_strips())


def _row_of(table: DataTable, text: str) -> int | None:
    for i in range(table.row_count):
        if any(text in str(c) for c in table.get_row_at(i)):
            return i
    return None


def test_a_long_driver_error_stays_in_its_column_and_shows_whole_on_enter(caplog):
    mod = _long_error_card()
    plugins = load_plugins(extra={"long_error_card": mod})
    caplog.set_level(logging.INFO)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            table = app.query_one("#audio-table", DataTable)
            await wait_for(pilot, lambda: _row_of(table, "long-error-card") is not None, 20)
            row = _row_of(table, "long-error-card")
            shown = str(table.get_row_at(row)[2])
            assert shown.endswith("…") and len(shown) <= 40, shown
            # the columns after it stay on the screen: the twin's host API shows
            twin = [str(c) for c in table.get_row_at(_row_of(table, "digital twin"))]
            offset = sum(c.get_render_width(table) for c in list(table.columns.values())[:3])
            assert offset < 80 - len("simulated"), (offset, twin)
            # the whole error: enter on its row, and the log
            table.focus()
            table.move_cursor(row=row)
            await pilot.press("enter")
            result = app.query_one("#devices-result")
            await wait_for(pilot, lambda: mod.LONG_ERROR in str(result.content), 10, "whole")
            assert any(mod.LONG_ERROR in r.getMessage() for r in caplog.records)

    asyncio.run(scenario())


def test_the_status_line_shows_the_saved_path_at_80_by_24():
    from .test_devices import _bench_card_plugin

    plugins = load_plugins(extra={"bench_card": _bench_card_plugin()})

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            table = app.query_one("#audio-table", DataTable)
            card = "Bench Card B"
            await wait_for(pilot, lambda: _row_of(table, card) is not None, 20, "listed")
            table.focus()
            table.move_cursor(row=_row_of(table, card))
            await pilot.press("enter", "enter")  # the first asks, the second uses it
            pane = app.pane("devices")
            await wait_for(pilot, lambda: "in use; saved" in pane.result, 20, "picked")
            pane.scroll_home(animate=False)
            table.focus()
            await pilot.pause(0.3)
            text = " ".join(line.strip() for line in screen_text(app).splitlines())
            assert "in use; saved to" in text, text
            assert overrides_path("sim").name in text, text

    asyncio.run(scenario())


def test_a_test_signal_during_an_estop_is_refused_on_the_line(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            pane = app.pane("devices")
            seen: list[str] = []
            real = pane._show_result

            def spy(text, *a, **kw):
                seen.append(text)
                return real(text, *a, **kw)

            pane._show_result = spy
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, what="e-stopped")
            await pilot.press("t")
            await wait_for(pilot, lambda: "refused" in pane.result, 20, "refused")
            assert "refused: e-stop active, ctrl+r resets" in pane.result
            assert not any("playing" in t for t in seen), seen

    asyncio.run(scenario())
