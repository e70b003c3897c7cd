"""Issue 27, new-user try (UI A), Scenes (F6) at 80 x 24: the projector line says what
the demo does as its row does (never "running" once it stops); ``k`` closes a projector
showing a scene only when pressed again within a few seconds, the demos' line asking; a
long progress line shows whole (no row cut after a comma)."""

from __future__ import annotations

import asyncio
from types import SimpleNamespace

from console.cli.main import Context
from console.session.demos import DemoControl
from console.tui.app import HapTableApp
from plugins.demos.panel import CLOSE_AGAIN_S
from plugins.demos.projector_line import needs_text

from .conftest import wait_for
from .test_camera_layout import text_in

KNOB_SHOWN = {
    "connected": True,
    "scene": "knob",
    "unprepared_needs": ["knob", "contacts"],
    "unprepared_why": {},
}


async def knob_shown_scenes(app, pilot, monkeypatch, feed: dict | None = None) -> tuple:
    """Scenes with the projector showing the knob scene (its status as ``KNOB_SHOWN``,
    closing it noted, the demo's ``feed``), the focus on the screen: (pane, its work
    line, the closes noted)."""
    await wait_for(pilot, lambda: app.pane("scenes") is not None, what="scenes")
    pane, session = app.pane("scenes"), app.session
    closed: list[int] = []
    monkeypatch.setattr(session.scenes, "status", lambda: dict(KNOB_SHOWN))
    monkeypatch.setattr(session.scenes, "close_projector", lambda: closed.append(1))
    monkeypatch.setattr(session.demos, "scene_feed", lambda: feed)
    work = app.query_one("#demo-work")
    focused = lambda: app.focused is not None and pane in app.focused.ancestors_with_self  # noqa: E731
    await wait_for(pilot, focused, 10, "the focus on Scenes")
    return pane, work, closed


def test_the_feed_says_what_the_demo_does_now():
    demos = DemoControl(SimpleNamespace())
    demos.run = SimpleNamespace(scene_name="knob", stopped=False)
    demos.name, demos.state, demos._forward = "knob", "stopping", SimpleNamespace(ready=True)
    feed = demos.scene_feed()
    assert feed["state"] == "stopping"
    line = needs_text(dict(KNOB_SHOWN), feed)
    assert "(running)" not in line and "until it ends (stopping)" in line, line
    line = needs_text(dict(KNOB_SHOWN), {**feed, "state": "running"})
    assert "sent by the knob demo (running)" in line, line


def test_close_asks_again_and_lines_stay_true_at_80x24(plugins, monkeypatch):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            feed = {"demo": "knob", "scene": "knob", "sent": True, "state": "running"}
            pane, work, closed = await knob_shown_scenes(app, pilot, monkeypatch, feed)
            session = app.session
            await pilot.press("k")
            asked = f"k again within {CLOSE_AGAIN_S:g} s"
            await wait_for(pilot, lambda: asked in text_in(app, work), 10, "k asks again")
            assert closed == [], "k closed a projector showing a scene at once"
            await pilot.press("k")
            await wait_for(pilot, lambda: closed == [1], 10, "the second k closes it")
            # the demo ends: its row and the projector line say so at the same moment
            pane.demo_name = "knob"
            monkeypatch.setattr(session.demos, "scene_feed", lambda: None)
            pane._stopped("knob", "stopped")
            line = str(app.query_one("#projector-status").render())
            assert "(running)" not in line and "sent by the knob demo" not in line, line
            # a start's progress longer than a row shows whole
            text = "demo flow: opening the camera, 14 s, longer than guessed (12 s)"
            work.show(text, 0.4)
            whole = "longer than guessed (12 s)"
            await wait_for(pilot, lambda: whole in text_in(app, work), 10, "the line whole")

    asyncio.run(scenario())
