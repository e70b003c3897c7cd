"""Issue 27: an unexpected exception in a console worker ended the whole console
(Textual's default: the app exits); the operator lost it to a self-test bug. The rule
(``console.tui.workers``): the outputs stop by the kernel's normal stop, the traceback
goes to the log file, one line says what failed on that screen and in ctrl+l's log, and
the console goes on (its e-stop too)."""

from __future__ import annotations

import asyncio
import time

import pytest

from console.cli.main import Context
from console.core.types import OutputPlan
from console.session.camera import CameraService
from console.signals.stimuli import _piezo
from console.signals.waveforms import tone
from console.tui.app import HapTableApp
from console.tui.logs import capture_logs, log_path, release_logs, view_handler

from .conftest import wait_for
from .test_latency_measure_demo import _screen


def _play_then_fail(app):
    """Start a play of 60 s (the fast twin plays it unpaced, in some 8 s), then fail as
    a bug does."""
    out = app.session.outputs
    fs = out.limits.sample_rate_hz
    seg = _piezo(tone(250.0, 10.0, 60.0, fs), "PC", "250 Hz, 60 s")
    out.play(OutputPlan(fs, (seg,), name="long tone"), wait=False)
    raise RuntimeError("injected bug")


def _silent(app) -> bool:
    st = app.session.outputs.status()
    return not st["busy"] and not any(abs(v) > 0.0 for v in st["gate"]["level_v"])


async def _fails_and_goes_on(app, pilot, what: str) -> None:
    await wait_for(pilot, lambda: "injected bug" in _screen(app), 30, "the failure's line")
    text = " ".join(_screen(app).split())
    assert f"{what} failed: RuntimeError: injected bug (details in" in text, text
    assert "the console goes on" in text, text
    assert app.is_running
    end = time.monotonic() + 3.0  # the stop ramps down in ms; the play alone takes 8 s+
    while not _silent(app) and time.monotonic() < end:
        await pilot.pause(0.05)
    assert _silent(app), app.session.outputs.status()
    lines = view_handler().lines  # ctrl+l's log: the line, not the traceback
    assert any(f"{what} failed: RuntimeError: injected bug" in line for line in lines)
    assert not any("Traceback" in line for line in lines)
    logged = log_path().read_text(errors="replace")  # the traceback: in the log file
    assert "Traceback (most recent call last)" in logged and "injected bug" in logged
    await pilot.press("ctrl+e")  # the e-stop still works
    await wait_for(pilot, lambda: app.session.outputs.estopped, 10, "e-stopped")
    assert app.is_running


@pytest.mark.parametrize("size", [(80, 24)])
def test_a_failing_latency_worker_leaves_the_console_up_and_silent(plugins, monkeypatch, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="latency")
        orig = CameraService.watch

        def watch(svc, viewer, on, fps=None):
            if on:
                _play_then_fail(app)
            return orig(svc, viewer, on, fps)

        monkeypatch.setattr(CameraService, "watch", watch)
        removed = capture_logs(app)  # as the console's main does: file and ctrl+l
        try:
            await _scenario(app, size)
        finally:
            release_logs(removed)

    async def _scenario(app, size):
        async with app.run_test(size=size) as pilot:
            head = app.query_one("#lat-head")
            await wait_for(pilot, lambda: "m measures" in str(head.render()), 20, "idle hint")
            await wait_for(pilot, lambda: app.session.outputs is not None, 20, "outputs")
            await pilot.press("m")
            await _fails_and_goes_on(app, pilot, "measuring the camera loop")

    asyncio.run(scenario())


@pytest.mark.parametrize("size", [(80, 24)])
def test_a_failing_vibration_worker_leaves_the_console_up_and_silent(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        removed = capture_logs(app)  # as the console's main does: file and ctrl+l
        try:
            await _scenario(app, size)
        finally:
            release_logs(removed)

    async def _scenario(app, size):
        async with app.run_test(size=size) as pilot:
            pane = app.pane("vibration")
            await wait_for(pilot, lambda: app.session.outputs is not None, 20, "outputs")
            pane.service.measure = lambda *a, **k: _play_then_fail(app)
            await pilot.pause(0.5)
            await pilot.press("m")
            await pilot.pause(0.3)
            if "injected bug" not in _screen(app):
                await pilot.press("m")  # a kept map: m again measures anew
            await _fails_and_goes_on(app, pilot, "the measurement")

    asyncio.run(scenario())
