"""Every text field on every screen takes whatever an operator types without closing
the console: a name no folder can take, a slash, a bracket, a huge number, letters
where a number goes, nothing at all; then Enter. The field may refuse it (one line),
never the console (a new operator typed ``P 0/`` as a participant and the console
closed with a traceback)."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp, panel_tabs

from .conftest import wait_for

#: the panels without a tab (pushed over the screens by a key or the palette)
MODALS = ("gestures",)
#: screens without a text field of their own
NO_FIELDS = ("devices", "relays", "electrostatic", "scenes", "latency")
TYPED = ("P 0/", "../../x", "[red]x", "'", "1e999", "-1", "nan", "abc", "", "9" * 80, "é ✓")


#: the screens with a tab (checked against the plugins' registrations below)
TABS = (
    "devices",
    "camera",
    "vibration",
    "relays",
    "electrostatic",
    "scenes",
    "latency",
    "signals",
    "scope",
    "studies",
)


def test_every_screen_is_typed_into(plugins):
    assert tuple(panel_tabs(plugins)) == TABS


@pytest.mark.parametrize("tab", TABS)
def test_fields_take_any_text(plugins, tab):
    _check(plugins, tab)


def _check(plugins, tab: str) -> None:
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial=tab)
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            await wait_for(pilot, lambda: app.pane(tab) is not None, what=tab)
            await pilot.pause(0.3)
            fields = list(app.pane(tab).query(Input))
            assert fields or tab in NO_FIELDS, tab
            await _type_into(app, pilot, fields, tab)
            assert app.is_running and app._exception is None, tab

    asyncio.run(scenario())


async def _type_into(app, pilot, fields: list[Input], where: str) -> None:
    """Each of ``TYPED`` into each field, then Enter; the console still running."""
    for field in fields:
        for text in TYPED:
            if field.disabled:
                break
            if field.display:  # a field shown: typed into as a person would
                field.focus()
                await pilot.pause()
            field.value = text
            await pilot.pause()
            await field.action_submit()  # Enter (a hidden one's key opens it)
            await pilot.pause(0.05)
            assert app.is_running and app._exception is None, (where, field.id, text)
            if app.session.outputs.estopped:
                break


def _modal_panels(plugins) -> list[str]:
    return sorted(n for n, r in plugins.of("panel").items() if r.tab is None)


def test_every_modal_panel_is_typed_into(plugins):
    assert _modal_panels(plugins) == list(MODALS)


@pytest.mark.parametrize("name", MODALS)
def test_modal_panel_fields_take_any_text(plugins, name):
    """The panels opened by a key or the palette (Camera's ``g``: Gestures)."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            app.push_screen(plugins.of("panel")[name].factory(app))
            await pilot.pause(0.5)
            fields = list(app.screen.query(Input))
            assert fields, name
            await _type_into(app, pilot, fields, name)
            assert app.is_running and app._exception is None, name

    asyncio.run(scenario())
