"""A toast never hides what a screen says at 80 x 24 (issue 27, third new-user try):
the Scenes screen's demo status and its keys stay in view while notifications show."""

from __future__ import annotations

import asyncio

from textual.widgets._toast import Toast

from console.cli.main import Context
from console.plugin_api.runtime import Snapshot
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_scenes_truthful import _screen, _twin_demo


def test_toasts_leave_the_scenes_status_in_view(plugins, monkeypatch):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24), notifications=True) as pilot:
            await wait_for(pilot, lambda: app.pane("scenes") is not None, 30, "scenes")
            _twin_demo(app, monkeypatch)
            app.session.emit(Snapshot("demo", "flow", data={"demo": "flow", "running": True}))
            await wait_for(pilot, lambda: "twin:" in _screen(app), 30, "status shown")
            app.notify("a driver said something long elsewhere " * 3, severity="warning")
            app.notify("e-stop reset: outputs stay silent until something plays")
            await wait_for(  # the newest only (``console.tui.toasts``)
                pilot, lambda: "e-stop reset" in _screen(app).splitlines()[0], 30, "toasts"
            )
            await pilot.pause(0.3)  # laid out
            screen = _screen(app)
            assert "space puts your finger on the twin" in screen, screen
            assert "demos (d): enter start/stop" in screen, screen
            assert "e-stop reset: outputs stay silent" in screen.splitlines()[0]  # the newest
            tabs = app.query_one("#tabs")
            for toast in app.screen.query(Toast):  # over the title row only
                assert not toast.region or not toast.region.overlaps(tabs.region)

    asyncio.run(scenario())
