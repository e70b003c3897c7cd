"""The OpenCV camera driver with a fake VideoCapture injected at the seam (no camera)."""

from __future__ import annotations

import os
import queue

import numpy as np
import pytest

from plugins.drivers import camera_opencv
from plugins.drivers.camera_opencv import FrameTiming, OpenCVCamera, SimpleProps, to_gray8
from plugins.drivers.errors import DeviceError

PROPS = SimpleProps("W", "H", "FPS", "AUTO_EXP", "EXP", "GAIN", "READ_TIMEOUT", "POS_MSEC")


class World:
    """A simulated camera on a USB port: plugged or not, a clock, frames the test releases."""

    def __init__(self, fps: float = 60.0, size=(480, 640)) -> None:
        self.t_s = 100.0
        self.period_s = 1.0 / fps
        self.size = size
        self.plugged = True
        self.events: queue.Queue = queue.Queue()
        self.captures: list[FakeCapture] = []
        self.n = 0
        self.stop = None  # the camera's stop event: a blocked read returns when it is set
        self.stamp_lag_s: float | None = None  # buffer timestamp this long before the read
        self.refuse: set[tuple[str, float]] = set()  # (property, value) the driver refuses

    @property
    def stamp_ms(self) -> float:
        return 0.0 if self.stamp_lag_s is None else (self.t_s - self.stamp_lag_s) * 1e3

    def clock(self) -> float:
        return self.t_s

    def open(self, device):
        cap = FakeCapture(self, device)
        self.captures.append(cap)
        return cap

    def frame(self, skipped: int = 0, image: np.ndarray | None = None) -> None:
        self.events.put(("frame", skipped, image))

    def fail(self, n: int = 1) -> None:
        for _ in range(n):
            self.events.put(("fail", 0, None))


class FakeCapture:
    def __init__(self, world: World, device) -> None:
        self.world, self.device = world, device
        self.opened = world.plugged
        self.released = False
        self.props: dict = {}

    def isOpened(self) -> bool:  # noqa: N802 (cv2's name)
        return self.opened

    def set(self, prop, value) -> bool:
        if (prop, value) in self.world.refuse:
            return False
        self.props[prop] = value
        return True

    def get(self, prop) -> float:
        if prop == "POS_MSEC":  # the driver's buffer timestamp, ms on the monotonic clock
            return self.world.stamp_ms
        return {"W": self.world.size[1], "H": self.world.size[0]}.get(prop, self.props.get(prop, 0))

    def read(self):
        while not self.released and not (self.world.stop and self.world.stop.is_set()):
            try:
                kind, skipped, image = self.world.events.get(timeout=0.01)
            except queue.Empty:
                continue
            if kind == "fail" or not self.world.plugged:
                return False, None
            self.world.t_s += self.world.period_s * (1 + skipped)
            self.world.n += 1
            if image is None:
                image = np.full((*self.world.size, 3), self.world.n % 256, np.uint8)
            return True, image
        return False, None

    def release(self) -> None:
        self.released = True


@pytest.fixture
def world():
    return World()


@pytest.fixture
def camera(world):
    cams = []

    def make(**kw) -> OpenCVCamera:
        kw.setdefault("backoff_s", (0.001, 0.004))
        world.stop = None
        cam = OpenCVCamera(open_capture=world.open, props=PROPS, clock=world.clock, **kw)
        world.stop = cam._stop
        cams.append(cam)
        return cam

    yield make
    for cam in cams:
        cam.close()


def frames_seen(cam: OpenCVCamera, n: int, wait) -> None:
    wait(lambda: cam.status()["frames"] >= n, 10, f"{n} frames")


# ---------------------------------------------------------------- pure parts
def test_gray_conversion_matches_bt601_luma():
    rng = np.random.default_rng(3)
    bgr = rng.integers(0, 256, (48, 64, 3), dtype=np.uint8)
    b, g, r = (bgr[:, :, i].astype(np.float64) for i in range(3))
    luma = 0.299 * r + 0.587 * g + 0.114 * b  # ITU-R BT.601, in floating point
    got = to_gray8(bgr)
    assert got.dtype == np.uint8 and got.shape == (48, 64)
    assert np.max(np.abs(got - luma)) < 1.0  # within one grey level of the exact value
    assert np.mean(np.abs(got - np.round(luma))) < 0.01  # and nearly always the rounded one
    bgra = np.dstack([bgr, np.full((48, 64), 255, np.uint8)])
    np.testing.assert_array_equal(to_gray8(bgra), got)
    gray = bgr[:, :, 1]
    np.testing.assert_array_equal(to_gray8(gray), gray)
    np.testing.assert_array_equal(to_gray8(gray[:, :, None]), gray)
    y16 = (gray.astype(np.uint16) << 8) | 0x7F
    np.testing.assert_array_equal(to_gray8(y16), gray)


@pytest.mark.parametrize(
    "bad", [np.zeros((4, 4), np.float32), np.zeros((4, 4, 2), np.uint8), np.zeros(16, np.uint8)]
)
def test_gray_conversion_refuses_what_it_cannot_convert(bad):
    with pytest.raises(ValueError, match="camera gave"):
        to_gray8(bad)


def test_frame_timing_counts_skipped_frames_and_fps():
    t = FrameTiming(60.0)
    p = 1 / 60
    assert [t.add(100 + k * p) for k in range(10)] == [0] * 10
    assert t.fps == pytest.approx(60.0)
    assert t.add(100 + 9 * p + 3 * p) == 2  # two frames never arrived
    assert t.add(100 + 13 * p + 0.4 * p) == 0  # jitter below 1.5 periods is not a drop
    assert t.skipped == 2
    t.reset()
    assert t.add(500.0) == 0  # a reconnect gap is not counted


def test_device_argument():
    assert camera_opencv.device_arg("0") == 0 and camera_opencv.device_arg(2) == 2
    assert camera_opencv.device_arg("/dev/video4") == "/dev/video4"


# ---------------------------------------------------------------- the camera
def test_settings_from_the_profile_are_applied(world, camera, stub_profile, monkeypatch):
    monkeypatch.setattr(camera_opencv, "_opencv_capture", world.open)
    monkeypatch.setattr(camera_opencv, "_props", lambda: PROPS)
    p = stub_profile(camera__device="/dev/video2", camera__fps=75.0, camera__exposure=120.0)
    cam = camera_opencv.from_profile(p)
    world.stop = cam._stop
    try:
        cap = world.captures[0]
        assert cap.device == "/dev/video2"
        assert cap.props["W"] == 640 and cap.props["H"] == 480 and cap.props["FPS"] == 75.0
        assert cap.props["AUTO_EXP"] == 1.0 and cap.props["EXP"] == 120.0  # manual exposure
        assert "GAIN" not in cap.props  # -1: leave the camera's automatic gain alone
        assert cam.status()["size_px"] == (640, 480)
    finally:
        cam.close()
    cam2 = camera(exposure=-1, gain=30)
    cap2 = world.captures[-1]
    assert cap2.props["AUTO_EXP"] == 3.0 and "EXP" not in cap2.props and cap2.props["GAIN"] == 30
    assert cam2.status()["state"] == "running"


def test_ps3_eye_automatic_exposure_and_refused_settings_are_reported(world, camera):
    world.refuse = {("AUTO_EXP", 3.0), ("FPS", 75.0)}  # gspca ov534: auto is menu value 0
    cam = camera(fps=75.0)
    cap = world.captures[-1]
    assert cap.props["AUTO_EXP"] == 0.0
    assert cam.status()["settings_rejected"] == ["fps"]  # the operator sees what did not apply


def test_frames_are_grayscale_handed_out_once(world, camera, wait):
    cam = camera()
    assert cam.read(timeout_s=0.01) is None  # nothing yet
    world.frame()
    f = cam.read(timeout_s=5)
    assert f is not None
    assert f.image.dtype == np.uint8 and f.image.shape == (480, 640)
    assert np.all(f.image == 1) and f.seq == 0
    assert f.t_capture_s == pytest.approx(100 + 1 / 60)
    assert cam.read(timeout_s=0.01) is None  # not handed out twice
    world.frame()
    assert cam.read(timeout_s=5).seq == 1


def test_capture_time_is_the_driver_timestamp_when_plausible(world, camera, wait):
    world.stamp_lag_s = 0.004  # the frame left the sensor 4 ms before read() returned
    cam = camera()
    world.frame()
    f = cam.read(5)
    assert f.t_capture_s == pytest.approx(100 + 1 / 60 - 0.004)
    world.stamp_lag_s = 3600.0  # a timestamp on some other clock is not used
    world.frame()
    g = cam.read(5)
    assert g.t_capture_s == pytest.approx(100 + 2 / 60)
    assert cam.status()["device_timestamps"] == 1


def test_frames_the_reader_missed_and_frames_the_camera_skipped(world, camera, wait):
    cam = camera()
    for _ in range(3):
        world.frame()
    frames_seen(cam, 3, wait)
    f = cam.read(0.01)
    assert f.seq == 2 and np.all(f.image == 3)  # the newest; two were never read
    world.frame(skipped=2)  # the camera lost two frames on the bus
    frames_seen(cam, 4, wait)
    g = cam.read(0.01)
    assert g.seq == 5  # a gap of two in the sequence
    st = cam.status()
    assert (st["dropped_reader"], st["dropped_camera"], st["dropped"]) == (2, 2, 4)
    assert st["frames"] == 4


def test_measured_fps(world, camera, wait):
    cam = camera()
    for _ in range(30):
        world.frame()
    frames_seen(cam, 30, wait)
    assert cam.status()["fps"] == pytest.approx(60.0)


def test_bad_frame_is_counted_not_fatal(world, camera, wait):
    cam = camera()
    world.frame(image=np.zeros((480, 640), np.float64))
    world.frame()
    frames_seen(cam, 1, wait)
    st = cam.status()
    assert st["bad_frames"] == 1 and "float64" in st["error"]
    assert cam.read(1).image.dtype == np.uint8


def test_unplug_reconnects_and_frames_flow_again(world, camera, wait):
    cam = camera(fail_limit=3)
    world.frame()
    assert cam.read(5) is not None
    world.plugged = False
    world.fail(3)
    wait(lambda: cam.status()["state"] == "reconnecting", 10, "reconnecting")
    assert world.captures[0].released
    wait(lambda: len(world.captures) >= 4, 10, "retries with backoff")
    assert cam.read(0.01) is None
    world.t_s += 7.0  # seven seconds unplugged: not 420 dropped frames
    world.plugged = True
    wait(lambda: cam.status()["state"] == "running", 10, "reconnected")
    assert world.captures[-1].props["W"] == 640  # settings re-applied to the new capture
    world.frame()
    world.frame()
    frames_seen(cam, 3, wait)
    f = cam.read(1)
    assert f is not None and f.seq == 2
    st = cam.status()
    assert st["reconnects"] == 1 and st["dropped_camera"] == 0
    assert all(c.released for c in world.captures[:-1])


def test_a_single_failed_read_does_not_reconnect(world, camera, wait):
    cam = camera(fail_limit=3)
    world.fail(2)
    world.frame()
    frames_seen(cam, 1, wait)
    assert cam.status()["reconnects"] == 0 and len(world.captures) == 1


def test_camera_absent_at_start_is_a_clear_error(world):
    world.plugged = False
    with pytest.raises(DeviceError, match=r"\[camera\] device = '3'.*video devices present"):
        OpenCVCamera("3", open_capture=world.open, props=PROPS)


def test_close_is_idempotent_and_releases(world, camera):
    cam = camera()
    cam.close()
    cam.close()
    assert world.captures[0].released
    assert cam.status()["state"] == "stopped"
    assert cam.read(0.01) is None


# ---------------------------------------------------------------- probe
def test_probe_missing_node(stub_profile):
    st = camera_opencv.probe(stub_profile(camera__device="/dev/video-does-not-exist"))
    assert st.state == "missing" and "does not exist" in st.why and "plug in" in st.fix


def test_probe_present_node(stub_profile, tmp_path):
    node = tmp_path / "video9"
    node.write_bytes(b"")
    st = camera_opencv.probe(stub_profile(camera__device=str(node)))
    assert st.state == "ok" and str(node) in st.why


@pytest.mark.skipif(os.geteuid() == 0, reason="root may open any device node")
def test_probe_without_permission(stub_profile, tmp_path):
    node = tmp_path / "video9"
    node.write_bytes(b"")
    node.chmod(0)
    st = camera_opencv.probe(stub_profile(camera__device=str(node)))
    assert st.state == "missing" and "video" in st.fix


def test_real_videocapture_on_a_file_gives_gray_frames_and_reopens_at_its_end(tmp_path, wait):
    """The real cv2.VideoCapture (FFMPEG on a file instead of V4L2): types, sizes, and
    end-of-file read failures treated like an unplug (release, reopen, frames again)."""
    cv2 = pytest.importorskip("cv2")
    path = tmp_path / "clip.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 60, (64, 48))
    if not writer.isOpened():
        pytest.skip("this OpenCV cannot write MJPG .avi")
    levels = [20 * (i + 1) for i in range(10)]
    for level in levels:
        writer.write(np.full((48, 64, 3), level, np.uint8))
    writer.release()

    cam = OpenCVCamera(
        str(path),
        fps=60,
        open_capture=lambda d: cv2.VideoCapture(d, cv2.CAP_ANY),
        fail_limit=2,
        backoff_s=(0.05, 0.1),
    )
    try:
        wait(lambda: cam.status()["reconnects"] >= 1, 20, "end of file and a reopen")
        wait(lambda: cam.status()["frames"] > len(levels), 20, "frames after the reopen")
        frame = cam.read(5)
        st = cam.status()
    finally:
        cam.close()
    assert frame is not None
    assert frame.image.dtype == np.uint8 and frame.image.shape == (48, 64)
    assert min(abs(float(frame.image.mean()) - lv) for lv in levels) < 4  # MJPG is lossy
    assert st["size_px"] == (64, 48)  # the file cannot be resized: the real size is reported
    assert "width_px" in st["settings_rejected"]
    assert st["bad_frames"] == 0


def test_frames_that_came_while_nobody_read_are_not_drops(world, camera, wait):
    """A camera kept open while its screen is hidden: the frames meanwhile are unread,
    not dropped; frames a reader misses while it reads still are."""
    cam = camera()
    assert cam.read(0.01) is None  # the reader is there ...
    world.t_s += 5.0  # ... then away for five seconds (the Camera screen hidden)
    for _ in range(4):
        world.frame()
    frames_seen(cam, 4, wait)
    assert cam.read(0.01).seq == 3  # back: the newest
    st = cam.status()
    assert (st["dropped"], st["dropped_reader"], st["unread"]) == (0, 0, 3)
    for _ in range(3):  # reading again: what it misses now is dropped
        world.frame()
    frames_seen(cam, 7, wait)
    cam.read(0.01)
    st = cam.status()
    assert (st["dropped"], st["dropped_reader"], st["unread"]) == (2, 2, 3)


def test_exposure_and_gain_change_while_running_from_the_grab_thread(world, camera, wait):
    """The console sets exposure and gain on a running camera (``AdjustableCamera``): the
    grab thread hands them to the capture before its next read; -1 is automatic again;
    a value the driver refuses is reported, and reported no more once one is taken."""
    from console.core.contracts import AdjustableCamera

    cam = camera()
    cap = world.captures[-1]
    assert isinstance(cam, AdjustableCamera)
    assert cam.control_values() == {"exposure": -1.0, "gain": -1.0}
    assert "GAIN" not in cap.props and cap.props["AUTO_EXP"] == 3.0
    cam.set_control("gain", 40)
    cam.set_control("exposure", 120)
    world.frame()
    wait(lambda: cap.props.get("GAIN") == 40.0, 10, "the gain applied")
    wait(lambda: cap.props.get("EXP") == 120.0, 10, "the exposure applied")
    assert cap.props["AUTO_EXP"] == 1.0  # manual exposure
    world.refuse = {("GAIN", 44.0)}
    cam.set_control("gain", 44)
    cam.set_control("exposure", -30)  # below -1: automatic
    world.frame()
    wait(lambda: cam.status()["settings_rejected"] == ["gain"], 10, "the refusal reported")
    assert cap.props["AUTO_EXP"] == 3.0 and cam.control_values()["exposure"] == -1.0
    world.refuse = set()
    cam.set_control("gain", 48)
    world.frame()
    wait(lambda: cap.props.get("GAIN") == 48.0, 10, "the next gain applied")
    wait(lambda: cam.status()["settings_rejected"] == [], 10, "the refusal cleared")
    with pytest.raises(ValueError, match="no camera control"):
        cam.set_control("focus", 1)
    assert cam.control_keys() == {"exposure": "camera.exposure", "gain": "camera.gain"}
