"""Every field of every screen names itself in the footer (80 x 24), the console's rule,
not one screen's: a new operator's try (issue 27, item 9) found Gestures' subjects and
reps showing only ``esc back ^e E-STOP ? help f1-f10 screens``, and Signals' expression,
name and target all showing ``^e E-STOP ^o play ^s save ...``: after Tab from the
library the operator typed `` * 2`` into the target, taking it for the expression.

The walk: F1..F10 and the Gestures panel (Camera, ``g``); on each, Tab round the whole
chain, then the keys that open a field (Camera ``o`` and ``U``, Vibration ``:``, Scope
``o``). Wherever a text field, a number field or a drop-down has the focus it is on
screen and the footer's first words are its name (``target:``), then what Enter does
there (and Esc, in a text field), E-STOP kept (a path field, which types every key, ``?``
too, dropped it from the Gestures panel's footer). Every field a screen holds is reached one way or the
other: a new field not named here fails the walk."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Input, Select

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.focus_keys import name_field
from plugins.studies.panel_fields import FIELD_NAMES as STUDIES_NAMES

from .conftest import wait_for

#: each field's id and the name the footer gives it first
NAMES = {
    "stimulus": "test signal",  # Devices' drop-down
    "camera-recording": "recording",
    "camera-target": "TUIO target",
    "vib-cmd": "command",
    "sig-expr": "expression",
    "sig-name": "name",
    "sig-target": "target",
    "scope-recording": "recording",
    "gp-dataset": "dataset",
    "gp-subjects": "subjects",
    "gp-reps": "reps",
    "gp-cv": "cv",
    "gp-model": "model",
    **STUDIES_NAMES,
}
#: the keys that open a field on a screen (the field is no Tab stop until then)
OPENERS = {"camera": ("o", "U"), "vibration": ("colon",), "scope": ("o",)}


def _footer(app) -> str:
    return " ".join(app.screen._compositor.render_strips()[-1].text.split())


def _visible(app, widget) -> bool:
    """Whether ``widget`` shows on the screen: drawn, its first row on it, above the
    footer and the safety bar."""
    r = widget.region
    return (
        widget in app.screen._compositor.visible_widgets
        and r.width > 0
        and 0 <= r.y < app.screen.region.height - 2
    )


def _fields(screen, scope) -> set[str]:
    return {w.id for w in scope.query("Input, Select") if w.id and w.screen is screen}


async def _look(app, pilot, seen: dict, where: str) -> None:
    focused = app.focused
    if not isinstance(focused, Input | Select) or focused.id in seen:
        return
    name = NAMES.get(focused.id, "")
    for _ in range(50):  # the footer rebuilds, the screen scrolls, after a refresh
        await pilot.pause(0.1)
        if _visible(app, focused) and _footer(app).startswith(f"{name}: "):
            break
    seen[focused.id] = (where, _footer(app), _visible(app, focused), isinstance(focused, Input))


async def _tab_round(app, pilot, seen: dict, where: str) -> None:
    await wait_for(pilot, lambda: app.focused is not None, 30, f"a focus on {where}")
    first = app.focused
    for _ in range(40):
        await _look(app, pilot, seen, where)
        await pilot.press("tab")
        await pilot.pause(0.05)
        if app.focused is first:
            break


def _problems(seen: dict) -> list[str]:
    bad = []
    for wid, (where, footer, visible, text) in seen.items():
        name = NAMES.get(wid, f"<{wid} has no name in NAMES>")
        if not footer.startswith(f"{name}: "):
            bad.append(f"{where} {wid}: footer {footer!r} does not start with {name!r}:")
        elif "⏎ " not in footer or (text and "esc " not in footer):
            bad.append(f"{where} {wid}: footer {footer!r} says no Enter / Esc")
        if footer.split().count("esc") > 1:  # one key, one word (not esc buttons esc back)
            bad.append(f"{where} {wid}: footer {footer!r} says Esc twice")
        if "^e E-STOP" not in footer:  # it acts in every field: the footer says so
            bad.append(f"{where} {wid}: footer {footer!r} lost E-STOP")
        if not visible:
            bad.append(f"{where} {wid}: focused but not on screen")
    return bad


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_every_field_of_every_screen_is_named_first_in_the_footer_and_in_view(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        seen: dict[str, tuple] = {}
        missed: list[str] = []
        async with app.run_test(size=size) as pilot:
            for tab in list(app.tabs):
                key = app.tabs[tab][1]
                await pilot.press(key)
                await wait_for(pilot, lambda t=tab: app.active_tab == t, 30, tab)
                await wait_for(pilot, lambda t=tab: app.pane(t) is not None, 30, f"{tab} pane")
                pane = app.pane(tab)
                await pilot.pause(0.5)
                await _tab_round(app, pilot, seen, tab)
                for opener in OPENERS.get(tab, ()):
                    pane.focus()
                    await pilot.pause(0.2)
                    await pilot.press(opener)
                    await wait_for(pilot, lambda: isinstance(app.focused, Input), 10, opener)
                    await _look(app, pilot, seen, f"{tab} {opener}")
                    await pilot.press("escape")
                    await pilot.pause(0.2)
                missed += [f"{tab} {f}" for f in _fields(app.screen, pane) - set(seen)]
            await pilot.press(app.tabs["camera"][1])
            await wait_for(pilot, lambda: app.active_tab == "camera", 30, "camera")
            app.pane("camera").focus()
            await pilot.pause(0.3)
            await pilot.press("g")
            await wait_for(pilot, lambda: type(app.screen).__name__ == "GesturesPanel", 30, "g")
            panel = app.screen
            await wait_for(pilot, lambda: panel.focused is not None, 30, "a button focused")
            await _tab_round(app, pilot, seen, "gestures")
            missed += [f"gestures {f}" for f in _fields(panel, panel) - set(seen)]
        problems = _problems(seen) + [f"{m}: reached neither by Tab nor a key" for m in missed]
        assert not problems, "\n".join(problems)

    asyncio.run(scenario())


def test_a_long_field_name_wins_over_help_and_screens_never_over_e_stop(plugins):
    """Where a field's name and words do not fit beside the keys every screen shows, the
    name stays: ``? help`` and ``f1-f10 screens`` give way (``?`` lists every key), E-STOP
    never does. Before, those three were kept whatever the width and the name went."""
    long_name = "the channel this signal is meant for (PA, PA,PC or screen)"

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.pane("signals") is not None, 30, "signals")
            target = app.query_one("#sig-target", Input)
            name_field(target, long_name, enter="plot", escape="leave")
            target.focus()
            await wait_for(pilot, lambda: app.focused is target, 10, "the target")
            await wait_for(pilot, lambda: _footer(app).startswith(long_name), 10, "the name")
            footer = _footer(app)
            assert "^e E-STOP" in footer, footer
            assert "⏎ plot" in footer, footer
            assert "^o play" not in footer, footer  # the screen's own keys went first

    asyncio.run(scenario())
