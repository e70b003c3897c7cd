"""Issue 27, fourth new-user try: the second ``a`` says at once that the run is being
aborted, and says it until the run stopped (not an older line about ``r`` in a
simulated run); then the status says how the run ended."""

from __future__ import annotations

import asyncio

from .studies_pilot import wait_for
from .test_panel_issue27 import _app, _running


def _words(text: str) -> str:
    return " ".join(text.split())


def test_the_second_a_says_aborting_until_the_run_stopped(double_plugins, map_file, tmp_path):
    async def scenario():
        app = _app(double_plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await _running(pilot, app, map_file, tmp_path)
            shown: list[tuple[str | None, str]] = []  # (the run then, the status block)
            write = pane._status

            def spy(text: str) -> None:
                write(text)
                shown.append((pane.running, _words(str(pane.query_one("#study-status").render()))))

            pane._status = spy
            await pilot.press("r")
            await pilot.press("a")
            mark = len(shown)
            await pilot.press("a")
            await wait_for(pilot, lambda: pane.running is None, 30, "the run stopped")
            await wait_for(pilot, lambda: "stopped: aborted" in shown[-1][1], 30, "ended")
            # from the first line that says it (a status written while the key was on its
            # way may still offer "a again"), every line says it until the run stopped
            after = shown[mark:]
            first = next((i for i, (_r, t) in enumerate(after) if "aborting P01's run" in t), None)
            assert first is not None, after
            during = [text for running, text in after[first:] if running]
            assert during, after
            for text in during:
                assert "aborting P01's run" in text, text
                assert "replay:" not in text and "a again" not in text, text
            assert "aborting" not in shown[-1][1], shown[-1]

    asyncio.run(scenario())
