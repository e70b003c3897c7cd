"""The Gestures panel says how big and how long a synthesis is before it starts, and
starts it only on a second ``s`` (issue 27: 5 x 40 was ~2.3 GB and ~20 min, unannounced)."""

from __future__ import annotations

import asyncio

from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


def test_synth_says_size_and_time_then_asks(plugins, tmp_path):
    ds = tmp_path / "set"

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
            app.push_screen(plugins.of("panel")["gestures"].factory(app))
            await wait_for(pilot, lambda: type(app.screen).__name__ == "GesturesPanel")
            panel = app.screen
            await wait_for(pilot, lambda: bool(panel.query("#gp-files")), what="panel composed")
            work = panel.work
            panel.query_one("#gp-dataset", Input).value = str(ds)
            panel.query_one("#gp-subjects", Input).value = "1"
            panel.query_one("#gp-reps", Input).value = "1"

            # first s: the size and the time, measured; nothing written
            await pilot.press("s")
            await wait_for(pilot, lambda: work.outcome is not None, 60, "estimate")
            assert work.outcome == "done", work.text
            text = work.text
            assert "1 x 10 x 1 = 10 samples" in text and "about" in text, text
            assert " MB and " in text and text.startswith("s again within"), text
            assert not ds.exists()

            # the fields changed: s measures again instead of starting
            panel.query_one("#gp-reps", Input).value = "2"
            await pilot.press("s")
            await wait_for(pilot, lambda: work.outcome is not None, 60, "estimate again")
            assert "1 x 10 x 2 = 20 samples" in work.text and not ds.exists()

            # another action in between (t: no dataset yet) replaces the question: s
            # then measures again, it never starts what is no longer on the screen
            await pilot.press("t")
            await wait_for(pilot, lambda: "s again" not in work.text, 30, "t answered")
            await pilot.press("s")
            await wait_for(pilot, lambda: work.outcome is not None, 60, "estimate, third")
            assert "s again within" in work.text and not ds.exists()

            # s again: the synthesis it announced
            await pilot.press("s")
            await wait_for(pilot, lambda: work.outcome is not None, 120, "synthesis")
            assert work.outcome == "done", work.text
            assert "synthesized 20 samples (1 x 10 x 2)" in work.text
            assert ds.is_dir()

    asyncio.run(scenario())
