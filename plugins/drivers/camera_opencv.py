"""A real camera through OpenCV (V4L2 on Linux): the PS3 Eye under the glass.

A grab thread reads frames as the camera delivers them, converts them to 8-bit
grayscale and keeps the newest; ``read(timeout_s)`` hands out each frame at most once.
After consecutive read failures (an unplug) the capture is released and reopened with
exponential backoff (state ``reconnecting``). ``status()`` reports the measured frame
rate and dropped frames: those the camera skipped (gaps in arrival times longer than
1.5 frame periods) and those the reader missed while it was reading (it read within
``READER_AWAY_S``, or waits in ``read``). Frames that came while nobody read (a screen
not shown, a stopped loop) are not drops: ``unread`` counts them apart. Frame ``seq`` counts camera frame
slots, so a consumer sees every drop as a gap. ``t_capture_s`` is the V4L2 buffer
timestamp (CLOCK_MONOTONIC, the clock of ``time.monotonic``) when the driver gives a
plausible one, else the time the read returned. ``cv2`` is imported lazily.
"""

from __future__ import annotations

import contextlib
import glob
import os
import sys
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import numpy as np

from console.plugin_api import DeviceStatus, Frame, TunableRange
from plugins.drivers.errors import DeviceError


def to_gray8(image: np.ndarray) -> np.ndarray:
    """8-bit single-channel image from what a capture returns (gray, BGR, BGRA, 16-bit)."""
    img = np.asarray(image)
    if img.ndim == 3 and img.shape[2] == 1:
        img = img[:, :, 0]
    if img.dtype == np.uint16:
        img = (img >> 8).astype(np.uint8)
    elif img.dtype != np.uint8:
        raise ValueError(f"camera gave {img.dtype} pixels; expected 8- or 16-bit")
    if img.ndim == 2:
        return np.ascontiguousarray(img)
    if img.ndim == 3 and img.shape[2] in (3, 4):
        import cv2

        code = cv2.COLOR_BGR2GRAY if img.shape[2] == 3 else cv2.COLOR_BGRA2GRAY
        return cv2.cvtColor(img, code)  # BT.601 luma
    raise ValueError(f"camera gave an image of shape {img.shape}; expected (H, W) or (H, W, 3)")


class FrameTiming:
    """Arrival-time accounting: measured fps over a window and frames the camera skipped."""

    def __init__(self, nominal_fps: float, window: int = 120) -> None:
        self.period_s = 1.0 / float(nominal_fps)
        self.times_s: deque[float] = deque(maxlen=window)
        self.skipped = 0

    def add(self, t_s: float) -> int:
        """Record a frame arriving at ``t_s``; returns how many frames were skipped before it."""
        missed = 0
        if self.times_s:
            dt = t_s - self.times_s[-1]
            if dt > 1.5 * self.period_s:
                missed = max(0, round(dt / self.period_s) - 1)
        self.skipped += missed
        self.times_s.append(t_s)
        return missed

    def reset(self) -> None:
        """Forget the last arrival (after a reconnect the gap is not a camera drop)."""
        self.times_s.clear()

    @property
    def fps(self) -> float:
        if len(self.times_s) < 2:
            return 0.0
        span = self.times_s[-1] - self.times_s[0]
        return (len(self.times_s) - 1) / span if span > 0 else 0.0


def device_arg(device: str | int) -> str | int:
    """A V4L2 index (``0``, ``"0"``) stays an int; anything else is a path."""
    if isinstance(device, int):
        return device
    text = str(device).strip()
    return int(text) if text.isdigit() else text


def _video_nodes() -> list[str]:
    return sorted(glob.glob("/dev/video*"))


def _opencv_capture(device: str | int) -> Any:
    import cv2

    api = cv2.CAP_V4L2 if sys.platform.startswith("linux") else cv2.CAP_ANY
    return cv2.VideoCapture(device, api)


def _props() -> SimpleProps:
    import cv2

    return SimpleProps(
        cv2.CAP_PROP_FRAME_WIDTH,
        cv2.CAP_PROP_FRAME_HEIGHT,
        cv2.CAP_PROP_FPS,
        cv2.CAP_PROP_AUTO_EXPOSURE,
        cv2.CAP_PROP_EXPOSURE,
        cv2.CAP_PROP_GAIN,
        getattr(cv2, "CAP_PROP_READ_TIMEOUT_MSEC", None),
        cv2.CAP_PROP_POS_MSEC,
    )


class SimpleProps:
    """The VideoCapture property ids the driver sets (cv2's constants, or a test's)."""

    def __init__(
        self, width, height, fps, auto_exposure, exposure, gain, read_timeout_ms, pos_msec=None
    ):
        self.width, self.height, self.fps = width, height, fps
        self.auto_exposure, self.exposure, self.gain = auto_exposure, exposure, gain
        self.read_timeout_ms = read_timeout_ms
        self.pos_msec = pos_msec


#: the controls an operator changes while the camera runs (-1: the driver's automatic)
CONTROLS = {"exposure": TunableRange(-1.0, 10000.0, 10.0), "gain": TunableRange(-1.0, 255.0, 4.0)}

DEVICE_STAMP_MAX_AGE_S = 1.0  # a buffer timestamp older than this is not on our clock
#: a reader that has not called ``read`` for this long is away: frames meanwhile are unread
READER_AWAY_S = 0.5
V4L2_EXPOSURE_MANUAL = 1.0  # V4L2_CID_EXPOSURE_AUTO menu values
V4L2_EXPOSURE_AUTO = 3.0  # aperture priority: what UVC cameras call automatic
V4L2_EXPOSURE_AUTO_GSPCA = 0.0  # fully automatic: what gspca drivers (PS3 Eye) offer


class OpenCVCamera:
    """An OpenCV capture in a grab thread, reconnecting after an unplug."""

    def __init__(
        self,
        device: str | int = "0",
        width_px: int = 640,
        height_px: int = 480,
        fps: float = 60.0,
        exposure: float = -1.0,
        gain: float = -1.0,
        *,
        open_capture: Callable[[str | int], Any] | None = None,
        props: SimpleProps | None = None,
        clock: Callable[[], float] = time.monotonic,
        fail_limit: int = 3,
        backoff_s: tuple[float, float] = (0.1, 2.0),
    ) -> None:
        self.device = device_arg(device)
        self.width_px, self.height_px, self.fps = int(width_px), int(height_px), float(fps)
        self.exposure, self.gain = float(exposure), float(gain)
        self._open_capture = open_capture or _opencv_capture
        self._props = props or _props()
        self._clock = clock
        self._fail_limit = int(fail_limit)
        self._backoff_s = backoff_s
        self._timing = FrameTiming(self.fps)
        self._cond = threading.Condition()
        self._stop = threading.Event()
        self._pending = threading.Event()  # exposure or gain changed while running
        self._latest: Frame | None = None
        self._taken = True
        self._seq = -1
        self._frames = 0
        self._dropped_reader = 0
        self._unread = 0  # frames replaced while nobody was reading
        self._reading = 0  # read() calls waiting now
        self._last_read_s = clock()  # the opener reads next: a reader from the start
        self._reconnects = 0
        self._bad_frames = 0
        self._device_stamps = 0
        self._rejected: list[str] = []
        self._state = "starting"
        self._error = ""
        self._size_px: tuple[int, int] = (0, 0)
        self.source = f"opencv:{self.device}"
        self._cap = self._open()
        if self._cap is None:
            nodes = ", ".join(_video_nodes()) or "none"
            raise DeviceError(
                f"[camera] device = {device!r}: cannot open the camera ({self._error}); "
                f"video devices present: {nodes}; plug it in or fix [camera] device"
            )
        self._state = "running"
        self._thread = threading.Thread(target=self._run, name="opencv-camera", daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ capture
    def _open(self) -> Any:
        try:
            cap = self._open_capture(self.device)
        except Exception as exc:
            self._error = f"{type(exc).__name__}: {exc}"
            return None
        if cap is None or not cap.isOpened():
            self._error = "the capture did not open"
            if cap is not None:
                cap.release()
            return None
        p = self._props
        rejected: list[str] = []

        def put(name: str, prop: Any, value: float) -> bool:
            ok = bool(cap.set(prop, value))
            if not ok:
                rejected.append(name)
            return ok

        put("width_px", p.width, self.width_px)
        put("height_px", p.height, self.height_px)
        put("fps", p.fps, self.fps)
        self._put_controls(cap, put)
        if p.read_timeout_ms is not None:
            cap.set(p.read_timeout_ms, 1000)  # not every backend has it: never reported
        self._rejected = rejected
        self._size_px = (int(cap.get(p.width)), int(cap.get(p.height)))
        self._error = ""
        return cap

    def _put_controls(self, cap: Any, put: Callable[[str, Any, float], bool]) -> None:
        """Exposure and gain to the capture (-1: the driver's automatic)."""
        p = self._props
        if self.exposure >= 0:
            put("auto_exposure", p.auto_exposure, V4L2_EXPOSURE_MANUAL)
            put("exposure", p.exposure, self.exposure)
        elif not cap.set(p.auto_exposure, V4L2_EXPOSURE_AUTO):  # UVC: aperture priority
            put("auto_exposure", p.auto_exposure, V4L2_EXPOSURE_AUTO_GSPCA)  # PS3 Eye: auto
        if self.gain >= 0:
            put("gain", p.gain, self.gain)

    def _apply_pending(self, cap: Any) -> None:
        """Controls set while running, applied from the grab thread (the one that reads
        the capture); a refused one is listed in ``settings_rejected``."""
        if not self._pending.is_set():
            return
        self._pending.clear()
        rejected = [r for r in self._rejected if r not in ("auto_exposure", "exposure", "gain")]

        def put(name: str, prop: Any, value: float) -> bool:
            ok = bool(cap.set(prop, value))
            if not ok:
                rejected.append(name)
            return ok

        self._put_controls(cap, put)
        self._rejected = rejected

    # ------------------------------------------------------------------ AdjustableCamera
    def controls(self) -> dict[str, TunableRange]:
        """Exposure and gain (driver units; -1: automatic)."""
        return dict(CONTROLS)

    def control_values(self) -> dict[str, float]:
        return {"exposure": self.exposure, "gain": self.gain}

    def control_keys(self) -> dict[str, str]:
        return {"exposure": "camera.exposure", "gain": "camera.gain"}

    def set_control(self, name: str, value: float) -> None:
        """Exposure or gain from the next frames on (-1 or below: automatic)."""
        rng = CONTROLS.get(name)
        if rng is None:
            raise ValueError(f"{name!r} is no camera control: use one of {', '.join(CONTROLS)}")
        v = max(-1.0, float(rng.clamp(value)))
        if name == "exposure":
            self.exposure = v
        else:
            self.gain = v
        self._pending.set()

    def _release(self) -> None:
        cap, self._cap = self._cap, None
        if cap is not None:
            with contextlib.suppress(Exception):
                cap.release()

    def _reconnect(self) -> None:
        self._release()
        self._state = "reconnecting"
        self._timing.reset()
        delay = self._backoff_s[0]
        while not self._stop.is_set():
            if self._stop.wait(delay):
                return
            cap = self._open()
            if cap is not None:
                self._cap = cap
                self._reconnects += 1
                self._state = "running"
                return
            delay = min(delay * 2, self._backoff_s[1])

    def _capture_time(self, cap: Any, now_s: float) -> float:
        """The driver's buffer timestamp when it is on our clock (V4L2: CLOCK_MONOTONIC,
        as ``time.monotonic``), else the time ``read`` returned."""
        if self._props.pos_msec is None:
            return now_s
        try:
            t_dev_s = float(cap.get(self._props.pos_msec)) / 1e3
        except Exception:
            return now_s
        if 0.0 <= now_s - t_dev_s <= DEVICE_STAMP_MAX_AGE_S:
            self._device_stamps += 1
            return t_dev_s
        return now_s

    def _run(self) -> None:
        fails = 0
        while not self._stop.is_set():
            cap = self._cap
            if cap is None:
                self._reconnect()
                continue
            self._apply_pending(cap)
            try:
                ok, image = cap.read()
            except Exception as exc:
                ok, image = False, None
                self._error = f"read: {type(exc).__name__}: {exc}"
            if not ok or image is None:
                fails += 1
                self._error = self._error or "read failed"
                if fails >= self._fail_limit:
                    fails = 0
                    self._reconnect()
                continue
            fails = 0
            now = self._clock()
            t_s = self._capture_time(cap, now)
            try:
                gray = to_gray8(image)
            except ValueError as exc:
                self._bad_frames += 1
                self._error = str(exc)
                continue
            missed = self._timing.add(t_s)
            with self._cond:
                self._seq += 1 + missed
                self._frames += 1
                if not self._taken:  # replaced unread: a drop only if someone reads
                    reading = self._reading or now - self._last_read_s <= READER_AWAY_S
                    if reading:
                        self._dropped_reader += 1
                    else:
                        self._unread += 1
                self._latest = Frame(gray, self._seq, t_s, self.source)
                self._taken = False
                self._cond.notify_all()

    # ------------------------------------------------------------------ Camera
    def read(self, timeout_s: float = 0.1) -> Frame | None:
        """The newest frame not yet returned, waiting up to ``timeout_s``; else None."""
        with self._cond:
            self._reading += 1
            try:
                if self._taken:
                    self._cond.wait_for(lambda: not self._taken or self._stop.is_set(), timeout_s)
                if self._taken or self._latest is None:
                    return None
                self._taken = True
                return self._latest
            finally:
                self._reading -= 1
                self._last_read_s = self._clock()

    def close(self) -> None:
        """Stop the grab thread and release the camera. Safe to call twice."""
        self._stop.set()
        with self._cond:
            self._cond.notify_all()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout=5.0)
        self._release()
        self._state = "stopped"

    def status(self) -> dict[str, Any]:
        return {
            "driver": "opencv",
            "device": str(self.device),
            "state": self._state,
            "fps": self._timing.fps,
            "fps_requested": self.fps,
            "size_px": self._size_px,
            "frames": self._frames,
            "dropped": self._timing.skipped + self._dropped_reader,
            "dropped_camera": self._timing.skipped,
            "dropped_reader": self._dropped_reader,
            "unread": self._unread,
            "bad_frames": self._bad_frames,
            "device_timestamps": self._device_stamps,
            "settings_rejected": list(
                self._rejected
            ),  # [camera] keys the driver refused  # frames stamped by the driver's clock
            "reconnects": self._reconnects,
            "error": self._error,
        }


def from_profile(profile: Any) -> OpenCVCamera:
    """Factory registered as camera ``opencv``."""
    return OpenCVCamera(
        device=profile.get("camera.device"),
        width_px=profile.get("camera.width_px"),
        height_px=profile.get("camera.height_px"),
        fps=profile.get("camera.fps"),
        exposure=profile.get("camera.exposure"),
        gain=profile.get("camera.gain"),
    )


def probe(profile: Any) -> DeviceStatus:
    """Does the V4L2 node exist and may we open it? (does not open the camera)"""
    name = "opencv"
    try:
        import cv2  # noqa: F401
    except ImportError as exc:
        return DeviceStatus(
            "camera", name, "missing", f"cv2: {exc}", "pip install opencv-contrib-python-headless"
        )
    dev = device_arg(profile.get("camera.device"))
    if not sys.platform.startswith("linux"):
        return DeviceStatus("camera", name, "ok", f"device {dev!r} (not checked on this OS)")
    node = f"/dev/video{dev}" if isinstance(dev, int) else dev
    if not os.path.exists(node):
        nodes = ", ".join(_video_nodes()) or "none"
        return DeviceStatus(
            "camera",
            name,
            "missing",
            f"{node} does not exist (video devices: {nodes})",
            "plug in the camera (PS3 Eye) or set [camera] device",
        )
    if not os.access(node, os.R_OK | os.W_OK):
        return DeviceStatus(
            "camera",
            name,
            "missing",
            f"no read/write permission on {node}",
            "add your user to the 'video' group (sudo usermod -aG video $USER), log in again",
        )
    label = ""
    sys_name = f"/sys/class/video4linux/{os.path.basename(node)}/name"
    if os.path.exists(sys_name):
        with open(sys_name, encoding="utf-8", errors="replace") as f:
            label = f" ({f.read().strip()})"
    return DeviceStatus("camera", name, "ok", f"{node}{label}")
