"""Issue 27 (Scenes, 120 x 40 and 80 x 24): Tab visits only widgets that act on keys (the
scenes table, the demos table, the tab bar), each visibly focused and named in the
footer by what its keys do: "start scene", "start/stop demo", "←→ screens"."""

from __future__ import annotations

import asyncio

from textual.widgets import DataTable
from textual.widgets._tabbed_content import ContentTabs

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for

#: what the footer says while each Tab stop has the focus
NAMED = {"scene-table": "start scene", "demo-table": "start/stop demo", "tabs": "←→ screens"}


def _lines(app) -> list[str]:
    return [strip.text for strip in app.screen._compositor.render_strips()]


def _stop(widget) -> str:
    if isinstance(widget, ContentTabs):
        return "tabs"
    assert isinstance(widget, DataTable), f"Tab stopped on {widget!r}"
    return widget.id


def _cursor_style(app, word: str):
    """The style of ``word`` where the screen shows it (a table's cursor row)."""
    for strip in app.screen._compositor.render_strips():
        for seg in strip:
            if word in seg.text:
                return seg.style
    raise AssertionError(f"{word!r} not on screen")


async def _tab_round(app, pilot) -> dict[str, str]:
    """Tab through the screen once: each stop's footer."""
    seen: dict[str, str] = {}
    for _ in range(4):
        await pilot.press("tab")
        await pilot.pause()
        stop = _stop(app.focused)
        await wait_for(pilot, lambda s=stop: NAMED[s] in _lines(app)[-1], 10, f"{stop} named")
        seen[stop] = _lines(app)[-1]
    return seen


def test_tab_stops_act_and_are_named(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(120, 40)) as pilot:
            scenes = lambda: app.query_one("#scene-table")  # noqa: E731
            await wait_for(pilot, lambda: app.focused is scenes(), 30, "scenes focused")
            seen = await _tab_round(app, pilot)
            assert set(seen) == set(NAMED), seen
            for stop, footer in seen.items():  # each named, the others' names absent
                others = [NAMED[o] for o in NAMED if o != stop and NAMED[o] not in NAMED[stop]]
                assert not any(name in footer for name in others), footer
            # the focused table's cursor row is drawn apart from the other table's
            scenes().focus()
            await wait_for(pilot, lambda: app.focused is scenes(), 10, "scenes again")
            focused = _cursor_style(app, "alignment")
            app.query_one("#demo-table").focus()
            await pilot.pause()
            assert _cursor_style(app, "alignment") != focused
            await pilot.resize_terminal(80, 24)
            await wait_for(pilot, lambda: app.size.width == 80, 10, "80 columns")
            assert set(await _tab_round(app, pilot)) == set(NAMED)

    asyncio.run(scenario())
