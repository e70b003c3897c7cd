"""Camera and Latency screens on the camera twin: the live view with its overlay,
tuning with immediate effect, background capture, the touch-calibration wizard, and the
per-stage latency table."""

from __future__ import annotations

import asyncio
import json

import numpy as np
import pytest

from console.cli.main import Context
from console.config.profile import PROJECT_PROFILES
from console.core.types import Contact, Hand, HandShape
from console.files import paths
from console.tui.app import HapTableApp
from console.tui.camera_picture import overlay_pixels

from .conftest import wait_for


def _app(plugins, initial):
    return HapTableApp(Context("sim", plugins), fast=True, initial=initial)


def _sketched_dataset(root) -> None:
    """One subject's four repetitions of every gesture, sketched, as the dataset format
    has them (``plugins.gestures.dataset``)."""
    from plugins.gestures import sketch
    from plugins.gestures.dataset import write_background, write_sample

    bg = sketch.background()
    write_background(root, bg)
    rng = np.random.default_rng(3)
    for g in sketch.STATIC + sketch.DYNAMIC:
        for rep in range(4):
            poses = sketch.gesture_poses(
                g, 4 if g in sketch.STATIC else 5, pos_px=(320.0, 240.0),
                theta_deg=rng.uniform(-30, 30), left=bool(rep % 2), size=1.0, speed=1.0,
            )  # fmt: skip
            frames = [sketch.draw([p], bg, rng=rng) for p in poses]
            write_sample(root, g, f"s1_{rep:03d}", frames, subject="s1", fps=60,
                         hand="left" if rep % 2 else "right")  # fmt: skip


def _said(app) -> str:
    """The Camera screen's status line (its own outcomes: one error, one place)."""
    found = app.query("#camera-status")
    return str(found.first().render()) if found else ""


async def _first_frame(app, pilot):
    await wait_for(
        pilot,
        lambda: (
            app.session.camera_started is not None
            and app.session.camera_started.snapshot() is not None
        ),
        30,
        "first camera frame",
    )


def test_overlay_marks_hand_outline_contacts_and_target():
    hand = Hand(
        contour_px=np.array([[100.0, 100.0], [300.0, 100.0], [300.0, 300.0]]),
        center_px=(200.0, 200.0),
        radius_px=50.0,
        angle_deg=0.0,
        shape=HandShape.of(np.zeros(3), 1),
    )
    work = {"hands": (hand,), "contacts": (Contact(1, (320.0, 240.0)),)}
    ov = overlay_pixels((480, 640), cols=64, rows=24, work=work, target_px=(0.0, 0.0))
    assert tuple(ov[10, 10]) == (60, 220, 60)  # contour point (100, 100) px
    assert tuple(ov[24, 32]) == (255, 60, 60)  # the contact at the image centre
    assert tuple(ov[0, 0]) == (255, 230, 0)  # the target


def test_camera_view_tuning_and_background(plugins):
    async def scenario():
        app = _app(plugins, "camera")
        async with app.run_test(size=(100, 30)) as pilot:
            await _first_frame(app, pilot)
            svc = app.session.camera_started
            view = app.query_one("#camera-view")
            await wait_for(pilot, lambda: type(view.render()).__name__ != "Content", 10)
            # the twin's demo script shows a hand: the view reports it
            info = app.query_one("#camera-info")
            await wait_for(pilot, lambda: "hands 1" in str(info.render()), 30, "a hand")
            before = svc.params()["body_threshold"]
            await pilot.press("T")
            assert svc.params()["body_threshold"] == before + 2
            assert svc.classifier.params.body_threshold == before + 2  # next frame uses it
            await pilot.press("t", "t")
            assert svc.params()["body_threshold"] == before - 2
            bg_before = np.array(svc.classifier.background.image, copy=True)
            await pilot.press("b", "b")  # the twin's hand is in view: b again takes it
            assert not np.array_equal(bg_before, svc.classifier.background.image)
            await pilot.press("v")
            assert app.pane("camera").view == "diff"
            # leaving the camera screen stops the frame loop
            await pilot.press("f1")
            await wait_for(pilot, lambda: not svc.running, 10, "camera stopped")

    asyncio.run(scenario())


@pytest.mark.slow
def test_touch_calibration_wizard_on_the_twin(plugins):
    async def scenario():
        app = _app(plugins, "camera")
        async with app.run_test(size=(100, 30)) as pilot:
            await _first_frame(app, pilot)
            pane = app.pane("camera")
            await pilot.press("k")
            await wait_for(pilot, lambda: pane.cal_result is not None, 90, "calibration done")
            r = pane.cal_result.report()
            assert r["pairs"] == 12
            # the twin's touches scatter ~1.5 mm and land ~2 mm behind the target: the
            # leave-one-out error shows it (a residual correction may fit the touched
            # points themselves exactly)
            assert 0.5 < r["loo_rms_mm"] < 8.0
            assert r["rms_mm"] <= r["loo_rms_mm"]
            assert "on a new touch (leave-one-out" in pane.cal_message
            await pilot.press("S")
            # in the profile's state directory, never in the repository's profiles/
            path = paths.profile_state_dir("sim", "touch_calibration.json")
            saved = json.loads(path.read_text())
            assert saved["format"].startswith("haptable-touch-calibration")
            assert not (PROJECT_PROFILES / "touch_calibration.json").exists()

    asyncio.run(scenario())


def test_latency_screen_shows_stage_percentiles(plugins):
    async def scenario():
        app = _app(plugins, "latency")
        async with app.run_test(size=(100, 30)) as pilot:
            head = app.query_one("#lat-head")
            await wait_for(pilot, lambda: "m measures" in str(head.render()), 20, "the hint")
            await pilot.press("m")  # the screen starts no loop by itself: m measures
            await _first_frame(app, pilot)
            table = app.query_one("#lat-table")

            def rows():
                return {str(r[0]): r for r in map(table.get_row_at, range(table.row_count))}

            # the rows show once the loop reports; their p50 once a frame was processed
            await wait_for(
                pilot,
                lambda: str(rows().get("vision", ("", "-"))[1]) != "-",
                30,
                "latency rows with a vision p50",
            )
            assert {"vision", "classify"} <= set(rows())
            assert float(str(rows()["vision"][1])) > 0  # p50 ms (cells are text)
            head = str(app.query_one("#lat-head").render())
            assert "fps" in head and "dropped" in head
            # the audio line once the outputs are open (they may open after the camera)
            lat_audio = app.query_one("#lat-audio")
            await wait_for(
                pilot, lambda: "output latency" in str(lat_audio.render()), 30, "audio line"
            )
            assert "underruns 0" in str(lat_audio.render())

    asyncio.run(scenario())


def test_calibration_comes_from_the_classifier_and_is_absent_plainly(plugins):
    """k asks the classifier for its touch-calibration session (the pane imports no
    plugin); a classifier without one gets a plain sentence, not a crash."""

    async def scenario():
        app = _app(plugins, "camera")
        async with app.run_test(size=(100, 30)) as pilot:
            await _first_frame(app, pilot)
            pane = app.pane("camera")
            info = app.query_one("#camera-wizard")
            await pilot.press("k")
            assert pane.calibration is not None
            assert len(pane.calibration.targets_mm) == 12  # [projector] 4 x 3 targets
            await wait_for(pilot, lambda: "touch target 1 of 12" in str(info.render()), 10)
            await pilot.press("x")
            assert pane.calibration is None
            await wait_for(pilot, lambda: "calibration cancelled" in str(info.render()), 10)

            svc = app.session.camera_started
            real = svc.classifier
            plain = {k: getattr(real, k) for k in ("tunables", "tunable_ranges", "views")}
            svc.classifier = type("NoCalibration", (), plain)()  # no touch_calibration
            await pilot.press("k")
            assert pane.calibration is None
            await wait_for(pilot, lambda: "offers none" in str(info.render()), 10)
            assert "[gestures] classifier" in str(info.render())
            svc.classifier = real

    asyncio.run(scenario())


def test_g_opens_the_gestures_panel_and_a_model_trained_there_is_used(
    plugins, tmp_path, one_model_setting
):
    """From the Camera screen, g opens the Gestures panel; a model trained there to the
    profile's [gestures] model file goes straight to the camera's classifier."""
    from textual.widgets import Input

    async def scenario():
        app = _app(plugins, "camera")
        async with app.run_test(size=(80, 24)) as pilot:
            await _first_frame(app, pilot)
            assert app.session.camera_started.classifier.model is None  # the sim profile has none
            await wait_for(pilot, lambda: app.focused is app.pane("camera"), what="focus")
            await pilot.press("g")
            await wait_for(pilot, lambda: type(app.screen).__name__ == "GesturesPanel")
            panel = app.screen
            fields = ("#gp-files", "#gp-dataset", "#gp-model", "#gp-subjects", "#gp-reps")
            await wait_for(pilot, lambda: all(panel.query(f) for f in fields), what="panel")
            panel.default_model = tmp_path / "profile-model.skops"  # as if the profile named it
            # a dataset in the documented format, sketched (the panel's synthesis has a
            # test of its own: here what counts is where the trained model goes)
            await asyncio.to_thread(_sketched_dataset, tmp_path / "set")
            for name, value in (
                ("dataset", str(tmp_path / "set")),
                ("model", str(panel.default_model)),
            ):
                panel.query_one(f"#gp-{name}", Input).value = value
            work = panel.work
            await pilot.press("t", "t")  # t asks first, t again trains
            await wait_for(pilot, lambda: work.outcome is not None, 300, "trained")
            assert work.outcome == "done", work.text
            res = panel.query_one("#gp-result")
            await wait_for(pilot, lambda: "uses it now" in str(res.render()), 10)
            clf = app.session.camera_started.classifier
            assert clf.model is not None and clf.model.meta["evaluation"]["cv"] == "2fold"
            await pilot.press("escape")
            await wait_for(pilot, lambda: type(app.screen).__name__ != "GesturesPanel")
            # the camera screen now names a gesture for what the twin's hand does
            info = app.query_one("#camera-info")
            await wait_for(
                pilot, lambda: "gesture: -" not in str(info.render()), 30, "a gesture named"
            )

    asyncio.run(scenario())


def test_w_keeps_the_tuned_thresholds_for_the_profile(plugins):
    """T raises the body threshold, W writes it to the profile's overrides file and says
    where; the next load of the profile has it."""
    from console.config.profile import load_profile

    async def scenario():
        app = _app(plugins, "camera")
        async with app.run_test(size=(100, 30)) as pilot:
            await _first_frame(app, pilot)
            svc = app.session.camera_started
            before = svc.params()["body_threshold"]
            await pilot.press("T")
            await wait_for(pilot, lambda: svc.params()["body_threshold"] == before + 2)
            await pilot.press("W", "W")  # the first asks
            await wait_for(
                pilot,
                lambda: "overrides.toml" in _said(app),
                10,
                "the status line naming the file",
            )
            return before

    before = asyncio.run(scenario())
    assert load_profile("sim", plugins).get("vision.body_threshold") == before + 2


def test_devices_results_arriving_after_the_console_closed_are_dropped(plugins):
    """The camera test ends on the Devices screen (f1): its device listing (PortAudio, a
    probe per relay driver) may finish after the console has closed; its result must not
    raise into a console that is gone (it failed the camera test now and then)."""

    async def scenario():
        app = _app(plugins, "devices")
        async with app.run_test(size=(100, 30)) as pilot:
            await wait_for(pilot, lambda: app.pane("devices") is not None, 10, "devices")
            pane = app.pane("devices")
            await wait_for(pilot, lambda: pane.query("#audio-table"), 10, "composed")
            await pane.remove()  # what closing does to it
            pane._show_devices([], [])  # the worker's late result
            pane._show([])

    asyncio.run(scenario())


def test_contact_ids_are_written_next_to_the_contacts_on_the_view():
    """The classifier's contact ids appear as text on the half-block view, right of the
    contact's cell; the picture stays half blocks elsewhere."""
    from rich.console import Console

    from console.tui.camera_picture import blob_labels
    from console.tui.plots import HalfBlockImage

    work = {"contacts": (Contact(7, (320.0, 240.0)), Contact(12, (630.0, 10.0)))}
    labels = blob_labels((480, 640), cols=64, rows=24, work=work)
    assert labels == {(12, 34): "7", (0, 63): "12"}
    con = Console(width=80, record=True, color_system="truecolor")
    con.print(HalfBlockImage(np.full((48, 64), 90.0), None, labels))
    lines = con.export_text().splitlines()
    assert lines[12][34] == "7" and set(lines[12][:34]) == {"▀"}
    assert lines[0][63] == "1"  # clipped at the right edge, never wrapped
    assert len(lines[0]) == 64


def test_any_vision_setting_is_chosen_tuned_and_kept(plugins):
    """] walks to the smoothing setting, + raises it (the next frame uses it), W keeps
    every setting; the next console's classifier starts with them."""
    from console.config.profile import load_profile

    async def scenario():
        app = _app(plugins, "camera")
        async with app.run_test(size=(110, 40)) as pilot:
            await _first_frame(app, pilot)
            svc = app.session.camera_started
            pane = app.pane("camera")
            info = app.query_one("#camera-settings")
            # the twin takes exposure and gain (multipliers of its light): rows to tune
            await wait_for(pilot, lambda: "gain" in str(info.render()), 10)
            assert "gain" in svc.params() and "exposure" in svc.params()
            while pane.chosen_key() != "smooth_px":
                await pilot.press("right_square_bracket")
            before = svc.params()["smooth_px"]
            await pilot.press("plus")
            assert svc.classifier.params.smooth_px == before + 2
            await wait_for(
                pilot, lambda: f"▸ smooth_px {before + 2}" in str(info.render()), 10, "shown"
            )
            while pane.chosen_key() != "background_alpha":
                await pilot.press("left_square_bracket")
            alpha = svc.params()["background_alpha"]
            await pilot.press("minus")
            assert svc.classifier.background.alpha == pytest.approx(alpha - 0.005)
            await pilot.press("W", "W")  # the first asks
            await wait_for(
                pilot,
                lambda: "overrides.toml" in _said(app),
                10,
                "the status line naming the file",
            )
            return before + 2, alpha - 0.005

    smooth, alpha = asyncio.run(scenario())
    prof = load_profile("sim", plugins)
    assert prof.get("vision.smooth_px") == smooth
    assert prof.get("vision.background_alpha") == pytest.approx(alpha)
    clf = plugins.build("classifier", "svm", prof)
    assert clf.tunables()["smooth_px"] == smooth


def test_tuio_is_switched_and_pointed_from_the_camera_screen_and_kept(plugins):
    """U types the TUIO target, u switches it on: the camera loop's bundles reach a UDP
    socket there; both are kept for the profile and the next console's loop streams
    again; a bad target is one line and changes nothing."""
    import socket

    from console.config.profile import load_profile
    from console.session.camera import CameraService

    rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    rx.bind(("127.0.0.1", 0))
    rx.settimeout(10)
    port = rx.getsockname()[1]

    async def scenario():
        app = _app(plugins, "camera")
        async with app.run_test(size=(110, 40)) as pilot:
            await _first_frame(app, pilot)
            svc = app.session.camera_started
            info = app.query_one("#camera-settings")
            await wait_for(
                pilot, lambda: "tuio: off -> 127.0.0.1:3333" in str(info.render()), 10, "tuio off"
            )
            await pilot.press("U")
            box = app.query_one("#camera-target")
            assert box.display and box.has_focus
            box.value = "nowhere"
            await pilot.press("enter")
            await wait_for(
                pilot,
                lambda: "host:port" in _said(app),
                10,
                "the bad target refused",
            )
            await pilot.press("U")
            box.value = f"127.0.0.1:{port}"
            await pilot.press("enter")
            await wait_for(pilot, lambda: svc.sink_state("tuio")[1] == f"127.0.0.1:{port}")
            # the field closes once its answer is said, a refresh after the sender moved
            await wait_for(pilot, lambda: not box.display, 10, "the field closed")
            await pilot.press("u")
            await wait_for(pilot, lambda: svc.sink_state("tuio")[0], 10, "tuio on")
            await wait_for(pilot, lambda: f"tuio: on -> 127.0.0.1:{port}" in str(info.render()), 10)

    try:
        asyncio.run(scenario())
        data, _ = rx.recvfrom(65536)
        assert data.startswith(b"#bundle")
        prof = load_profile("sim", plugins)
        assert (prof.get("tuio.enabled"), prof.get("tuio.port")) == (True, port)
        while True:  # drain what the first console sent
            rx.settimeout(0.5)
            try:
                rx.recvfrom(65536)
            except TimeoutError:
                break
        svc = CameraService(prof, plugins)
        svc.start()
        try:
            rx.settimeout(10)
            assert rx.recvfrom(65536)[0].startswith(b"#bundle")  # restored at the next start
            svc.set_sink("tuio", False)
            assert load_profile("sim", plugins).get("tuio.enabled") is False
        finally:
            svc.close()
    finally:
        rx.close()


def test_the_view_turns_with_the_camera_and_the_roi_is_set_from_the_screen(plugins):
    """rotate_deg + turns the view upright for a camera mounted a quarter turn off (the
    view becomes portrait), roi_left_px + narrows what segmentation sees; W keeps both."""
    from console.config.profile import load_profile

    async def scenario():
        app = _app(plugins, "camera")
        async with app.run_test(size=(110, 40)) as pilot:
            await _first_frame(app, pilot)
            svc = app.session.camera_started
            pane = app.pane("camera")
            await wait_for(pilot, lambda: pane.shown is not None, 10, "a picture")
            rows2, cols = pane.shown.rgb.shape[:2]
            assert cols > rows2  # 640 x 480: landscape
            while pane.chosen_key() != "rotate_deg":
                await pilot.press("right_square_bracket")
            await pilot.press("plus")
            assert svc.classifier.orientation.rotate_deg == 90

            def portrait():
                r2, c = pane.shown.rgb.shape[:2]
                return r2 > c

            await wait_for(pilot, portrait, 10, "the turned view")
            while pane.chosen_key() != "roi_left_px":
                await pilot.press("right_square_bracket")
            await pilot.press("plus", "plus")
            assert svc.classifier.orientation.margins_px == (16, 0, 0, 0)
            await pilot.press("W", "W")  # the first asks
            await wait_for(
                pilot,
                lambda: "overrides.toml" in _said(app),
                10,
                "kept",
            )

    asyncio.run(scenario())
    prof = load_profile("sim", plugins)
    assert (prof.get("vision.rotate_deg"), prof.get("vision.roi_left_px")) == (90, 16)
    assert plugins.build("classifier", "svm", prof).orientation.margins_px == (16, 0, 0, 0)


def test_a_worker_s_result_after_the_console_closed_is_dropped(plugins):
    """``from_thread``, the way every pane's worker hands its result to the screen: once
    the console has stopped the result is dropped (None), never raised."""
    from console.tui.util import from_thread

    async def scenario():
        app = _app(plugins, "devices")
        async with app.run_test(size=(100, 30)) as pilot:
            await pilot.pause()
        return app

    app = asyncio.run(scenario())
    assert from_thread(app, lambda: 1 / 0) is None


def test_the_twin_renders_apart_at_the_view_s_rate_and_closing_ends_it(plugins):
    """On the twin the Camera screen's camera renders in its own process, at the rate the
    view shows (its info says so); the console's end leaves no camera process behind."""
    from console.tui.panes.camera import CameraPane

    async def scenario():
        app = _app(plugins, "camera")
        async with app.run_test(size=(120, 40)) as pilot:
            await _first_frame(app, pilot)
            st = app.session.camera_started.status()["camera"]
            assert st["process"] and st["alive"]
            assert st["rate_fps"] == CameraPane.VIEW_FPS
            info = app.query_one("#camera-info")
            said = lambda: " ".join(str(info.render()).split())  # noqa: E731
            await wait_for(pilot, lambda: "the view's rate; it can" in said(), 10, "rate")
            return st["pid"]

    pid = asyncio.run(scenario())
    try:
        with open(f"/proc/{pid}/stat") as f:
            state = f.read().rsplit(")", 1)[1].split()[0]
    except FileNotFoundError:
        state = "gone"
    assert state in ("gone", "Z"), "the camera process ended with the console"


def test_the_live_numbers_re_layout_the_panel_only_when_its_rows_may_change():
    """The side panel's live block: numbers changing within lines that fit (or keep their
    length) take the same rows (no layout of the screen); a line more, or a line that
    wraps and changed its length, may not."""
    from console.tui.camera_picture import same_height

    a = "twin: 7 fps\nloop 7 fps, dropped 0 (camera) + 0 (queue)\ngain 1"
    assert same_height(a, "twin: 8 fps\nloop 8 fps, dropped 0 (camera) + 0 (queue)\ngain 0.995", 31)
    assert not same_height(a, a + "\nnoise 2.9", 31)
    assert not same_height(
        a, "twin: 7 fps\nloop 7 fps, dropped 12 (camera) + 0 (queue)\ngain 1", 31
    )
    assert same_height(a, "twin: 7 fps\nloop 7 fps, dropped 12 (camera) + 0 (queue)\ngain 1", 60)
