"""The Vibration screen's m with an accelerometer input: the guided roving-sensor run on a
1 x 2 grid of the twin (short chirps): the next point and the last point's coherence are
shown, Esc stops it with the point kept, m resumes at the next point and loads the map."""

from __future__ import annotations

import asyncio
import threading
from pathlib import Path

import pytest

from console.cli.main import Context
from console.config.profile import PROJECT_PROFILES
from console.tui.app import HapTableApp
from console.tui.roving_view import RovingView

from .conftest import wait_for, words_on

ACCEL = """
[audio_inputs.accel]
channel = 1
kind = "accelerometer"
sensitivity = 10.2

[audio_inputs.loopback]
channel = 2
kind = "loopback"
sensitivity = 1.0

[projector]
flow_pairs = ["F:1:2"]
"""


@pytest.fixture
def tiny(tmp_path, plugins, monkeypatch):
    """The sim profile with a 1 x 2 grid and an accelerometer; 2 chirps of 0.2 s a point."""
    from plugins.vibrotactile import roving_console
    from plugins.vibrotactile.roving import RovingSettings

    short = RovingSettings(level_v=90.0, knee_hz=300.0, repeats=2, sweep_s=0.2, tail_s=0.1)
    monkeypatch.setattr(roving_console, "CONSOLE_SETTINGS", short)
    text = (PROJECT_PROFILES / "sim.toml").read_text()
    text = text.replace("rows = 7\ncolumns = 12", "rows = 1\ncolumns = 2", 1)
    text = text.replace("block_size = 64", "block_size = 1024", 1)
    path = tmp_path / "roving.toml"
    path.write_text(text + ACCEL)
    return Context(str(path), plugins)


async def _press_m(app, pilot):
    """The Vibration screen once its outputs are open and its grid focused, after ``m``."""
    pane = app.pane("vibration")
    await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
    await wait_for(pilot, lambda: app.focused is pane.focus_target, what="grid focused")
    await pilot.press("m")
    return pane


def test_m_runs_the_roving_sensor_stops_and_resumes(tiny, monkeypatch):
    pressed, shown = threading.Event(), RovingView._step

    def step(self, s, stop):  # the first "next: point 2" waits for Esc (no race on a busy CPU)
        shown(self, s, stop)
        if s.get("event") == "next" and s["point"] == 2 and not pressed.is_set():
            pressed.wait(30)

    monkeypatch.setattr(RovingView, "_step", step)

    async def scenario():
        app = HapTableApp(tiny, fast=True, initial="vibration")
        async with app.run_test(size=(120, 40)) as pilot:
            pane = await _press_m(app, pilot)

            def line() -> str:
                return words_on(app, "#vib-roving") if app.query("#vib-roving") else ""

            await wait_for(pilot, lambda: "next: point 2" in line(), 60, "point 1 measured")
            assert "roving sensor: 1/2 points" in line()
            assert "next: point 2 at (102, 44) mm" in line()
            assert "last: point 1 coherence min" in line()
            assert line().endswith(": passes") or line().endswith(": FAILS")
            await pilot.press("escape")
            pressed.set()
            await wait_for(pilot, lambda: "stopped" in words_on(app, "#vib-status"), 30, "stop")
            assert words_on(app, "#vib-status") == "roving measurement stopped: 1/2 points kept"
            assert "m resumes with the next point" in line() and pane.session is None
            await pilot.press("m")
            await wait_for(pilot, lambda: pane.session is not None, 60, "map loaded")
            await wait_for(pilot, lambda: "roving map done" in line(), 10, "done line")
            assert pane.session.vmap.points.size == 2
            assert "last: point 2 coherence min" in line()  # resumed with point 2, not 1
            assert "2 points" in words_on(app, "#vib-status")

    asyncio.run(scenario())


def test_m_with_a_dummy_measures_each_point_twice_and_keeps_the_mass_free_map(tiny, monkeypatch):
    """``dummy_mass_g`` on the accelerometer's input: each point's second pass is asked
    for ("clip the 14 g dummy on"), and the map kept is the cancellation of the two."""
    import numpy as np

    from console.tui.roving_view import roving_map_path

    path = Path(tiny.profile_arg)
    path.write_text(
        path.read_text().replace(
            'kind = "accelerometer"', 'kind = "accelerometer"\nmass_g = 7.0\ndummy_mass_g = 14.0'
        )
    )
    ctx = Context(str(path), tiny.pm)
    lines, shown = [], RovingView._show_step

    def show(self, s, stop):
        shown(self, s, stop)
        lines.append(self.progress.line())

    monkeypatch.setattr(RovingView, "_show_step", show)
    where = []

    async def scenario():
        app = HapTableApp(ctx, fast=True, initial="vibration")
        async with app.run_test(size=(120, 40)) as pilot:
            pane = await _press_m(app, pilot)
            await wait_for(pilot, lambda: pane.session is not None, 90, "map loaded")
            where.append(roving_map_path(pane.service.cached_map_path()))

    asyncio.run(scenario())
    assert any("clip the 14 g dummy on the sensor at point 1" in t for t in lines)
    assert any("point 2 at (102, 44) mm (without the dummy)" in t for t in lines)
    parts = sorted(where[0].with_name(where[0].name + ".parts").glob("point_*.npz"))
    assert len(parts) == 2
    with np.load(parts[0]) as got:
        assert {"frf_sensor", "frf_with_dummy"} <= set(got.files)
        # the kept FRF is neither pass: the sensor's mass is taken out
        assert not np.allclose(got["frf"], got["frf_sensor"])
