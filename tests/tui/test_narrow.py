"""At 80 columns every screen's tab shows in the tab bar (titles shortened to fit when
they must), and the footer shows whole keys only: the screen's most important first,
E-STOP and ``?`` (the help, which lists the rest) always."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Footer, Tabs
from textual.widgets._footer import FooterKey

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for

SIZES = [(80, 24), (120, 40)]


def _lines(app) -> list[str]:
    return [strip.text for strip in app.screen._compositor.render_strips()]


def _shown(app, region) -> str:
    row = _lines(app)[region.y]
    return row[region.x : region.right]


def test_fit_titles_shortens_the_longest_first():
    from console.tui.narrow import fit_titles

    titles = ["Devices", "Camera", "Vibration", "Electrostatic", "Scope"]
    assert fit_titles(titles, 200) == titles
    short = fit_titles(titles, 35)
    assert sum(map(len, short)) <= 35
    assert short[1] == "Camera" and short[4] == "Scope"  # the short ones are kept
    assert short[3].endswith("…") and "Electrostatic".startswith(short[3][:-1])
    for title, got in zip(titles, fit_titles(titles, 10), strict=True):
        assert got == title or (got.endswith("…") and title.startswith(got[:-1]))


def _check_tabs(app, where: str) -> None:
    tabs = app.query_one("#tabs").query_one(Tabs)
    screen = app.screen.region
    titles = {tab: title for tab, (title, _key, _reg) in app.tabs.items()}
    for tab in tabs.query("Tab"):
        pane_id = tab.id.removeprefix("--content-tab-")
        label = tab.label.plain
        assert screen.contains_region(tab.region), f"{where}: tab {label!r} at {tab.region}"
        assert label in _shown(app, tab.region), (where, label, _shown(app, tab.region))
        title = titles[pane_id]
        assert label == title or (label.endswith("…") and title.startswith(label[:-1])), (
            where,
            title,
            label,
        )


def _footer_laid_out(app) -> bool:
    """The footer recomposes after the focus moved (its keys mount, then are laid out)."""
    keys = [k for k in app.screen.query_one(Footer).query(FooterKey) if k.display]
    return bool(keys) and all(k.region.area > 0 for k in keys)


def _check_footer(app, where: str) -> list[str]:
    footer = app.screen.query_one(Footer)
    keys = [k for k in footer.query(FooterKey) if k.display]
    assert keys, f"{where}: an empty footer"
    for k in keys:
        assert footer.region.contains_region(k.region), (where, k.key, k.region)
        assert k.description in _shown(app, k.region), (where, k.key, _shown(app, k.region))
    shown = [k.key for k in keys]
    assert "question_mark" in shown, f"{where}: no ? help in {shown}"
    assert "ctrl+e" in shown, f"{where}: no E-STOP in {shown}"
    return shown


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_every_tab_and_the_help_key_show_on_every_screen(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            assert len(app.tabs) >= 10  # Studies and Scope included
            for tab, (_title, key, _reg) in app.tabs.items():
                await pilot.press(key)
                await wait_for(pilot, lambda t=tab: app.active_tab == t, 10, tab)
                await pilot.pause(0.3)
                await wait_for(pilot, lambda: _footer_laid_out(app), 10, "the footer laid out")
                _check_tabs(app, f"{tab} at {size}")
                shown = _check_footer(app, f"{tab} at {size}")
                if tab == "camera":  # the screen's own keys that open something: in
                    # the footer, or on the keys line under the view, whole on screen
                    line = app.query_one("#camera-keys")
                    said = _shown(app, line.region)
                    assert line.region.width and app.screen.region.contains_region(line.region)
                    assert "k" in shown and "g gestures" in said and "u U TUIO" in said, (
                        shown,
                        said,
                    )

    asyncio.run(scenario())
