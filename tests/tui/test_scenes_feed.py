"""The Scenes screen's projector line derives from what runs (issue 27): with the knob
scene shown and the knob demo running and sending it, the scene's live input is sent by
that demo (never "nothing sends it yet: start the knob demo"); a demo that runs without
reaching the projector says so and how to fix it."""

from __future__ import annotations

import asyncio
from types import SimpleNamespace

from console.cli.main import Context
from console.session.demos import DemoControl
from console.tui.app import HapTableApp

from .conftest import wait_for

KNOB_SHOWN = {
    "connected": True,
    "scene": "knob",
    "unprepared_needs": ["knob", "contacts"],
    "unprepared_why": {},
}


def _line(app) -> str:
    return str(app.query_one("#projector-status").render())


def test_the_projector_line_says_the_running_demo_sends_the_scene(plugins, monkeypatch):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(pilot, lambda: app.pane("scenes") is not None, what="scenes")
            pane = app.pane("scenes")
            session = app.session
            monkeypatch.setattr(session.scenes, "status", lambda: dict(KNOB_SHOWN))
            # no demo runs: the fix is to start it
            monkeypatch.setattr(session.demos, "scene_feed", lambda: None)
            pane.show_projector()
            assert "nothing sends it yet: start the knob demo" in _line(app)
            # the knob demo runs and its scene reaches the projector
            feed = {"demo": "knob", "scene": "knob", "sent": True}
            monkeypatch.setattr(session.demos, "scene_feed", lambda: feed)
            pane.show_projector()
            line = _line(app)
            assert "nothing sends it" not in line and "start the knob demo" not in line
            assert "knob and contacts: sent by the knob demo" in line
            # it runs but its scene events reach no projector
            feed = {"demo": "knob", "scene": "knob", "sent": False}
            monkeypatch.setattr(session.demos, "scene_feed", lambda: feed)
            pane.show_projector()
            line = _line(app)
            assert "start the knob demo" not in line and "sends its scene to no projector" in line
            # the flow demo runs: the knob scene's input is still not sent by anything
            feed = {"demo": "flow", "scene": "flow_hand", "sent": True}
            monkeypatch.setattr(session.demos, "scene_feed", lambda: feed)
            pane.show_projector()
            assert "nothing sends it yet" in _line(app)

    asyncio.run(scenario())


def test_scene_feed_follows_the_running_demo_and_its_forward():
    session = SimpleNamespace()
    demos = DemoControl(session)
    assert demos.scene_feed() is None
    demos.run = SimpleNamespace(scene_name="knob", stopped=False)
    demos.name, demos.state = "knob", "running"
    feed = {"demo": "knob", "scene": "knob", "sent": False, "state": "running"}
    assert demos.scene_feed() == feed
    demos._forward = SimpleNamespace(ready=True)
    assert demos.scene_feed() == {**feed, "sent": True}
    demos.state = "starting"  # preparing: nothing runs yet
    assert demos.scene_feed() is None
