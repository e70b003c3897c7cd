"""A check box's and a switch's state reads in characters, not in shades: a new operator
read an unticked "record trials" as on (Textual's ``▐X▌`` is drawn in both states). The
Studies check boxes show ``[x]`` / ``[ ]``, the Relays switches ``[on ]`` / ``[off]``,
at 80 x 24 and 120 x 40; no source builds a bare ``Checkbox`` or ``Switch``."""

from __future__ import annotations

import ast
import asyncio
from pathlib import Path

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import SIZES, screen_lines

ROOT = Path(__file__).resolve().parents[2]


def _bare_toggles() -> list[str]:
    """Where a source builds Textual's own ``Checkbox(...)`` or ``Switch(...)``."""
    found = []
    for top in ("console", "plugins"):
        for path in (ROOT / top).rglob("*.py"):
            if path.name == "ticks.py":
                continue
            for node in ast.walk(ast.parse(path.read_text())):
                if not isinstance(node, ast.Call):
                    continue
                f = node.func
                name = f.id if isinstance(f, ast.Name) else getattr(f, "attr", "")
                if name in ("Checkbox", "Switch"):
                    found.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    return found


def test_every_check_box_and_switch_says_its_state_in_characters():
    assert _bare_toggles() == []


def _shown(app) -> str:
    return "\n".join(screen_lines(app))


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_studies_check_boxes_show_x_or_blank(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.pane("studies") is not None, 30, "studies")
            await wait_for(pilot, lambda: "record trials" in _shown(app), 30, "the box")
            assert "[ ] record trials" in _shown(app), _shown(app)
            assert "[x] simulated" in _shown(app), _shown(app)
            box = app.pane("studies").query_one("#record")
            box.focus()
            await pilot.press("space")
            await wait_for(pilot, lambda: "[x] record trials" in _shown(app), 5, "ticked")

    asyncio.run(scenario())


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_relay_switches_say_on_or_off(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")

            def row() -> str:
                return next(x for x in screen_lines(app) if "relay 3" in x)

            await wait_for(pilot, lambda: "[off]" in row(), 10, "relay 3 off")
            await pilot.press("3")
            await wait_for(pilot, lambda: "[on ]" in row(), 10, "relay 3 on")

    asyncio.run(scenario())


def _luminance(rgb) -> float:
    """WCAG relative luminance of an (r, g, b) colour."""
    lin = [(c / 255) / 12.92 if c <= 10 else ((c / 255 + 0.055) / 1.055) ** 2.4 for c in rgb]
    return 0.2126 * lin[0] + 0.7152 * lin[1] + 0.0722 * lin[2]


def _mark_contrasts(app, mark: str) -> list[float]:
    """The WCAG contrast of each ``mark`` drawn on the screen, its colour on its ground."""
    found = []
    for strip in app.screen._compositor.render_strips():
        for seg in strip:
            if mark in seg.text and seg.style is not None and seg.style.color is not None:
                fg = seg.style.color.get_truecolor()
                bg = seg.style.bgcolor.get_truecolor()
                lum = sorted((_luminance(fg), _luminance(bg)), reverse=True)
                found.append((lum[0] + 0.05) / (lum[1] + 0.05))
    return found


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_ticked_and_unticked_marks_read_on_their_ground(plugins, size):
    """A new operator could not read ``[ ]`` (black on dark navy, colour 16 on 17); both
    marks have at least WCAG's 4.5:1 contrast."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: "record trials" in _shown(app), 30, "the box")
            await pilot.pause(0.2)
            for mark in ("[ ]", "[x]"):
                contrasts = _mark_contrasts(app, mark)
                assert contrasts and min(contrasts) >= 4.5, (mark, contrasts)

    asyncio.run(scenario())
