"""What the console looks like at 80 x 24 (the smallest supported terminal): snapshots
of each screen with a stable set of plugins (so another plugin's new registration does
not change them). ``python -m console.tui.screenshot`` takes larger views. Update with ``pytest tests/tui/test_snapshots.py --snapshot-update``
after checking the new SVGs by eye."""

from __future__ import annotations

import difflib
import html
import pickle
import re
from pathlib import Path

import pytest
from pytest_textual_snapshot import node_to_report_path

from console.cli.main import Context
from console.config.plugins import load_plugins
from console.tui.app import HapTableApp

from .conftest import command, wait_for

SIZE = (80, 24)
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(autouse=True)
def _home_is_the_project(monkeypatch):
    """The project's own files read ``~/profiles/...`` wherever it was checked out (a
    path shows under ``~`` or absolute, never relative to the working folder:
    ``console.files.paths.shown_path``): the pictures do not depend on the machine."""
    monkeypatch.setenv("HOME", str(ROOT))


def _app(initial: str, *extra: str) -> HapTableApp:
    builtins = {
        "twin": "plugins.twin",
        "twin.camera": "plugins.twin.camera",
        "twin.plate": "plugins.twin.plate",
        # the plugins whose screens are tabs (F5 Electrostatic, F6 Scenes)
        "electrostatic": "plugins.electrostatic",
        "demos": "plugins.demos",
        **{n: f"plugins.{n}" for n in extra},
    }
    return HapTableApp(Context("sim", load_plugins(builtins=builtins)), fast=True, initial=initial)


def svg_rows(svg: str) -> list[str]:
    """The text of a snapshot, one string per terminal row."""
    rows: dict[float, list[tuple[float, str]]] = {}
    for m in re.finditer(r'<text class="[^"]*" x="([\d.]+)" y="([\d.]+)"[^>]*>(.*?)</text>', svg):
        rows.setdefault(float(m[2]), []).append((float(m[1]), html.unescape(m[3])))
    return ["".join(t for _, t in sorted(r)) for _, r in sorted(rows.items())]


@pytest.fixture
def snap(snap_compare, request):
    """snap_compare that, on a mismatch, prints which rows of text differ (a CI run has
    no report to open)."""

    def compare(app, **kwargs) -> bool:
        if snap_compare(app, **kwargs):
            return True
        data = pickle.loads(node_to_report_path(request.node).read_bytes())
        expected, actual = svg_rows(data[1]), svg_rows(data[2])
        diff = "\n".join(difflib.unified_diff(expected, actual, "expected", "actual", lineterm=""))
        print(diff or "the text is the same: colours or styles differ")
        return False

    return compare


async def _settle(app, pilot) -> None:
    await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
    await pilot.pause(0.3)
    await pilot.wait_for_scheduled_animations()


def test_devices(snap):
    app = _app("devices", "gestures")  # the sim profile's classifier: its doctor row

    async def run_before(pilot):
        await _settle(app, pilot)
        await wait_for(pilot, lambda: app.query_one("#device-table").row_count >= 3)
        # the sound cards come from a worker: the snapshot waits for their rows and the
        # header drawn in line with them
        table = app.query_one("#audio-table")
        await wait_for(pilot, lambda: table.row_count >= 1, 30)

        def header_laid_out() -> bool:
            head, row = table.render_line(0).text, table.render_line(1).text
            return head.find("host API") == row.find("simulated") >= 0

        await wait_for(pilot, header_laid_out, 30, "the sound cards' header laid out")
        await pilot.pause(0.3)

    assert snap(app, terminal_size=SIZE, run_before=run_before)


def test_relays_after_a_toggle(snap):
    app = _app("relays")

    async def run_before(pilot):
        await _settle(app, pilot)
        await pilot.press("3")
        await wait_for(pilot, lambda: app.session.outputs.relay_state() == frozenset({3}))
        await wait_for(pilot, lambda: app.query_one("#relaylog").row_count == 1)
        await pilot.pause(0.5)
        await pilot.wait_for_scheduled_animations()

    assert snap(app, terminal_size=SIZE, run_before=run_before)


def test_vibration_with_a_pair_selected(snap, map_file):
    app = _app("vibration", "vibrotactile")

    async def run_before(pilot):
        await _settle(app, pilot)
        pane = app.pane("vibration")
        await command(app, pilot, f"load {map_file}")
        await wait_for(pilot, lambda: pane.session is not None, 30)
        pane.selected = [51, 52]
        pane.move_cursor(52)
        pane._redraw_grid()
        pane._show_selection()
        await wait_for(pilot, lambda: "lookup table" in str(app.query_one("#vib-info").render()))
        # the tables build in their own worker: under load the status still shows progress
        await wait_for(pilot, lambda: pane.status_text.endswith("; ready"), 60)
        await pilot.pause(0.3)
        await pilot.wait_for_scheduled_animations()

    assert snap(app, terminal_size=SIZE, run_before=run_before)


def test_electrostatic(snap):
    app = _app("electrostatic", "electrostatic")

    async def run_before(pilot):
        await _settle(app, pilot)
        # the setting's lines as the terminal shows them (a loaded machine paints them a
        # frame after the widget has them)
        await wait_for(pilot, lambda: "above threshold" in _painted(app), 30, "the setting")
        await pilot.pause(0.2)

    assert snap(app, terminal_size=SIZE, run_before=run_before)


def _painted(app) -> str:
    """What the terminal shows now."""
    return "\n".join(strip.text for strip in app.screen._compositor.render_strips())


def test_help(snap):
    app = _app("relays")

    async def run_before(pilot):
        await _settle(app, pilot)
        await pilot.press("question_mark")
        await wait_for(pilot, lambda: type(app.screen).__name__ == "HelpScreen")
        await pilot.pause(0.3)
        await pilot.wait_for_scheduled_animations()

    assert snap(app, terminal_size=SIZE, run_before=run_before)
