"""The keys the console promises work wherever the focus is, and typed work is never lost
to one: ``?`` opens the help from a text field too (no signal expression takes ``?``),
ctrl+z brings back what a key replaced in a field. The help reads as paragraphs wrapped
to the terminal (no line broken early, no orphan word), and every screen says what it
shows."""

from __future__ import annotations

import asyncio

import pytest
from textual.geometry import Region
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.glue import groups
from console.tui.help import ENTRY  # the help's own notion of an entry

from .conftest import wait_for

EXPR = "seq(sine(250 Hz, 40 V, 0.5 s) * adsr(10 ms, 50 ms, 0.7, 100 ms), silence(0.2 s)) * 3"
SIZES = [(80, 24), (120, 40)]


def _is_help(app) -> bool:
    return type(app.screen).__name__ == "HelpScreen"


async def _signals_with_expression(app, pilot) -> Input:
    """The tester's steps: F8, the expression, Enter, F3, F8 (the field has the focus)."""
    await pilot.press("f8")
    await wait_for(pilot, lambda: app.query("#sig-expr"), 10, "signals built")
    expr = app.query_one("#sig-expr", Input)
    await _focused(app, pilot, expr)
    expr.value = EXPR
    await pilot.press("enter")
    await pilot.press("f3")
    await wait_for(pilot, lambda: app.active_tab == "vibration", 10, "f3")
    await pilot.press("f8")
    await wait_for(pilot, lambda: app.active_tab == "signals", 10, "f8")
    await _focused(app, pilot, expr)
    return expr


async def _focused(app, pilot, field: Input) -> None:
    """``field`` has the focus as F8 gives it (the switch's focus request gives up after
    a few seconds on a loaded machine: then it is focused as a click would)."""
    try:
        await wait_for(pilot, lambda: app.focused is field, 8, "expression focused")
    except AssertionError:
        field.focus()
        await wait_for(pilot, lambda: app.focused is field, 5, "expression focused")


@pytest.mark.parametrize("size", SIZES)
def test_question_mark_opens_help_from_the_expression_and_keeps_it(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            expr = await _signals_with_expression(app, pilot)
            from .test_field_types_question_mark import _footer

            assert "? help" in _footer(app)  # what the screen promises ...
            await pilot.press("question_mark")
            await wait_for(pilot, lambda: _is_help(app), 5, "help open")  # ... works
            assert expr.value == EXPR  # and the signal being designed is still there
            await pilot.press("escape")
            await wait_for(pilot, lambda: not _is_help(app), 5, "help closed")
            assert expr.value == EXPR

    asyncio.run(scenario())


def test_ctrl_z_brings_back_what_a_key_replaced(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(120, 40)) as pilot:
            expr = await _signals_with_expression(app, pilot)
            # with the whole line selected, a typed key replaces it (as in any editor)
            expr.select_all()
            await pilot.press("x")
            assert expr.value == "x"
            await pilot.press("ctrl+z")
            assert expr.value == EXPR
            await pilot.press("ctrl+t")  # the ramp added in plain sight: undone too
            assert expr.value.endswith("* ramp(5 ms)")
            await pilot.press("ctrl+z")
            assert expr.value == EXPR

    asyncio.run(scenario())


# ---------------------------------------------------------------------- the help's text
#: the start of a new entry: ``b        capture``, ``t / T    body``, ``s: synthesize``


def _help_lines(app) -> tuple[list[str], int]:
    """The help as the terminal shows it: every line of the text widget, and its width."""
    w = app.screen.query_one("#help-text")
    strips = w.render_lines(Region(0, 0, w.size.width, w.size.height))
    return [s.text.rstrip() for s in strips], w.size.width


def broken_early(lines: list[str], width: int) -> list[str]:
    """Lines that end inside a paragraph although the next line's first word (with the
    unit glued to it, ``console.tui.glue``) would have fit on them: a hard line break (an orphan word when the widget wraps it again)."""
    bad = []
    for line, nxt in zip(lines, lines[1:], strict=False):
        if not line.strip() or not nxt.strip() or ENTRY.match(nxt.lstrip()):
            continue
        continues = nxt[0].isspace() or nxt[0].islower() or nxt[0] in "(0123456789"
        word = groups(nxt.lstrip())[0]  # a number goes with its unit (``glue``)
        if continues and len(line) + 1 + len(word) <= width:
            bad.append(f"{line!r} / {nxt!r}")
    return bad


@pytest.mark.parametrize("size", SIZES)
@pytest.mark.parametrize("tab", ["signals", "camera"])
def test_help_is_wrapped_to_the_terminal(plugins, size, tab):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial=tab)
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.pane(tab) is not None, 10, "pane")
            await pilot.pause(0.3)
            await pilot.press("question_mark")
            await wait_for(pilot, lambda: _is_help(app), 5, "help open")
            await wait_for(pilot, lambda: app.screen.query("#help-text"), 5, "help composed")
            await pilot.pause(0.1)
            lines, width = _help_lines(app)
            assert max(len(ln) for ln in lines) <= width
            text = " ".join(" ".join(lines).split())
            assert "This screen" in text
            # the screen's own keys come first, in view without scrolling (sixth try)
            assert text.index("This screen") < text.index("HapTable console"), text[:200]
            bad = broken_early(lines, width)
            assert not bad, f"help lines broken early at {size}:\n" + "\n".join(bad)

    asyncio.run(scenario())


def test_the_orphan_check_catches_a_hard_break():
    lines = [
        "[ / ]    choose a setting (thresholds, smoothing, blob sizes, background,",
        "rotation,",
        "         mirror, region of interest)",
        "b        capture the background",
    ]
    assert len(broken_early(lines, 76)) == 1  # "rotation," then "mirror," would fit


@pytest.mark.parametrize("size", SIZES)
def test_latency_help_says_what_the_screen_shows(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="latency")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.pane("latency") is not None, 10, "pane")
            await pilot.press("question_mark")
            await wait_for(pilot, lambda: _is_help(app), 5, "help open")
            await wait_for(pilot, lambda: app.screen.query("#help-text"), 5, "help composed")
            await pilot.pause(0.1)
            lines, _width = _help_lines(app)
            text = " ".join(lines)
            section = " ".join(text.split("This screen", 1)[1].split())
            for said in ("p50", "p99", "sparkline", "underrun", "fps", "demo"):
                assert said in section, (said, section)

    asyncio.run(scenario())


@pytest.mark.parametrize("width", [40, 60, 76, 86, 116])
def test_every_screens_help_wraps_without_orphans(width):
    """Every pane's and panel's help (as the help screen wraps it) at any width: no line
    wider than the widget, none broken early, no word lost."""
    from console.tui.help import help_text

    from .test_literal_text import pane_help_texts

    for where, text in pane_help_texts().items():
        lines = help_text(text, width).plain.split("\n")
        assert max(len(ln) for ln in lines) <= width, where
        assert not broken_early(lines, width), (where, broken_early(lines, width))
        assert " ".join(lines).split() == text.split(), where  # every word, in order
