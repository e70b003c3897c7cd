"""The Gestures panel (F2, ``g``) at 80 x 24 keeps the user's work: one ``Esc`` with a
training under way asks first, on the work's line (and the question lapses with its
window), a second one cancels it and the panel says so (it stays open: the next keys are
still the panel's) and the log keeps it; a dataset too small to
train on is refused before the training, in the panel's words (its reps field, ``s``),
never the command line's switches."""

from __future__ import annotations

import asyncio
import logging
import time

import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import text_in

SIZE = (80, 24)


async def _panel_from_camera(app, pilot):
    await wait_for(pilot, lambda: bool(app.query("#camera-status")), 60, "camera screen")
    await wait_for(pilot, lambda: app.focused is app.pane("camera"), 60, "focus on Camera")
    await pilot.press("g")
    await wait_for(pilot, lambda: type(app.screen).__name__ == "GesturesPanel", 30, "panel")
    panel = app.screen
    await wait_for(pilot, lambda: bool(panel.query("#gp-files")), 30, "panel composed")
    await wait_for(pilot, lambda: panel.focused is not None, 30, "a button focused")
    return panel


def _until_cancelled(progress, cancelled):
    progress(0.1, "fold 1/2: training")
    while not cancelled():
        time.sleep(0.02)
    raise RuntimeError("stopped")


def test_esc_with_training_under_way_asks_then_cancels_and_says_so(plugins, monkeypatch, caplog):
    import plugins.gestures.panel as gp

    monkeypatch.setattr(gp, "ESC_AGAIN_S", 1.0)  # the window, shorter for the test

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=SIZE) as pilot:
            panel = await _panel_from_camera(app, pilot)
            work = panel.work
            work.start("training", _until_cancelled, cancelled_says=": no model was written")
            await wait_for(pilot, lambda: work.busy, 10, "training runs")
            await pilot.press("escape")
            await pilot.pause(0.1)
            asked = text_in(app, work)
            assert app.screen is panel and work.busy, asked
            assert "Esc again within 1 s cancels the training; x cancels too" in asked, asked
            # the question lapses with its window: a later Esc asks again
            await wait_for(pilot, lambda: "Esc again" not in text_in(app, work), 5, "lapsed")
            assert work.busy
            await pilot.press("escape")
            await pilot.pause(0.1)
            assert app.screen is panel and work.busy
            await pilot.press("escape")
            await wait_for(pilot, lambda: not work.busy, 10, "cancelled")
            assert app.screen is panel
            said = text_in(app, work)
            assert "training cancelled: no model was written" in said, said

    with caplog.at_level(logging.INFO):
        asyncio.run(scenario())
    assert any("training cancelled" in r.getMessage() for r in caplog.records)


@pytest.fixture(scope="module")
def tiny_dataset(tmp_path_factory):
    from plugins.gestures.jobs import synth_atomic

    path = tmp_path_factory.mktemp("gestures") / "tiny"
    synth_atomic(path, 1, 2, workers=1)  # 1 subject x 10 gestures x 2 reps
    return path


def test_a_tiny_dataset_is_refused_before_training_in_the_panels_words(plugins, tiny_dataset):
    from plugins.gestures.panel import train_refusal

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=SIZE) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
            app.push_screen(plugins.of("panel")["gestures"].factory(app))
            await wait_for(pilot, lambda: type(app.screen).__name__ == "GesturesPanel", 30)
            panel = app.screen
            await wait_for(pilot, lambda: bool(panel.query("#gp-files")), 30, "composed")
            panel.query_one("#gp-dataset", Input).value = str(tiny_dataset)
            panel.action_refresh()
            files = panel.query_one("#gp-files")
            await wait_for(pilot, lambda: "20 samples" in text_in(app, files), 30, "files")
            await pilot.press("t")
            await pilot.pause(0.2)
            said = " ".join(text_in(app, panel.work).split())
            assert not panel.work.busy, said  # refused before the training started
            assert "2 of each gesture (1 subject x 2 reps)" in said, said
            assert "type 4 in reps and s" in said and "--" not in said, said

    asyncio.run(scenario())
    # a refusal worded for the shell met during the training: said in the panel's words
    cli = (
        "model selection: a gesture has fewer than 2 training samples to choose the "
        "harmonics and frames on; give --harmonics and --frames, or record more samples"
    )
    info = {"subjects": ["s1"], "gestures": 10, "samples": 20}
    assert "--" not in train_refusal(cli, info, "2fold")
    assert "--" not in train_refusal("--cv loso: the dataset has one subject", info, "loso")
