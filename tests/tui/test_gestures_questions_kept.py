"""The Gestures panel (Camera F2, ``g``) at 80 x 24 and 120 x 40: what it asks or refuses
while a training reports progress stays on the screen until answered or its window ends
(new operator's try: ``Esc`` during a training asked nothing the screen showed, yet a
second ``Esc`` cancelled; an F-key's refusal was gone before it could be read), and a
cancel leaves the operator in the panel (the next ``t`` trained again instead of
lowering the Camera screen's body threshold)."""

from __future__ import annotations

import asyncio
import logging
import time

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines
from .test_gestures_work_kept import _panel_from_camera

SIZES = [(80, 24), (120, 40)]


def _shown(app) -> str:
    """The whole screen's words, a wrapped line read as one."""
    return " ".join(" ".join(screen_lines(app)).split())


def _ticking(reports: list[int]):
    """A job reporting progress every 20 ms (as a training's folds do) until cancelled."""

    def job(progress, cancelled):
        n = 0
        while not cancelled():
            n += 1
            reports.append(n)
            progress(0.45, f"fold 1/2: training ({n})")
            time.sleep(0.02)
        raise RuntimeError("stopped")

    return job


async def _stays(pilot, app, text: str, reports: list[int], ticks: int = 5) -> None:
    """``text`` stays on the screen while the job reports ``ticks`` more times."""
    until = len(reports) + ticks
    while len(reports) < until:
        await pilot.pause(0.05)
        assert text in _shown(app), _shown(app)


async def _training(app, pilot):
    """The Gestures panel opened from Camera, a training under way reporting its
    progress: (the panel, its reports so far)."""
    panel = await _panel_from_camera(app, pilot)
    reports: list[int] = []
    panel.work.start("training", _ticking(reports))
    await wait_for(pilot, lambda: len(reports) > 5, 10, "training reports")
    return panel, reports


@pytest.mark.parametrize("size", SIZES)
def test_esc_asks_on_the_screen_while_progress_ticks_and_a_cancel_stays(plugins, size, caplog):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            panel, reports = await _training(app, pilot)
            await pilot.press("escape")
            asked = "Esc again within 3 s cancels the training"
            await wait_for(pilot, lambda: asked in _shown(app), 5, f"asked: {_shown(app)}")
            await _stays(pilot, app, asked, reports)
            assert asked in caplog.text  # and in the log
            assert "fold 1/2: training" in _shown(app)  # the progress shows too
            await pilot.press("escape")
            await wait_for(pilot, lambda: not panel.work.busy, 10, "cancelled")
            # the operator stays where they were: the panel shows the cancel
            assert app.screen is panel
            await wait_for(pilot, lambda: "training cancelled" in _shown(app), 5, _shown(app))
            # the next letter is the panel's (t trains), not the Camera screen's
            await pilot.press("t")
            await pilot.pause(0.2)
            assert app.screen is panel
            await pilot.press("escape")  # idle: Esc goes back
            await wait_for(pilot, lambda: app.screen is app.base, 10, "back on Camera")

    with caplog.at_level(logging.INFO):
        asyncio.run(scenario())


@pytest.mark.parametrize("size", SIZES)
def test_an_f_keys_refusal_stays_while_progress_ticks(plugins, size, monkeypatch):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            panel, reports = await _training(app, pilot)
            await pilot.press("f6")
            refused = "training runs here: x cancels it, then the F-key again"
            await wait_for(pilot, lambda: refused in _shown(app), 5, f"refused: {_shown(app)}")
            await _stays(pilot, app, refused, reports)
            assert app.screen is panel
            await pilot.press("x")
            await wait_for(pilot, lambda: not panel.work.busy, 10, "cancelled")
            assert refused not in _shown(app)  # answered: the job's end replaces it
            assert app.screen is panel

    asyncio.run(scenario())
