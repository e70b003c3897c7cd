"""The session's camera runs while a screen watches it and stops when none does; a demo
borrowing it keeps it closed until given back."""

from __future__ import annotations

import time
from types import SimpleNamespace

import numpy as np


def _wait(cond, timeout_s: float = 30.0) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.05)
    return cond()


def test_camera_runs_while_watched(profile, plugins):
    from console.session import ConsoleSession
    from console.session.events import Started, Stopped

    session = ConsoleSession(SimpleNamespace(profile=profile, pm=plugins), fast=True)
    events: list = []
    session.subscribe(lambda e: events.append(e) if e.topic == "camera" else None)
    assert session.camera_started is None  # created on first use
    cam = session.camera
    assert session.camera is cam and not cam.running
    camera_screen, latency_screen = object(), object()
    try:
        cam.watch(camera_screen, True)
        assert cam.running and cam.watched
        assert _wait(lambda: cam.snapshot() is not None), "a first frame"
        cam.watch(latency_screen, True)
        cam.watch(camera_screen, False)
        assert cam.running  # the latency screen still watches
        cam.watch(camera_screen, False)  # twice: still one viewer left
        assert cam.running
        cam.watch(latency_screen, False)
        assert not cam.running and not cam.watched  # nobody watches: stopped
        assert [type(e) for e in events] == [Started, Stopped]
        assert events[-1].reason == "nobody watches"

        cam.watch(camera_screen, True)
        assert cam.running
        cam.release("demo flow")  # a demo process opens the camera itself
        assert not cam.running and cam.camera is None
        assert events[-1] == Stopped("camera", reason="in use by demo flow")
        cam.watch(latency_screen, True)
        assert not cam.running  # not while it is lent
        cam.give_back()
        cam.watch(latency_screen, True)
        assert cam.running
    finally:
        session.close()
    assert not cam.running and cam.camera is None  # the session closes it


def test_a_viewer_leaving_before_the_start_keeps_it_closed(profile, plugins):
    """The start runs in a worker: when the screen is hidden before that worker gets to
    open the camera, the loop is not started for nobody."""
    import threading

    from console.session import ConsoleSession

    session = ConsoleSession(SimpleNamespace(profile=profile, pm=plugins), fast=True)
    cam = session.camera
    viewer = object()
    with cam._start_lock:  # another start (or stop) holds the camera meanwhile
        worker = threading.Thread(target=cam.watch, args=(viewer, True))
        worker.start()
        assert _wait(lambda: cam.watched, 5)  # counted, waiting to start
        with cam._lock:  # the screen is hidden: its viewer leaves
            cam._viewers.pop(id(viewer), None)
    worker.join(30)
    assert not worker.is_alive()
    assert not cam.running and cam.camera is None
    session.close()


def test_tuned_thresholds_are_kept_for_the_next_start(profile, plugins):
    """The Camera screen's W: the classifier's tunables go to the profile's overrides file
    (the user's config directory, never the repository's profiles/), and the next load of
    the profile starts the classifier with them."""
    import pytest

    from console.config.profile import PROJECT_PROFILES, load_profile
    from console.core.errors import UserError
    from console.files import paths
    from console.runtime.stages import open_classifier
    from console.session import ConsoleSession

    sim = (PROJECT_PROFILES / "sim.toml").read_bytes()
    session = ConsoleSession(SimpleNamespace(profile=profile, pm=plugins), fast=True)
    cam = session.camera
    try:
        with pytest.raises(UserError, match="first frame"):
            cam.save_tuning()
        cam.classifier = open_classifier(profile, plugins)
        before = cam.params()
        cam.set_param("body_threshold", before["body_threshold"] + 4)
        cam.set_param("highpass_sigma_px", 2.5)
        tuned = cam.params()
        assert tuned != before
        path = cam.save_tuning()
    finally:
        session.close()
    assert path == paths.profile_config_dir("sim", "overrides.toml")
    again = load_profile("sim", plugins)
    assert again.get("vision.body_threshold") == before["body_threshold"] + 4
    assert again.get("vision.highpass_sigma_px") == 2.5
    assert open_classifier(again, plugins).tunables() == tuned
    assert (PROJECT_PROFILES / "sim.toml").read_bytes() == sim


class _DialCamera:
    """A camera whose driver takes exposure and gain (an ``AdjustableCamera``)."""

    def __init__(self) -> None:
        from console.core.types import TunableRange

        self.values = {"exposure": -1.0, "gain": -1.0}
        self.ranges = {"exposure": TunableRange(-1, 1000, 10), "gain": TunableRange(-1, 100, 4)}

    def read(self, timeout_s: float = 0.1):
        return None

    def close(self) -> None:
        pass

    def status(self) -> dict:
        return {"driver": "dial"}

    def controls(self):
        return dict(self.ranges)

    def control_values(self):
        return dict(self.values)

    def control_keys(self):
        return {"exposure": "camera.exposure", "gain": "camera.gain"}

    def set_control(self, name: str, value: float) -> None:
        self.values[name] = float(value)


def test_exposure_and_gain_are_tuned_and_kept_where_the_driver_takes_them(profile, plugins):
    from console.config.profile import load_profile
    from console.session.camera import CameraService

    svc = CameraService(profile, plugins)
    svc.classifier = plugins.build("classifier", "svm", profile)
    svc.camera = plugins.build("camera", profile.get("camera.driver"), profile)
    try:  # the twin takes them too: multipliers of its light before the 8-bit clip
        assert svc.camera_controls()
        assert svc.params()["gain"] == 1.0 and svc.params()["exposure"] == 1.0
    finally:
        svc.camera.close()
    svc.camera = _DialCamera()
    assert svc.camera_controls()
    svc.set_param("gain", 2000)  # kept in the driver's range
    svc.set_param("exposure", 250)
    svc.set_param("body_threshold", 20)  # the classifier's still reach it
    assert svc.camera.values == {"exposure": 250.0, "gain": 100.0}
    assert svc.params()["gain"] == 100.0 and svc.params()["body_threshold"] == 20.0
    svc.save_tuning()
    again = load_profile(profile.path, plugins)
    assert (again.get("camera.exposure"), again.get("camera.gain")) == (250.0, 100.0)
    assert again.get("vision.body_threshold") == 20.0


def _process_alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def test_the_twin_renders_apart_at_the_rate_its_viewers_need(profile, plugins):
    """On the twin the console's camera renders in its own process; while only viewers
    that show a few frames a second watch (the Camera screen), it delivers that many;
    a frame hook (a calibration, a study, TUIO) or a viewer wanting every frame (the
    Latency screen) gets the camera's full rate. Closing the session ends the process."""
    from console.session import ConsoleSession

    session = ConsoleSession(SimpleNamespace(profile=profile, pm=plugins), fast=True)
    cam = session.camera
    camera_screen, latency_screen = object(), object()
    try:
        cam.watch(camera_screen, True, fps=7.5)
        st = cam.status()["camera"]
        assert st["process"] and st["alive"], st
        pid = st["pid"]
        assert _process_alive(pid)
        assert cam.wanted_rate() == 7.5 and st["rate_fps"] == 7.5
        assert _wait(lambda: cam.snapshot() is not None), "a first frame"
        seq0 = cam.snapshot()[0].seq
        assert _wait(lambda: cam.snapshot()[0].seq >= seq0 + 3 * 8), "frames 8 apart"

        def hook(frame, work):
            return None

        cam.frame_hooks.append(hook)
        assert cam.wanted_rate() is None and cam.status()["camera"]["rate_fps"] is None
        cam.frame_hooks.remove(hook)
        assert cam.status()["camera"]["rate_fps"] == 7.5
        cam.watch(latency_screen, True)  # the Latency screen measures every frame
        assert cam.wanted_rate() is None
        cam.watch(latency_screen, False)
        assert cam.wanted_rate() == 7.5
    finally:
        session.close()
    assert not _process_alive(pid), "no camera process left after the console closed"


def test_a_hidden_camera_screen_leaves_the_twin_rendering_nothing(profile, plugins):
    """The camera stays open when its last viewer leaves (the next visit starts at once),
    but the twin's process renders nothing meanwhile (rate 0)."""
    from console.session import ConsoleSession

    session = ConsoleSession(SimpleNamespace(profile=profile, pm=plugins), fast=True)
    cam = session.camera
    viewer = object()
    try:
        cam.watch(viewer, True, fps=7.5)
        assert _wait(lambda: cam.snapshot() is not None), "a first frame"
        cam.watch(viewer, False)
        assert not cam.running and cam.camera is not None
        assert cam.wanted_rate() == 0.0 and cam.status()["camera"]["rate_fps"] == 0.0
        frames = cam.camera.status()["frames"]
        time.sleep(0.5)
        assert cam.camera.status()["frames"] == frames
        cam.watch(viewer, True, fps=7.5)  # back: frames again
        seq = cam.snapshot()[0].seq
        assert _wait(lambda: cam.snapshot()[0].seq > seq), "frames after the pause"
    finally:
        session.close()


def test_b_learns_only_from_frames_under_the_current_exposure(profile, plugins):
    """A background is the median of frames under one exposure and gain: a change starts
    the recent frames again, and a frame taken before the change (still in flight) is not
    kept."""
    from console.core.types import Frame
    from console.session.camera import CameraService

    svc = CameraService(profile, plugins)
    svc.classifier = plugins.build("classifier", "svm", profile)
    svc.camera = _DialCamera()
    dark = np.full((4, 4), 40, np.uint8)
    for k in range(5):
        svc._sink(Frame(dark, k, time.monotonic()), {})
    assert len(svc.recent) == 5
    taken_before = time.monotonic()
    svc.set_param("exposure", 250)  # the operator (or e) changes the exposure
    assert len(svc.recent) == 0
    svc._sink(Frame(np.full((4, 4), 250, np.uint8), 5, taken_before), {})  # in flight
    time.sleep(0.06)
    bright = np.full((4, 4), 120, np.uint8)
    for k in range(3):
        svc._sink(Frame(bright, 6 + k, time.monotonic()), {})
    assert len(svc.recent) == 3
    assert float(svc.median_background().max()) == 120.0


def test_leaving_the_camera_screen_mid_start_returns_at_once(profile, plugins):
    """The Camera screen is left while the camera is still opening (slow driver, vision
    loading): the UI thread's leave returns at once, and the start that ends afterwards
    leaves the loop stopped."""
    import threading

    from console.session.camera import CameraService

    svc = CameraService(profile, plugins)
    gate = threading.Event()

    def slow_open(open_camera, open_classifier, learn_background):
        gate.wait(10)  # a driver that takes its time
        svc.camera = _DialCamera()
        svc.classifier = plugins.build("classifier", "svm", profile)

    svc._open = slow_open
    viewer = object()
    worker = threading.Thread(target=svc.watch, args=(viewer, True, 7.5))
    worker.start()
    assert _wait(lambda: svc._start_lock.locked(), 5)
    t0 = time.monotonic()
    svc.leave(viewer)
    assert time.monotonic() - t0 < 0.1, "the UI thread waited for the camera's start"
    gate.set()
    worker.join(30)
    assert _wait(lambda: not svc.running, 10), "started for nobody"
    svc.close()


def test_a_saved_model_that_does_not_fit_leaves_the_camera_running(profile, plugins):
    """A gesture model the vision cannot use (another version's, a broken file): the
    camera and its vision run on, no gesture is named, and the console says why with the
    fix where the operator is (no shell command)."""
    from console.session.camera import CameraService
    from plugins.gestures.settings import model_file

    path = model_file(profile)
    assert not path.exists()
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("a model from another version")
    svc = CameraService(profile, plugins)
    viewer = object()
    try:
        svc.watch(viewer, True)
        assert svc.running and not svc.error, svc.error
        assert _wait(lambda: svc.snapshot() is not None), "frames processed"
        assert "gestures.skops" in svc.classifier_problem
        assert "Camera (F2), g, then t" in svc.classifier_problem
        assert "haptable gestures" not in svc.classifier_problem
    finally:
        svc.close()
        path.unlink()


def test_closing_while_the_camera_opens_loads_no_vision_and_starts_nothing(profile, plugins):
    """The console quits while the Camera screen's start waits for the screen to take
    its first frame: the start gives up there (no vision loaded, no loop), the close does
    not wait for it, and nothing starts the camera again."""
    import threading

    from console.session.camera import CameraService

    built: list[str] = []

    class Counting:  # the plugins, counting what is built
        def __getattr__(self, name):
            return getattr(plugins, name)

        def build(self, kind, name, prof):
            built.append(kind)
            return plugins.build(kind, name, prof)

    svc = CameraService(profile, Counting())
    viewer = object()  # a screen that shows frames but never takes the first one
    worker = threading.Thread(target=svc.watch, args=(viewer, True, 30.0))
    worker.start()
    try:
        assert _wait(lambda: svc.camera is not None, 30), "the camera opened"
        assert "classifier" not in built  # still waiting for the first frame to be taken
        closer = threading.Thread(target=svc.close)
        closer.start()
        worker.join(30)
        closer.join(30)
        assert not worker.is_alive() and not closer.is_alive()
        assert "classifier" not in built, "the vision loaded for a console that quit"
        assert not svc.running and svc.camera is None and svc.classifier is None
        svc.watch(viewer, True, 30.0)  # a screen's late worker: the service stays closed
        assert not svc.running and svc.camera is None
    finally:
        svc.close()
