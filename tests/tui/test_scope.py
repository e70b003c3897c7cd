"""The Scope screen: what the gate handed the driver, per channel, in volts."""

from __future__ import annotations

import asyncio
import re
import time

from textual.widgets import Static

from console.cli.main import Context
from console.signals.stimuli import make_stimulus
from console.tui.app import HapTableApp
from console.tui.charts import Chart

from .conftest import wait_for

FS = 48000


def _text(app, id_: str) -> str:
    return str(app.query_one(id_, Static).content)


def test_a_played_stimulus_shows_its_peak_per_channel(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scope")
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            pane = app.pane("scope")
            await wait_for(pilot, lambda: "LIVE" in _text(app, "#scope-head"), 10, "live")
            plan = make_stimulus("sine-PB", FS)
            assert app.session.play_plan(plan, wait=False)  # as a screen does
            report = app.session.last_played()[1]
            await wait_for(pilot, report.done.is_set, 20, "played")
            await pilot.press("p")  # the last plan, whole
            await wait_for(
                pilot, lambda: "last plan sine-PB: 1.00 s on PB (done)" in _text(app, "#scope-head")
            )
            assert "FROZEN ON THE LAST PLAN" in _text(app, "#scope-head")
            assert "peak: piezo 20.0 V, screen 0.0 V" in _text(app, "#scope-info")
            shown = pane.shown
            assert shown.n >= FS  # the whole second, and the margins
            chart = app.query_one("#scope-chart", Chart)
            summary = chart.summary()
            assert "x: time (ms); y: output (V)" in summary
            assert re.search(r"piezo: x 0\.\.10[0-9]{2}\.?\d*, y -20\.?0*\.\.20", summary), summary
            assert "screen: x" in summary
            # frozen: nothing changes while more plays
            await pilot.press("space")  # run again
            assert "LIVE" in _text(app, "#scope-head")
            await pilot.press("space")  # freeze the live window
            assert pane.frozen is not None and "FROZEN" in _text(app, "#scope-head")
            before = pane.shown
            app.session.play_plan(make_stimulus("screen-180hz", FS), wait=True)
            await pilot.pause(0.5)
            assert pane.shown is before
            await pilot.press("space")
            await wait_for(pilot, lambda: pane.frozen is None and pane.shown is not before)

    asyncio.run(scenario())


def test_an_estop_ramp_is_visible(plugins):
    """Paced in real time: the e-stop lands in the middle of a tone; the Scope shows the
    level it ramped down from and a ramp as long as the slew limit allows."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="scope")
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            out = app.session.outputs
            plan = make_stimulus("sine-PA", FS)
            # well inside the 1 s tone: the amplifiers get it (on a loaded machine the
            # tone may end before a look finds it: then it is played again)
            inside = False
            for _ in range(5):
                assert app.session.play_plan(plan, wait=False)
                report = app.session.last_played()[1]
                t_end = time.monotonic() + 30
                while time.monotonic() < t_end and not report.done.is_set():
                    if app.session.scope(0.02).peak_v()["piezo"] > 5.0:
                        inside = True
                        break
                    await pilot.pause(0.02)
                if inside:
                    break
            assert inside, "the tone never reached the amplifiers"
            await pilot.press("ctrl+e")
            assert out.wait_safe(5)
            await pilot.pause(0.1)
            await pilot.press("p")
            await wait_for(
                pilot, lambda: "estop at" in _text(app, "#scope-info"), 10, "e-stop shown"
            )
            info = _text(app, "#scope-info")
            m = re.search(r"estop at ([\d.]+) ms: ramp ([\d.]+) V -> 0 V in ([\d.]+) ms", info)
            assert m, info
            level_v, ramp_ms = float(m.group(2)), float(m.group(3))
            # the tone's instantaneous value when the e-stop came (a sine: near zero now
            # and then); the trace before it holds the tone
            assert 0.0 <= level_v <= 20.0, info
            assert (
                re.search(r"piezo (\d+\.\d) V", info)
                and float(re.search(r"piezo (\d+\.\d) V", info).group(1)) > 5.0
            ), info
            slew = out.limits.slew_v_per_s("piezo", frozenset({"PA"}))
            assert abs(ramp_ms - level_v / slew * 1e3) <= 1e3 / FS + 0.01
            assert "operator e-stop" in info
            await pilot.press("ctrl+r")

    asyncio.run(scenario())


def test_the_last_plan_is_kept_after_the_ring_moved_on_and_a_new_play_unfreezes(plugins):
    """The scope's ring keeps ~4 s: 5 s more through the gate after a plan, the session
    still keeps that plan whole (kept when it ended); ``p`` shows the last plan the gate
    passed (whoever sent it: issue 27); the next plan played unfreezes the view."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scope")
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            pane, out = app.pane("scope"), app.session.outputs
            assert app.session.play_plan(make_stimulus("sine-PB", FS), wait=True)
            start = app.session.last_played()[1].segment_start[0]
            await wait_for(pilot, lambda: app.session.last_plan_trace() is not None, 10)
            for _ in range(5):  # another part of the console plays on the outputs
                out.play(make_stimulus("screen-180hz", FS), wait=True)
            assert app.session.scope(None).clock > start  # the ring lost the plan's start
            kept = app.session.last_plan_trace()[1]
            assert kept.n >= FS and kept.peak_v()["piezo"] == 20.0  # sine-PB, whole
            await pilot.press("p")
            head = _text(app, "#scope-head")
            assert "FROZEN ON THE LAST PLAN |" in head, head
            assert "gone" not in head and "last plan screen-180: 1.00 s on screen (done)" in head
            assert pane.shown.n >= FS  # the whole second
            assert "peak: piezo 0.0 V" in _text(app, "#scope-info")
            assert "space runs live" in head
            # the next plan played unfreezes the view
            assert app.session.play_plan(make_stimulus("sine-PA", FS), wait=False)
            await wait_for(pilot, lambda: "LIVE" in _text(app, "#scope-head"), 10, "live")
            assert pane.frozen is None and not pane.plan_view

    asyncio.run(scenario())
