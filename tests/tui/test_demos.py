"""The demos started from the Scenes screen on the twin, as an operator does: the demo runs
in its own process with the console's outputs handed over; the scripted hand performs,
the flow it reports is what the twin's amplifier and relays got (the process's twin log);
stopping, the e-stop and quitting leave the outputs silent and the relays open, the
process gone and the console's outputs back."""

from __future__ import annotations

import asyncio
import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from console.cli.main import Context
from console.core.types import patches_of
from console.tui.app import HapTableApp

from .conftest import wait_for

FS = 48000


def dominant_hz(x: np.ndarray, fs: int = FS) -> float:
    """Spectral peak (Hann window, 4x zero padding, parabolic refinement)."""
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size), n=4 * x.size))
    k = int(np.argmax(spec[1:])) + 1
    a, b, c = np.log(spec[k - 1 : k + 2] + 1e-300)
    return (k + 0.5 * (a - c) / (a - 2 * b + c)) * fs / (4 * x.size)


def played_bursts(rec: np.ndarray, log, part_n: int) -> list[tuple[frozenset, float]]:
    """(relay channels closed, dominant Hz) of each burst on the piezo channel, in order:
    the recording cut where the relays switched, then at silent gaps, then into parts of
    ``part_n`` samples (two parts on the same patches follow each other without a gap)."""
    bounds = sorted({0, rec.shape[0], *(min(r.clock, rec.shape[0]) for r in log)})
    out = []
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        closed = set()
        for r in log:
            if r.clock <= a:
                (closed.add if r.closed else closed.discard)(r.channel)
        nz = np.flatnonzero(rec[a:b, 0])
        if nz.size == 0:
            continue
        cuts = np.flatnonzero(np.diff(nz) > 480) + 1  # 10 ms of silence: a new burst
        for run in np.split(nz, cuts):
            if run.size <= 480:
                continue
            n = max(1, round((run[-1] + 1 - run[0]) / part_n))
            for k in range(n):
                k0 = a + run[0] + k * (run[-1] + 1 - run[0]) // n
                seg = rec[k0 : k0 + (run[-1] + 1 - run[0]) // n, 0]
                out.append((frozenset(closed), dominant_hz(seg)))
    return out


def part_n(app) -> int:
    """Samples in one part of a flow."""
    return int(round(app.ctx.profile.get("vibrotactile.part_s") * FS))


async def _start(app, pilot, name: str):
    """Open the demos table, highlight ``name``, press enter; wait until it runs."""
    await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
    await wait_for(pilot, lambda: app.pane("scenes") is not None, what="scenes pane")
    pane = app.pane("scenes")
    await pilot.press("d")
    table = app.query_one("#demo-table")
    await wait_for(pilot, lambda: app.focused is table, what="demo table focused")
    names = [str(table.get_row_at(i)[0]) for i in range(table.row_count)]
    assert set(names) == set(app.ctx.pm.of("demo"))
    table.move_cursor(row=names.index(name))
    await pilot.press("enter")
    try:
        await wait_for(pilot, lambda: pane.demo_state == "running", 60, f"{name} running")
    except AssertionError:
        raise AssertionError(
            f"{name} not running: state {pane.demo_state!r}, {app.query_one('#demo-work').text!r}"
        ) from None
    return pane


def twin_record(run) -> tuple[np.ndarray, list]:
    """What the demo process's twin outputs received: (recording (n, 2) V, relay log)."""
    path = Path(run.final["twin_log"])
    log = [SimpleNamespace(**r) for r in json.loads(path.read_text())["relay_log"]]
    with np.load(path.with_suffix(".npz")) as z:
        return z["recording_v"], log


def outputs_of(run) -> dict:
    """The demo's outputs (gate, audio, busy) as its process last reported them."""
    return run.snapshot().get("outputs") or {"gate": {}, "busy": True}


def _silent_and_open(run) -> None:
    """The process ended with its outputs silent and every relay open."""
    assert run.proc.poll() is not None, "the demo process still runs"
    gate = run.final["final"]["outputs"]["gate"]
    assert gate["level_v"] == [0.0, 0.0]
    assert gate["relays_closed"] == []
    _, log = twin_record(run)
    assert log and not log[-1].closed


async def _outputs_back(app, pilot):
    await wait_for(pilot, lambda: app.session.outputs is not None, 20, "the console's outputs back")
    return app.session.outputs


def test_flow_demo_from_the_scenes_screen_plays_the_flow_it_reports(flow_ctx):
    async def scenario():
        app = HapTableApp(flow_ctx, fast=False, initial="scenes")
        async with app.run_test(size=(100, 30)) as pilot:
            pane = app.pane("scenes")
            # plans on first use (fast); a loaded test machine must not trip the watchdog
            app.session.demos.params = {"flow": {"prepare": False, "watchdog_ms": 5000}}
            pane = await _start(app, pilot, "flow")
            run = app.session.demos.run
            # the demo's process is a client of the console's table; only the camera is lent
            clients = app.session.outputs.status()["kernel"]["clients"]
            assert any(f"(pid {run.proc.pid})" in c for c in clients), clients
            assert app.session.camera_started.borrower == "demo flow"

            def flow_done() -> bool:
                snap = run.snapshot()
                last = snap.get("flow", {}).get("last", [])
                return any(e.get("parts") for e in last) and not snap["outputs"]["busy"]

            try:
                await wait_for(pilot, flow_done, 45, "a flow played")
            except AssertionError as exc:
                snap = {k: v for k, v in run.snapshot().items() if k != "latency"}
                raise AssertionError(f"{exc}: {snap}") from None
            # the safety bar shows the demo's outputs while the process holds them
            bar = str(app.query_one("#safety").render())
            # (idle or still drawing the flow's end: the bar follows the outputs' state)
            assert bar.startswith(" ctrl+e E-STOP | ") and "not open" not in bar
            snap = run.snapshot()
            status = str(app.query_one("#demo-status").render())
            assert "flow right" in status and "latency p50/p99" in status
            assert "end to end" in status
            # the Latency screen shows the demo's loop, with the demo's stages
            await pilot.press("f7")
            await wait_for(pilot, lambda: app.pane("latency") is not None, 10, "latency pane")
            lat = app.pane("latency")
            try:
                await wait_for(pilot, lambda: lat.source == "demo flow", 20, "demo latency")
            except AssertionError as exc:
                head = app.query("#lat-head")
                raise AssertionError(
                    f"{exc}: tab={app.query_one('#tabs').active} source={lat.source!r} "
                    f"head={head and str(head.first().render())!r} stopped={run.stopped}"
                ) from None
            head = str(app.query_one("#lat-head").render())
            assert "demo flow" in head
            rows = app.query_one("#lat-table")
            labels = {str(rows.get_row_at(i)[0]) for i in range(rows.row_count)}
            assert {"capture", "vision", "classify", "scene", "effect", "output"} <= labels
            await pilot.press("f6")
            await pilot.press("s")
            await wait_for(pilot, lambda: pane.demo_name is None, 20, "demo stopped")
            assert run.stopped and not run.running
            assert app.session.camera_started.borrower is None  # given back
            out = await _outputs_back(app, pilot)
            assert not out.estopped
            _silent_and_open(run)
            rec, log = twin_record(run)
            assert run.final["twin_log"] in str(app.query_one("#demo-status").render())
        # what the demo reported is what the amplifier and the relays got
        chans = {n: int(v["relay_channel"]) for n, v in flow_ctx.profile.items("patches").items()}
        parts = [p for e in snap["flow"]["last"] for p in e.get("parts", [])]
        assert parts
        bursts = played_bursts(rec, log, part_n(app))
        assert len(bursts) >= len(parts)
        for p, (closed, hz) in zip(parts, bursts, strict=False):
            assert closed == {chans[q] for q in patches_of(p["actuator"])}
            assert hz == pytest.approx(p["frequency_hz"], abs=1.0)
        assert all(r.level_v == [0.0, 0.0] for r in log)  # relays switched in silence

    asyncio.run(scenario())


def test_estop_stops_a_running_demo(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await _start(app, pilot, "knob")
            run = app.session.demos.run
            screen = int(app.ctx.profile.get("screen.relay_channel"))

            def playing() -> bool:
                st = outputs_of(run)
                gate = st["gate"]
                return screen in gate.get("relays_closed", ()) and gate["level_v"][1] != 0

            await wait_for(pilot, playing, 20, "knob playing on the screen electrode")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: pane.demo_name is None, 20, "demo stopped")
            assert run.stopped and not run.running
            assert pane.demo_state == "e-stopped"
            assert app.session.camera_started.borrower is None
            assert run.final["final"]["outputs"]["gate"]["estopped"]  # the process's gate
            _silent_and_open(run)
            rec, _ = twin_record(run)
            assert np.any(rec[:, 1])  # it did play on the screen electrode
            # the console's outputs come back e-stopped, until the operator resets them
            out = await _outputs_back(app, pilot)
            assert out.estopped and "operator e-stop" in out.estop_reason
            assert "E-STOP" in str(app.query_one("#safety").render())

    asyncio.run(scenario())


def test_quitting_with_a_demo_running_leaves_nothing_running(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await _start(app, pilot, "knob")
            run = app.session.demos.run
            await wait_for(pilot, lambda: outputs_of(run)["busy"], 20, "knob playing")
            await pilot.press("q")
        assert run.stopped and not run.running
        _silent_and_open(run)
        assert app.session.outputs.closed  # left the table while quitting

    asyncio.run(scenario())


def test_starting_the_flow_shows_progress_and_can_be_cancelled(flow_ctx):
    """The demo's start (camera handed over, its process opening the camera) shows its
    steps and ``x`` cancels it; what the flow prepares behind the running demo is the
    demo's status line's (``tests/demos/test_flow_ready.py``)."""
    from console.tui.long_work import LongWork

    async def scenario():
        app = HapTableApp(flow_ctx, fast=False, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
            pane = app.pane("scenes")
            await pilot.press("d")
            await pilot.press("enter")  # flow: the first row
            lw = app.query_one("#demo-work", LongWork)
            await wait_for(pilot, lambda: "opening the camera" in lw.text, 30, "start shown")
            assert lw.progress is not None  # the bar shows
            run = app.session.demos.run  # its process opens the camera
            assert run is not None and app.session.outputs is not None
            await pilot.press("x")
            await wait_for(pilot, lambda: lw.outcome == "cancelled", 60, "cancelled")
            # the pane tidies up when the worker's end reaches it (a message later)
            await wait_for(
                pilot,
                lambda: app.session.demos.run is None and pane.demo_name is None,
                10,
                "tidied",
            )
            assert app.session.camera_started.borrower is None  # the camera is the console's again
            # its process ended: cancelled while starting, or stopped had it just started
            assert run.proc.wait(10) is not None and run.exit_reason in ("cancelled", "stopped")
            out = await _outputs_back(app, pilot)
            assert not out.estopped
            table = app.query_one("#demo-table")
            assert str(table.get_cell("flow", "state")) == "cancelled"

    asyncio.run(scenario())


def test_the_operators_finger_on_the_twin_gets_the_flow_where_it_rests(flow_ctx):
    async def scenario():
        app = HapTableApp(flow_ctx, fast=False, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.pane("scenes")
            app.session.demos.params = {"flow": {"prepare": False, "watchdog_ms": 5000}}
            pane = await _start(app, pilot, "flow")
            run = app.session.demos.run
            # the demo's process renders the twin camera in a process of its own
            assert run.snapshot()["camera"].get("process")

            def new_flow_near(n_before: int, where) -> bool:
                """A flow after the first ``n_before`` played, under a hand resting near
                ``where`` (the hand's centre is some cm from its fingertip); ``flows``
                counts plays only, ``last`` holds refusals too."""
                f = run.snapshot()["flow"]
                plays = [e for e in f["last"] if e.get("parts")]
                new = plays[-(f["flows"] - n_before) :]
                return f["flows"] > n_before and any(
                    np.hypot(*(np.array(e["rest_mm"]) - where)) < 80 for e in new
                )

            # the operator's finger replaces the scripted hand; a placement while a flow
            # still plays is skipped (one flow at a time), so move on until one plays
            await pilot.press("space")
            assert pane.hand_placed and pane.hand_mm is not None
            placed = False
            for step in range(6):
                n0, where = run.snapshot()["flow"]["flows"], np.array(pane.hand_mm)
                try:
                    await wait_for(pilot, lambda n=n0, w=where: new_flow_near(n, w), 8, "flow")
                    placed = True
                    break
                except AssertionError:
                    await pilot.press("down" if step % 2 == 0 else "left")
            assert placed, run.snapshot()["flow"]
            await wait_for(pilot, lambda: not outputs_of(run)["busy"], 20, "flow played")
            n1 = run.snapshot()["flow"]["flows"]
            await pilot.press("down")  # lifted and put down 20 mm further: a new placement
            moved = np.array(pane.hand_mm)
            assert np.hypot(*(moved - where)) == pytest.approx(20.0)
            await wait_for(pilot, lambda: new_flow_near(n1, moved), 20, "flow where it moved")
            # let it play out: a stop cuts a flow under way, and its cut burst is not counted
            await wait_for(pilot, lambda: not outputs_of(run)["busy"], 20, "second flow played")
            await pilot.press("s")
            await wait_for(pilot, lambda: pane.demo_name is None, 20, "demo stopped")
            snap = run.snapshot()
            _silent_and_open(run)
            rec, log = twin_record(run)
        chans = {n: int(v["relay_channel"]) for n, v in flow_ctx.profile.items("patches").items()}
        parts = [p for e in snap["flow"]["last"] for p in e.get("parts", [])]
        bursts = played_bursts(rec, log, part_n(app))
        assert len(bursts) >= len(parts)
        for p, (closed, hz) in zip(parts, bursts, strict=False):
            assert closed == {chans[q] for q in patches_of(p["actuator"])}
            assert hz == pytest.approx(p["frequency_hz"], abs=1.0)

    asyncio.run(scenario())


def test_a_demo_process_that_dies_is_shown_and_its_outputs_ramp_down(plugins):
    """kill -9 of the demo's process: the table's kernel ramps down what it played and
    opens the relays (a client that went away, not an e-stop); the console says so."""
    import os
    import signal

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await _start(app, pilot, "knob")
            run = app.session.demos.run
            os.kill(run.proc.pid, signal.SIGKILL)
            await wait_for(pilot, lambda: pane.demo_name is None, 20, "the console noticed")
            assert "exited (code -9)" in pane.demo_state
            assert app.session.camera_started.borrower is None
            out = await _outputs_back(app, pilot)
            await wait_for(pilot, lambda: not out.status()["busy"], 10, "its stream ramped down")
            st = out.status()["gate"]
            assert not out.estopped and st["relays_closed"] == [] and not any(st["level_v"])

    asyncio.run(scenario())


def test_haptable_estop_from_a_shell_reaches_the_demo_process(plugins):
    from console.runtime.control import send_command

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await _start(app, pilot, "knob")
            run = app.session.demos.run
            reply = await asyncio.to_thread(send_command, app.ctx.profile, "estop")
            assert reply and reply.startswith("ok")
            await wait_for(pilot, lambda: pane.demo_name is None, 20, "demo stopped")
            assert run.final["final"]["outputs"]["gate"]["estopped"]
            assert "another process" in run.estop_reason
            _silent_and_open(run)
            out = await _outputs_back(app, pilot)
            assert out.estopped

    asyncio.run(scenario())


def test_a_demo_started_while_the_console_plays_waits_its_turn_on_the_table(plugins):
    """The console and the demo are clients of one kernel: an audition under way plays
    to its end, the demo's stream after it; nothing is handed over."""
    from console.core.types import OutputPlan, Segment
    from console.signals.waveforms import tone

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            out = await _outputs_back(app, pilot)
            sig = tone(200, 20, 1.0, FS, 0.01)
            plan = OutputPlan(FS, (Segment(sig, np.zeros_like(sig), frozenset({"PA"})),))
            report = out.play(plan, wait=False)  # an audition under way
            await wait_for(pilot, lambda: out.status()["busy"], 5, "playing")
            await _start(app, pilot, "knob")
            assert app.session.outputs is out
            await wait_for(pilot, lambda: report.done.is_set(), 20, "the audition played")
            assert not report.error and len(report.segment_end) == 1
            run = app.session.demos.run
            await wait_for(pilot, lambda: outputs_of(run)["busy"], 20, "then the knob")

    asyncio.run(scenario())


def test_a_demo_runs_with_the_exposure_and_gain_the_console_set(plugins):
    """The Camera screen's exposure and gain go to the demo's camera, its thresholds to
    the demo's classifier (a camera control given to the classifier failed the start)."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="camera")
        async with app.run_test(size=(80, 24)) as pilot:

            def controls() -> bool:
                svc = app.session.camera_started
                return svc is not None and "gain" in svc.params()

            await wait_for(pilot, controls, 60, "the camera's exposure and gain")
            app.session.camera_started.set_param("gain", 1.5)
            await pilot.press("f6")
            await _start(app, pilot, "knob")
            snap = app.session.demos.run.snapshot()
            assert snap["camera"].get("gain") == 1.5, snap["camera"]
            assert not snap.get("last_error")

    asyncio.run(scenario())
