"""A field holding a path or typed work keeps it when it takes the focus (a new operator
tabbed into the Studies folder field, typed one character and the whole default path
was replaced: the focus had selected all of it)."""

from __future__ import annotations

import asyncio

from textual.widgets import Input

from .studies_pilot import studies_app, studies_pane, wait_for


def test_typing_in_the_folder_field_adds_to_the_path(double_plugins):
    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await studies_pane(pilot, app)
            for wid in ("out", "participant"):
                field = pane.query_one(f"#{wid}", Input)
                before = field.value
                assert before, wid
                pane.focus()
                await wait_for(
                    pilot, lambda: app.focused is pane.focus_target, 30, "the screen's keys"
                )
                field.focus()
                await wait_for(pilot, lambda f=field: app.focused is f, 30, f"{wid} focused")
                await pilot.press("x")
                assert field.value == before + "x", (wid, before, field.value)

    asyncio.run(scenario())
