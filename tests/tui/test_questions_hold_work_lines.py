"""Issue 27: two timed questions were said on a work line (``LongWork``) that other code
writes directly: Scenes' ``k again within 4 s closes the projector`` (held on the pane,
while a demo's progress went to the line itself) and the Gestures panel's ``s again
within 20 s to start`` (the estimate's summary, with a timer of its own). A demo's
progress or any other line said meanwhile replaced the question while ``k`` or ``s``
still did what it asked. The work line's setter waits for a question as every screen's
does: the question stays until it lapses, then the newest line said meanwhile shows."""

from __future__ import annotations

import asyncio

from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import text_in
from .test_issue27_ui_a_scenes import knob_shown_scenes


def test_scenes_k_question_holds_against_a_demo_s_progress(plugins, monkeypatch):
    import plugins.demos.panel as dp

    monkeypatch.setattr(dp, "CLOSE_AGAIN_S", 1.5)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            _pane, work, closed = await knob_shown_scenes(app, pilot, monkeypatch)
            await pilot.press("k")
            asked = "k again within 1.5 s closes the projector"
            await wait_for(pilot, lambda: asked in text_in(app, work), 10, "asks")
            work.show("demo flow: preparing the atlas (2 s left)", 0.5)  # its progress
            work.show("demo flow: preparing the atlas (1 s left)", 0.7)
            await pilot.pause(0.3)
            assert asked in text_in(app, work), text_in(app, work)  # still asked
            await pilot.press("k")  # answered in time: it closes
            await wait_for(pilot, lambda: closed == [1], 10, "closed")

            await pilot.press("k")  # asked again; this time it lapses
            await wait_for(pilot, lambda: asked in text_in(app, work), 10, "asks again")
            work.show("demo flow: preparing the atlas (1 s left)", 0.7)
            await pilot.pause(0.3)
            assert asked in text_in(app, work), text_in(app, work)
            await wait_for(pilot, lambda: asked not in text_in(app, work), 10, "lapsed")
            assert "preparing the atlas (1 s left)" in text_in(app, work)  # the newest
            assert closed == [1]

    asyncio.run(scenario())


def test_gestures_s_question_holds_its_line_until_it_lapses(plugins, tmp_path, monkeypatch):
    import plugins.gestures.panel as gp

    monkeypatch.setattr(gp, "CONFIRM_S", 2.0)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
            app.push_screen(plugins.of("panel")["gestures"].factory(app))
            await wait_for(pilot, lambda: type(app.screen).__name__ == "GesturesPanel")
            panel = app.screen
            await wait_for(pilot, lambda: bool(panel.query("#gp-files")), what="panel composed")
            work = panel.work
            panel.query_one("#gp-dataset", Input).value = str(tmp_path / "set")
            panel.query_one("#gp-subjects", Input).value = "1"
            panel.query_one("#gp-reps", Input).value = "1"
            await pilot.press("s")
            await wait_for(pilot, lambda: work.outcome is not None, 60, "estimate")
            asked = work.text
            assert asked.startswith("s again within 2 s to start"), asked
            work.show("reading the files ...")  # another line meanwhile: it waits
            await pilot.pause(0.3)
            assert work.text == asked, work.text
            await wait_for(pilot, lambda: work.text != asked, 10, "lapsed")
            assert work.text == "reading the files ...", work.text

            await pilot.press("s")  # asked anew; nothing said meanwhile: it says it lapsed
            await wait_for(pilot, lambda: work.text.startswith("s again within"), 60, "again")
            await wait_for(pilot, lambda: "again within" not in work.text, 10, "lapsed")
            assert work.text == gp.ESTIMATE_LAPSED, work.text

    asyncio.run(scenario())
