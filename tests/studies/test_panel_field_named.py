"""Studies (F10) at 80 x 24: the footer names the field that has the focus and what
Enter and Esc do there, as the Camera and Signals fields say theirs (on a new operator's
try, Tab onto the participant id, the folder or an age showed only ``^e E-STOP f1-f10
screens``: nothing said which field typed or how to leave it). Enter moves on to the
next field, Esc leaves for Start (what was typed stays)."""

from __future__ import annotations

import asyncio

from textual.widgets import Input, Select

from .studies_pilot import studies_app, studies_pane, wait_for

#: each field's id and the name its footer gives it
NAMES = {
    "protocol": "protocol",
    "participant": "participant id",
    "out": "folder",
    "age": "age",
    "sex": "sex",
    "handedness": "handedness",
    "hand_width_cm": "hand width cm",
    "hand_length_cm": "hand length cm",
}


def _footer(app) -> str:
    return app.screen._compositor.render_strips()[-1].text


def test_tab_onto_each_field_names_it_with_its_enter_and_esc(plugins):
    async def scenario():
        app = studies_app(plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await studies_pane(pilot, app)
            await wait_for(pilot, lambda: app.focused is pane.focus_target, 30, "Start")
            seen: dict[str, str] = {}
            for _ in range(30):  # round the screen's Tab stops once
                await pilot.press("tab")
                await pilot.pause(0.15)  # the footer rebuilds after a refresh
                focused = app.focused
                if isinstance(focused, Input | Select) and focused.id in NAMES:
                    seen[focused.id] = " ".join(_footer(app).split())
            assert set(seen) == set(NAMES), sorted(seen)
            for wid, footer in seen.items():
                name = NAMES[wid]
                assert footer.startswith(f"{name}: ⏎ "), (wid, footer)
                assert "esc leave" in footer, (wid, footer)
                others = [n for n in NAMES.values() if n != name and f"{n}:" in footer]
                assert not others, (wid, footer)  # the focused field's name, no other's
            for wid in ("participant", "out", "age"):
                assert seen[wid].startswith(f"{NAMES[wid]}: ⏎ next field esc leave"), seen[wid]
            # Enter moves on to the next Tab stop; Esc leaves for Start, the text kept
            age = pane.query_one("#age", Input)
            age.focus()
            await pilot.pause(0.1)
            await pilot.press("4", "2", "enter")
            await wait_for(pilot, lambda: app.focused is pane.query_one("#sex"), 5, "sex")
            assert age.value == "42", age.value
            await pilot.press("escape")
            await wait_for(pilot, lambda: app.focused is pane.focus_target, 5, "Start")
            assert age.value == "42", age.value

    asyncio.run(scenario())
