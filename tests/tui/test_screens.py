"""Each screen's main action, driven through the keyboard as an operator would, on the
twin; what played is checked in the twin's recording and relay log."""

from __future__ import annotations

import asyncio
import threading

import numpy as np
import pytest
from textual.widgets import Switch

from console.cli.main import Context
from console.core.types import patches_of
from console.tui.app import HapTableApp
from console.tui.safety_bar import SafetyBar

from .conftest import command, segment_in, wait_for, words_on


def _app(plugins, initial="devices", fast=True):
    return HapTableApp(Context("sim", plugins), fast=fast, initial=initial)


async def _ready(app, pilot):
    """Outputs open and the first screen focused (as a person waits to see it)."""
    await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")

    def focused() -> bool:
        pane = app.pane(app.initial)
        return pane is not None and app.focused is getattr(pane, "focus_target", None)

    await wait_for(pilot, focused, what="first screen focused")


async def _load_map(app, pilot, map_file):
    pane = app.pane("vibration")
    await command(app, pilot, f"load {map_file}")  # typed once the line has the focus
    await wait_for(pilot, lambda: pane.session is not None, 30, "map loaded")
    return pane


async def kept_map_grid(app, pilot, map_file):
    """Vibration with ``map_file`` loaded and a kept map on disk (``m`` asks before
    replacing it), back on its grid (Esc): the pane."""
    await _ready(app, pilot)
    pane = await _load_map(app, pilot, map_file)
    kept = app.session.vibration.cached_map_path()
    kept.parent.mkdir(parents=True, exist_ok=True)
    kept.write_bytes(b"")  # a kept map exists: m asks before replacing it
    await pilot.press("escape")  # back to the grid
    return pane


async def scrolled_then_relays(app, pilot, pane) -> None:
    """Vibration scrolled down (PageDown twice, where it scrolls), then Relays (F4)."""
    await pilot.pause(0.3)
    await pilot.press("pagedown", "pagedown")
    if pane.max_scroll_y > 0:  # at 120 x 40 the screen fits: nothing to scroll
        await wait_for(pilot, lambda: pane.scroll_y > 0, 10, "scrolled down")
    await pilot.press("f4")
    await wait_for(pilot, lambda: app.query_one("#tabs").active == "relays", 10)


async def two_points_asked(app, pilot, pane, asked: str) -> None:
    """On the grid: two points picked (``f`` plays between them), then ``m`` asked
    (``asked`` on the status line)."""
    await wait_for(pilot, lambda: app.focused is pane.focus_target, 10, "grid")
    await pilot.press("enter", "right", "enter")  # two points: f plays between
    await wait_for(pilot, lambda: len(pane.selected) == 2, 10, "two points")
    await pilot.pause(0.5)
    await pilot.press("m")
    await wait_for(pilot, lambda: asked in words_on(app, "#vib-status"), 10, "asked")


def _played_in_recording(out, plan) -> float:
    """Worst |recorded - planned| volts over the plan's segments (piezo channel)."""
    rec = out.recording()
    nz = np.flatnonzero(np.any(rec != 0, axis=1))
    starts = np.concatenate([[nz[0]], nz[1:][np.diff(nz) > 16]])
    worst = 0.0
    for seg in plan.segments:
        errs = [segment_in(rec[:, 0], seg.piezo_v, int(s)) for s in starts]
        worst = max(worst, min(errs))
    return worst


def test_relay_toggle_and_estop(plugins):
    async def scenario():
        app = _app(plugins, "relays", fast=False)
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            bar = app.query_one(SafetyBar)
            await wait_for(pilot, lambda: "E-STOP" in str(bar.render()))
            await pilot.press("1")
            await wait_for(pilot, lambda: app.session.outputs.relay_state() == frozenset({1}))
            await wait_for(pilot, lambda: "relays closed: 1" in str(bar.render()))
            await wait_for(pilot, lambda: app.query_one("#relay-1", Switch).value)
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped)
            assert app.session.outputs.relay_state() == frozenset()
            await wait_for(pilot, lambda: str(bar.render()).startswith(" E-STOP:"))
            assert bar.has_class("estop")
            # a toggle during the e-stop is refused, and the screen says why (the label says
            # "e-stop" for every relay already: wait on the refusal of this key itself)
            pane = app.pane("relays")
            await pilot.press("2")
            await wait_for(pilot, lambda: "e-stop" in pane.refused.get(2, "") and not pane.pending)
            assert "e-stop" in str(app.query_one("#interlock-2").render())
            assert app.session.outputs.relay_state() == frozenset()
            log = app.session.outputs.relay_log()
            assert [(r.channel, r.closed) for r in log] == [(1, True), (1, False)]
            assert all(r.level_v == (0.0, 0.0) for r in log)
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped)
            # the refused toggle is gone: it never runs after the reset
            await asyncio.sleep(0.3)
            assert app.session.outputs.relay_state() == frozenset()
            assert not any(r.channel == 2 for r in app.session.outputs.relay_log())

    asyncio.run(scenario())


def test_a_toggle_during_the_estop_never_runs_after_a_quick_reset(plugins, monkeypatch):
    """The key is refused when it is pressed: a relay command started during the e-stop
    and run after the reset (a slow worker thread: injected here by holding the outputs'
    relay command until the reset is done) would close a relay nobody asked for then."""

    async def scenario():
        app = _app(plugins, "relays")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            out = app.session.outputs
            pane = app.pane("relays")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: out.estopped and out.wait_safe(0))
            reset = threading.Event()
            set_relays = out.set_relays

            def held_until_reset(*a, **kw):
                reset.wait(10)
                return set_relays(*a, **kw)

            monkeypatch.setattr(out, "set_relays", held_until_reset)
            await pilot.press("2")
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not out.estopped)
            reset.set()
            await wait_for(pilot, lambda: not pane.pending, what="the toggle answered")
            await asyncio.sleep(0.3)
            assert out.relay_state() == frozenset()
            assert not any(r.channel == 2 for r in out.relay_log())
            # the refusal was the e-stop's: the reset took it off; the row says it is open
            row = str(app.query_one("#interlock-2").render())
            assert 2 not in pane.refused and row.startswith("open - ready"), row

    asyncio.run(scenario())


def test_vibration_audition_flow_and_hand_flow(plugins, map_file):
    async def scenario():
        app = _app(plugins, "vibration")
        async with app.run_test(size=(100, 30)) as pilot:
            await _ready(app, pilot)
            pane = await _load_map(app, pilot, map_file)
            # enter on the grid cell of point 51 (row 5, column 3)
            pane.move_cursor(51)
            await pilot.press("enter")
            await wait_for(pilot, lambda: len(app.session.played) == 1, what="point played")
            point = app.session.played[0]
            assert point.name == "point 51"
            await wait_for(pilot, lambda: "point 51" in str(app.query_one("#vib-info").render()))
            freq = point.meta["frequency_hz"]
            plot = app.query_one("#frf-plot").summary()
            assert f"plays at {freq:g} Hz" in plot and "PALL" in plot and "point 51" in plot
            assert "frequency (Hz)" in plot and "|H| (dB re 1 µm/V)" in plot
            # second point, then the flow both ways
            pane.move_cursor(52)
            await pilot.press("enter")
            await wait_for(pilot, lambda: len(app.session.played) == 2)
            await wait_for(
                pilot, lambda: "lookup table" in str(app.query_one("#vib-info").render())
            )
            info = str(app.query_one("#vib-info").render())
            assert "51 / 52:" in info and "52 / 51:" in info
            await pilot.press("f")
            await wait_for(pilot, lambda: len(app.session.played) == 3)
            await pilot.press("r")
            await wait_for(pilot, lambda: len(app.session.played) == 4)
            assert [p.name for p in app.session.played[2:]] == ["flow 51->52", "flow 52->51"]
            entry = pane.session.lookup(51, 52)
            part1 = app.session.played[2].meta["parts"][0]
            assert part1["frequency_hz"] == entry["frequency_hz"]
            assert part1["actuator"] == entry["actuator"]
            # flow under a hand at the cursor, to the right
            await pilot.press("d")
            await wait_for(pilot, lambda: len(app.session.played) == 5, 30, "hand flow")
            hand = app.session.played[4]
            assert hand.meta["direction"] == "right" and len(hand.segments) == 2
            await wait_for(pilot, lambda: not app.session.outputs.status()["busy"], 30)
            for plan in app.session.played:
                assert _played_in_recording(app.session.outputs, plan) < 1e-3

    asyncio.run(scenario())


def test_vibration_command_line_and_bad_input(plugins, map_file):
    async def scenario():
        app = _app(plugins, "vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = await _load_map(app, pilot, map_file)
            await command(app, pilot, "99")
            await pilot.pause(0.3)
            assert app.session.played == []  # point 99 does not exist: nothing plays
            await command(app, pilot, "51 52")  # its tables are built first: minutes loaded
            await wait_for(pilot, lambda: len(app.session.played) == 1, 120, "flow 51->52")
            assert app.session.played[0].name == "flow 51->52"
            assert pane.selected == [51, 52]
            await command(app, pilot, "import PA")
            await wait_for(
                pilot,
                lambda: "EXC=FILE" in str(app.query_one("#vib-status").render()),
                60,
                "import",
            )

    asyncio.run(scenario())


@pytest.mark.slow
def test_vibration_measurement_progress_and_cancel(plugins):
    async def scenario():
        app = _app(plugins, "vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = app.pane("vibration")
            # x at once, before the measurement's thread has started, still cancels it
            pane.action_measure()
            pane.action_cancel()
            await wait_for(
                pilot,
                lambda: "cancelled" in str(app.query_one("#vib-status").render()),
                60,
                "cancelled",
            )
            assert pane.session is None
            await pilot.press("m")
            bar = app.query_one("#vib-progress")
            await wait_for(pilot, lambda: "vibrometer: step" in pane.status_text, 60, "steps")
            assert bar.display
            await wait_for(pilot, lambda: pane.session is not None, 120, "measured")
            assert pane.session.vmap.points.size == 84
            assert "measured at" in str(app.query_one("#vib-status").render())

    asyncio.run(scenario())


def test_electrostatic_setting_and_preset(plugins):
    async def scenario():
        app = _app(plugins, "electrostatic")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = app.pane("electrostatic")
            for _ in range(15):  # +150 Vpp from 100: held at the 200 Vpp limit
                await pilot.press("plus")
            assert pane.vpp == 200.0
            await wait_for(
                pilot, lambda: "expected attraction" in str(app.query_one("#es-setting").render())
            )
            await pilot.press("p")
            await wait_for(pilot, lambda: len(app.session.played) == 1)
            plan = app.session.played[0]
            assert plan.segments[0].screen and abs(np.ptp(plan.segments[0].screen_v) - 200) < 1
            await wait_for(pilot, lambda: not app.session.outputs.status()["busy"], 10)
            rec = app.session.outputs.recording()
            assert abs(np.ptp(rec[:, 1]) - 200.0) < 1.0 and not np.any(rec[:, 0])
            # the first list entry is a knob condition: enter auditions it
            await pilot.press("enter")
            await wait_for(pilot, lambda: len(app.session.played) == 2, 30)
            assert app.session.played[1].name.startswith("knob ")

    asyncio.run(scenario())


def test_scenes_lists_registrations(plugins):
    async def scenario():
        app = _app(plugins, "scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            table = app.query_one("#scene-table")
            names = {str(table.get_row_at(i)[0]) for i in range(table.row_count)}
            assert names == set(plugins.of("scene"))
            assert "not started" in str(app.query_one("#projector-status").render())

    asyncio.run(scenario())


def test_help_on_question_mark_and_estop_over_it(plugins):
    async def scenario():
        app = _app(plugins, "relays")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            await pilot.press("question_mark")
            await wait_for(pilot, lambda: type(app.screen).__name__ == "HelpScreen")
            await wait_for(pilot, lambda: app.screen.query("#help-text"), 5, "help composed")
            text = str(app.screen.query_one("#help-text").render())
            assert "ctrl+e" in text and "toggle that relay" in text  # this screen's keys
            # the e-stop works on top of the help too
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped)
            await pilot.press("escape")
            await wait_for(pilot, lambda: type(app.screen).__name__ != "HelpScreen")

    asyncio.run(scenario())


def test_function_keys_open_and_focus_a_screen(plugins):
    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            await pilot.press("f4")
            await wait_for(pilot, lambda: app.query_one("#tabs").active == "relays", 10)
            try:
                await wait_for(
                    pilot, lambda: app.focused is not None and app.focused.id == "relay-1", 10
                )
            except AssertionError:
                sw = app.query_one("#relay-1")
                raise AssertionError(
                    f"focused={app.focused!r} sw.disabled={sw.disabled} focusable={sw.focusable}"
                    f" display={sw.display} visible={sw.visible} region={sw.region}"
                    f" screen={app.screen!r} stack={app.screen_stack} pane={app.pane('relays')!r}"
                    f" mounting={app._mounting!r}"
                ) from None

    asyncio.run(scenario())


@pytest.mark.slow
@pytest.mark.hardware
def test_scene_starts_and_stops_on_the_headless_projector(plugins, monkeypatch, map_file):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)

    async def scenario():
        app = _app(plugins, "scenes")
        async with app.run_test(size=(100, 30)) as pilot:
            await _ready(app, pilot)
            table = app.query_one("#scene-table")
            names = [str(table.get_row_at(i)[0]) for i in range(table.row_count)]
            table.move_cursor(row=names.index("grid"))
            await pilot.press("enter")
            await wait_for(
                pilot,
                lambda: (
                    app.session.projector is not None
                    and app.session.projector.status().get("shown_scene") == "grid"
                ),
                60,
                "grid shown",
            )
            status = app.query_one("#projector-status")
            await wait_for(pilot, lambda: "scene: grid" in str(status.render()), 5)
            assert "connected" in str(status.render())
            # auditioning a point lights it on the projected grid
            await pilot.press("f3")
            await wait_for(pilot, lambda: app.pane("vibration") is not None)
            vib = app.pane("vibration")
            vib.run_command(f"load {map_file}")
            await wait_for(pilot, lambda: vib.session is not None, 30)
            # the grid's tables come from the registered flow effect once a map is loaded
            await wait_for(pilot, lambda: app.session.projector.unprepared == [], 30)
            vib.run_command("51")
            await wait_for(pilot, lambda: app.session.projector.scene.state()["active"] == 51, 10)
            await wait_for(pilot, lambda: len(app.session.played) == 1, 10, "point played")
            lit = app.session.projector.scene.state()["excitation_patches"]
            assert set(lit) == set(patches_of(app.session.played[0].meta["actuator"]))
            await pilot.press("f6")
            await wait_for(pilot, lambda: "not prepared" not in str(status.render()), 10)
            await pilot.press("s")
            await wait_for(pilot, lambda: app.session.projector.status()["scene"] is None, 10)
            svc = app.session.projector
        # leaving the console stops the projector process
        assert svc.supervisor.pid is None and svc.supervisor.proc is None

    asyncio.run(scenario())


def test_command_palette_opens_a_screen(plugins):
    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            await pilot.press("ctrl+p")
            await wait_for(pilot, lambda: type(app.screen).__name__ == "SafetyPalette")
            await pilot.press(*"Open Relays")
            await pilot.pause(0.5)
            await pilot.press("enter")
            await wait_for(pilot, lambda: app.query_one("#tabs").active == "relays")
            assert app.pane("relays") is not None

    asyncio.run(scenario())
