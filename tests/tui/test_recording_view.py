"""Issue 31: the Camera and Scope screens show a recording. A tiny recording written with
the recorder directly (three frames, a hand with two contacts, a gesture, one plan): on
Camera (F2) ``o`` opens it, frame 1 shows, ``right`` steps to frame 2 (the counter and the
picture change), the live camera is let go meanwhile and ``escape`` brings it back; a
missing file is refused in one line naming it and the fix; on Scope (F9) ``o`` shows the
first plan's summary; a demo holding the camera keeps it while a recording shows."""

from __future__ import annotations

import asyncio
import threading
from types import SimpleNamespace

import numpy as np
import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.core.types import Frame, OutputPlan, Segment
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_camera_layout import text_in

SIZE = (80, 24)


def _frame(x_px: int) -> np.ndarray:
    img = np.full((480, 640), 20, np.uint8)
    img[150:330, x_px - 90 : x_px + 90] = 200  # a bright hand, moving right
    return img


@pytest.fixture
def recording(tmp_path):
    from plugins.recording.writer import Recorder

    done = threading.Event()
    done.set()

    class Outputs:
        def play(self, plan, wait=True):
            return SimpleNamespace(
                segment_start=[480], segment_end=[959], t_first_sample_s=0.5, error="", done=done
            )

    profile = SimpleNamespace(name="test", data={}, path=None)
    rec = Recorder(tmp_path / "run.h5", profile, queue_frames=16)
    plan = OutputPlan(
        48000,
        (Segment(np.sin(np.arange(480) / 10.0) * 20, np.zeros(480), frozenset({"PB"})),),
        "test pulse",
        meta={"kind": "test"},
    )
    rec.watch_outputs(Outputs()).play(plan, wait=False)
    for k, x in enumerate((200, 420, 440)):
        contacts = [
            SimpleNamespace(id=i, pos_px=(x + dx, 160.0), pos_mm=(0.0, 0.0), area_px=90.0)
            for i, dx in ((1, -40), (2, 40))
        ]
        hand = SimpleNamespace(
            center_px=(float(x), 240.0),
            center_mm=(300.0 + k, 200.0),
            radius_px=90.0,
            angle_deg=0.0,
            finger_count=2,
            contacts=contacts,
            descriptors=np.zeros(4),
        )
        gesture = SimpleNamespace(name="two_finger", kind="static", confidence=0.9)
        work = {"contacts": contacts, "hands": [hand], "gesture": gesture}
        rec(Frame(_frame(x), 1000 + k, 0.5 + k / 30), work)
    rec.close()
    assert rec.written == 3 and rec.error == ""
    return tmp_path / "run.h5"


async def _type_path(app, pilot, field: str, path: str) -> None:
    await pilot.press("o")
    await wait_for(pilot, lambda: app.focused is app.query_one(field), 20, f"{field} focused")
    app.query_one(field, Input).value = path
    await pilot.press("enter")


def test_camera_and_scope_show_a_recording(plugins, recording, tmp_path):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=SIZE) as pilot:
            await wait_for(
                pilot, lambda: "IR 640x480" in words_on(app, "#camera-title"), 60, "live view"
            )
            pane = app.pane("camera")
            await wait_for(pilot, lambda: app.focused is pane, 20, "camera focused")
            await _type_path(app, pilot, "#camera-recording", str(recording))
            await wait_for(
                pilot, lambda: "frame 1/3" in words_on(app, "#camera-title"), 30, "frame 1"
            )
            first = pane.shown
            await wait_for(
                pilot, lambda: "contacts 2" in text_in(app, app.query_one("#camera-info")), 20
            )
            info = text_in(app, app.query_one("#camera-info"))
            assert "hands 1 contacts 2" in info and "two_finger" in info, info
            # the live camera is let go: nobody watches it while the recording shows
            await wait_for(pilot, lambda: not app.session.camera.watched, 20, "camera let go")
            await pilot.press("right")
            await wait_for(
                pilot, lambda: "frame 2/3" in words_on(app, "#camera-title"), 30, "frame 2"
            )
            assert pane.shown.changed_rows(first)  # the picture changed (its colours)
            assert "frame 2/3" in text_in(app, app.query_one("#camera-info"))
            await pilot.press("escape")  # back to the live camera
            await wait_for(
                pilot, lambda: "IR 640x480" in words_on(app, "#camera-title"), 60, "live again"
            )
            assert app.session.camera.watched
            # a demo holding the camera: the recording shows, the demo keeps the camera
            svc = app.session.camera
            await asyncio.to_thread(svc.release, "demo knob")
            view = app.query_one("#camera-view")
            await wait_for(pilot, lambda: "demo knob" in text_in(app, view), 30, "borrowed")
            await _type_path(app, pilot, "#camera-recording", str(recording))
            await wait_for(
                pilot, lambda: "frame 1/3" in words_on(app, "#camera-title"), 30, "over a demo"
            )
            assert svc.borrower == "demo knob"
            await pilot.press("escape")
            await wait_for(pilot, lambda: "demo knob" in text_in(app, view), 30, "demo's again")
            assert svc.borrower == "demo knob"
            await asyncio.to_thread(svc.give_back)
            # a missing file: one line naming it and the fix, on the status line
            missing = tmp_path / "none.h5"
            await _type_path(app, pilot, "#camera-recording", str(missing))
            await wait_for(
                pilot, lambda: "no such file" in words_on(app, "#camera-status"), 30, "refusal"
            )
            said = str(app.query_one("#camera-status").render())
            assert "none.h5" in said and "type a recording's path" in said, said
            # one line (the panel wraps it); a path too long for it breaks after a "/"
            assert all(p.endswith("/") for p in said.strip().split("\n")[:-1]), said
            assert "frame" not in words_on(app, "#camera-title")  # still the live view

            await pilot.press("f9")
            await wait_for(pilot, lambda: app.pane("scope") is not None, 20, "scope")
            scope = app.pane("scope")
            await wait_for(pilot, lambda: app.focused is scope, 20, "scope focused")
            await _type_path(app, pilot, "#scope-recording", str(recording))
            await wait_for(
                pilot, lambda: "plan 1/1" in words_on(app, "#scope-head"), 30, "first plan"
            )
            await wait_for(
                pilot,
                lambda: "summary only" in app.query_one("#scope-chart").empty_text,
                30,
                "rendered",
            )  # why it draws nothing on the chart; the summary once, below it
            summary = words_on(app, "#scope-info")
            assert "test pulse: 0.01 s on PB" in summary, summary
            await pilot.press("escape")
            await wait_for(
                pilot, lambda: "RECORDING" not in words_on(app, "#scope-head"), 30, "live scope"
            )
            # a missing file on Scope: said, and still said after the live view's ticks
            await _type_path(app, pilot, "#scope-recording", str(missing))
            await wait_for(
                pilot, lambda: "no such file" in words_on(app, "#scope-head"), 30, "refusal"
            )
            await pilot.pause(1.0)  # several ticks of the live scope
            head = words_on(app, "#scope-head")
            assert "none.h5" in head, head
            assert head.split()[0] in ("LIVE", "FROZEN"), head  # the view's mode stays said

    asyncio.run(scenario())


def test_the_reader_is_found_by_capability_and_words_its_fix_per_place(plugins, tmp_path):
    from console.core.words import AT_CLI, AT_CONSOLE, worded
    from console.tui.recording_view import open_run, recording_reader

    assert recording_reader(plugins).__class__.__name__ == "RecorderFactory"
    missing = tmp_path / "none.h5"
    with pytest.raises(Exception) as got:
        open_run(plugins, str(missing))
    cli, here = worded(got.value, AT_CLI), worded(got.value, AT_CONSOLE)
    assert str(missing) in here and "no such file" in here and "type a recording" in here
    assert "--record FILE" in cli and "\n" not in cli + here
    assert "--record" not in here and "haptable" not in here  # no shell advice in the console
    not_h5 = tmp_path / "notes.h5"
    not_h5.write_text("hello")
    with pytest.raises(Exception) as got:
        open_run(plugins, str(not_h5))
    assert "not an HDF5 file" in worded(got.value, AT_CONSOLE)
