"""The Studies screen's order is its layout's (a new operator's try found the footer's
keys and the Tab order not matching it): the footer names the buttons' keys in the
buttons' left-to-right order (Replay's `r` in the help: the footer's room goes to `t`),
and Tab visits
the fields and buttons as they read, top to bottom and left to right, with no stop that
shows nothing (the screen itself)."""

from __future__ import annotations

import asyncio

import pytest

from .studies_pilot import studies_app, studies_pane, wait_for

#: the buttons left to right and the key each has in the footer
BUTTON_KEYS = (("start", "s start"), ("pause", "p pause"), ("replay", "r replay"),
               ("abort", "a abort"), ("analyse", "n analyse"))  # fmt: skip


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_footer_and_tab_follow_the_layout(double_plugins, size):
    from textual.widgets import Footer

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await studies_pane(pilot, app)
            await wait_for(pilot, lambda: app.focused is pane.focus_target, 20, "Start")
            footer = app.screen.query_one(Footer)
            await pilot.pause(0.3)
            shown = [s.text for s in app.screen._compositor.render_strips()][-1]
            at = [shown.find(key) for _, key in BUTTON_KEYS if key in shown]
            assert at == sorted(at), shown  # the buttons' order
            assert "s start" in shown and "a abort" in shown, shown
            assert footer is not None
            # Tab from the first field: the reading order of what it visits
            protocol = pane.query_one("#protocol")
            protocol.focus()
            await wait_for(pilot, lambda: app.focused is protocol, 10, "the first field")
            stops = []  # every Tab stop round to the first field again
            for _ in range(40):
                await pilot.press("tab")
                if app.focused is protocol:
                    break
                stops.append(app.focused)
            assert pane not in stops, [w.id for w in stops]  # no stop showing nothing
            seen = [protocol] + [w for w in stops if pane in w.ancestors]
            seen = seen[: [w.id for w in seen].index("study-trials") + 1]
            where = [(w.region.y, w.region.x) for w in seen]
            assert where == sorted(where), [(w.id, r) for w, r in zip(seen, where, strict=True)]
            assert [w.id for w in seen][:2] == ["protocol", "participant"]
            assert "start" in [w.id for w in seen] and "analyse" in [w.id for w in seen]

    asyncio.run(scenario())
