"""A question with a time limit ("X again within N s ...") leaves its line when its
window ends (``console.tui.lapse``), at 80 x 24: Scenes' ``k`` with a scene shown and
Camera's ``b`` with a hand on the glass; and every such question in the console and its
plugins is one that lapses and holds its line while asked (``lapse`` or ``ask`` where it is
asked: ``console.tui.question_hold``; a timer of its own let other lines replace it)."""

from __future__ import annotations

import asyncio
import re
from pathlib import Path

import numpy as np

from console.cli.main import Context
from console.tui import camera_wizard
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import _first_frame, text_in
from .test_issue27_ui_a_scenes import knob_shown_scenes

ROOT = Path(__file__).resolve().parents[2]
ASKS = re.compile(r"f\"[^\"]*again within \{")


def _lapses(path: Path) -> bool:
    """``path`` lets its questions lapse, or a module of its package that uses its
    words does (``vibration_words`` asks, ``vibration`` lapses it)."""

    def lapses(text: str) -> bool:
        # lapse's own question, or a work line's (``LongWork.ask``, a summary that asks):
        # each holds its line (``console.tui.question_hold``); a timer of its own does not
        asks = "from console.tui.lapse import ask" in text or "asks_s=" in text
        return "lapse(" in text or ".ask(" in text or asks

    if lapses(path.read_text()):
        return True
    return any(
        path.stem in p.read_text() and lapses(p.read_text())
        for p in path.parent.glob("*.py")
        if p != path
    )


def test_every_timed_question_lapses():
    asking = [
        p for d in ("console", "plugins") for p in (ROOT / d).rglob("*.py")
        if ASKS.search(p.read_text())
    ]  # fmt: skip
    assert len(asking) >= 4, asking
    assert [str(p.relative_to(ROOT)) for p in asking if not _lapses(p)] == []


def test_scenes_k_question_lapses(plugins, monkeypatch):
    import plugins.demos.panel as dp

    monkeypatch.setattr(dp, "CLOSE_AGAIN_S", 1.0)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            _pane, work, closed = await knob_shown_scenes(app, pilot, monkeypatch)
            await pilot.press("k")
            await wait_for(pilot, lambda: "k again within 1 s" in text_in(app, work), 10, "asks")
            await wait_for(pilot, lambda: "again within" not in text_in(app, work), 10, "lapsed")
            assert closed == []
            await pilot.press("k")  # its window passed: k asks again, it does not close
            await wait_for(pilot, lambda: "k again within 1 s" in text_in(app, work), 10, "")
            assert closed == []

    asyncio.run(scenario())


def test_camera_b_question_lapses(plugins, monkeypatch):
    monkeypatch.setattr(camera_wizard, "BACKGROUND_AGAIN_S", 1.0)
    yy, xx = np.mgrid[0:480, 0:640]
    hand = np.where((xx - 400) ** 2 + (yy - 200) ** 2 < 60**2, 210.0, 30.0)  # on the glass

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=(80, 24)) as pilot:
            await _first_frame(app, pilot)
            svc = app.session.camera_started
            monkeypatch.setattr(svc, "median_background", lambda: hand.copy())
            status = app.query_one("#camera-status")
            await pilot.press("b")
            await wait_for(pilot, lambda: "b again within 1 s" in text_in(app, status), 10, "")
            await wait_for(pilot, lambda: "again within" not in text_in(app, status), 10, "")
            said = text_in(app, status)
            assert "the background is as before" in said, said

    asyncio.run(scenario())
