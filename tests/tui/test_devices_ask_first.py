"""A new operator's try, finding 16c: keys that act at once on a real table ask first,
as Delete of a saved signal and ``a`` of a study run do. On Devices, Enter on the relay
board in use rewrote overrides.toml: it changes nothing now and says so; another card is
used on Enter again; ``s`` (chirps on every relay path) runs on ``s`` again. On Camera,
``W`` (overwrites the saved vision settings) keeps them on ``W`` again."""

from __future__ import annotations

import asyncio

from textual.widgets import DataTable

from console.cli.main import Context
from console.config.plugins import load_plugins
from console.config.profile import overrides_path
from console.tui.app import HapTableApp
from console.tui.panes import devices_selftest as devices_mod

from .conftest import wait_for, words_on
from .test_camera import _first_frame
from .test_devices import _bench_card_plugin, _row_of


def test_devices_enter_and_s_ask_first_and_the_device_in_use_changes_nothing(monkeypatch):
    ran: list[bool] = []

    def selftest(profile, pm):  # the UI's part only: no chirps
        ran.append(True)
        return True, "self-test: all paths healthy (1 s)"

    monkeypatch.setattr(devices_mod, "run_selftest", selftest)
    plugins = load_plugins(extra={"bench_card": _bench_card_plugin()})

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            pane = app.pane("devices")
            said = lambda: words_on(app, "#devices-result")  # noqa: E731
            relays = app.query_one("#relay-table", DataTable)
            await wait_for(pilot, lambda: _row_of(relays, "twin") is not None, 20, "listed")
            relays.focus()
            relays.move_cursor(row=_row_of(relays, "twin"))
            await pilot.press("enter", "enter")
            await wait_for(pilot, lambda: "in use already" in said(), 20, "said")
            assert "relay board 'twin' in use already: nothing changed" in said()
            assert not overrides_path("sim").exists()
            # another card: the first Enter asks, nothing saved; Enter again uses it
            cards = app.query_one("#audio-table", DataTable)
            cards.focus()
            cards.move_cursor(row=_row_of(cards, "Bench Card B"))
            await pilot.press("enter")
            await wait_for(pilot, lambda: "enter again within 3 s" in said(), 10, "asked")
            await pilot.pause(0.3)
            assert not overrides_path("sim").exists() and "saving" not in pane.result
            await pilot.press("enter")
            await wait_for(pilot, lambda: "in use; saved" in said(), 20, "used")
            assert app.session.outputs_profile.get("audio.device") == "Bench Card B (JACK)"
            # the self-test: s asks, s again runs it
            await pilot.press("s")
            await wait_for(pilot, lambda: "s again within 3 s" in said(), 10, "asked")
            await pilot.pause(0.3)
            assert ran == []
            await pilot.press("s")
            await wait_for(pilot, lambda: "healthy" in said(), 20, "ran")
            assert ran == [True]

    asyncio.run(scenario())


def test_camera_w_asks_before_it_overwrites_the_saved_vision_settings(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="camera")
        async with app.run_test(size=(80, 24)) as pilot:
            await _first_frame(app, pilot)
            status = lambda: words_on(app, "#camera-status")  # noqa: E731
            await pilot.press("W")
            await wait_for(pilot, lambda: "W again within 3 s" in status(), 10, "asked")
            await pilot.pause(0.3)
            assert not overrides_path("sim").exists()
            await pilot.press("W")
            await wait_for(pilot, lambda: "kept in" in status(), 10, "kept")
            assert (
                "[vision]" in overrides_path("sim").read_text()
                or overrides_path("sim").stat().st_size
            )

    asyncio.run(scenario())
