"""Issue 27 (a new operator's try): ``s`` refused a person's run for its age
(``age = '-5': give whole years``) and the line stayed under another participant's
progress once the participant changed. A refusal is about the fields and the run as
they were: it goes when they change."""

from __future__ import annotations

import asyncio

import pytest

from .studies_pilot import studies_app, studies_pane, wait_for


def _status(pane) -> str:
    return " ".join(str(pane.query_one("#study-status").render()).split())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_an_age_refusal_goes_with_another_participant(double_plugins, map_file, tmp_path, size):
    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            pane.query_one("#out").value = str(tmp_path / "results")
            pane.query_one("#simulate").value = False
            pane.query_one("#age").value = "-5"
            await pilot.pause(0.2)
            pane.focus()
            await pilot.press("s")
            await wait_for(pilot, lambda: "give whole years" in _status(pane), 10, "refused")
            assert pane.running is None
            pane.query_one("#participant").value = "P03"
            await wait_for(
                pilot, lambda: "give whole years" not in _status(pane), 5, "the line goes"
            )
            assert pane.running is None

    asyncio.run(scenario())
