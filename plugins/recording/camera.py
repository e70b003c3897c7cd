"""The camera driver ``replay``: a recording's frames with their recorded frame numbers
and capture times, as fast as they are read (``realtime=False``) or at their recorded
pace; ``ready`` holds each frame until a frame loop can take it. Without
``[recording] replay_file`` it gives no frame and ``haptable doctor`` says what to set."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from console.plugin_api import DeviceStatus, Frame, UserError

from .reader import Recording, open_recording

NO_FILE = "set [recording] replay_file to a recording (haptable demo ... --record FILE)"


class ReplayCamera:
    """A recording's frames as a camera: ``read()`` gives them in order, then ``None``
    (``recording`` ``None``: none at all). ``close()`` closes the file when ``owns``."""

    def __init__(
        self, recording: Recording | None, *, realtime: bool = False, owns: bool = False
    ) -> None:
        self.rec, self.realtime, self.owns = recording, realtime, owns
        #: ``ready() -> bool``: hold the next frame until it says so (a frame loop's queue
        #: empty: no frame dropped however slow the machine); ``None``: never held
        self.ready: Any = None
        self._k = 0
        self._t0: float | None = None
        self._closed = False

    @property
    def n_frames(self) -> int:
        return 0 if self.rec is None else self.rec.n_frames

    @property
    def finished(self) -> bool:
        return self._k >= self.n_frames

    def read(self, timeout_s: float = 0.1) -> Frame | None:
        if self._closed or self.finished or self.rec is None:
            if self.rec is None:
                time.sleep(timeout_s)
            return None
        t_end = time.monotonic() + timeout_s
        while self.ready is not None and not self.ready():
            if time.monotonic() > t_end:
                return None
            time.sleep(0.001)
        k = self._k
        t_s = float(self.rec.t_capture_s[k])
        if self.realtime:
            now = time.monotonic()
            if self._t0 is None:
                self._t0 = now - t_s
            wait = self._t0 + t_s - now
            if wait > timeout_s:
                time.sleep(timeout_s)
                return None
            if wait > 0:
                time.sleep(wait)
        self._k += 1
        return Frame(self.rec.frame(k), int(self.rec.seq[k]), t_s, source="replay")

    def background(self) -> np.ndarray:
        bg = None if self.rec is None else self.rec.background()
        if bg is None:
            where = "no recording" if self.rec is None else f"recording {self.rec.path}"
            raise UserError(f"camera 'replay': {where} has no background; {NO_FILE}")
        return bg

    def status(self) -> dict:
        fps = 0.0
        if self.n_frames > 1:
            span_s = float(self.rec.t_capture_s[-1] - self.rec.t_capture_s[0])
            fps = (self.n_frames - 1) / span_s if span_s > 0 else 0.0
        out = {"driver": "replay", "fps": fps, "frames": self._k, "dropped": 0}
        if self.rec is None:
            out["error"] = NO_FILE
        return out

    def close(self) -> None:
        if not self._closed and self.owns and self.rec is not None:
            self.rec.close()
        self._closed = True


def open_replay_camera(profile: Any) -> ReplayCamera:
    """The camera driver ``replay``: ``[recording] replay_file``'s frames at their pace."""
    raw = profile.get("recording.replay_file") or ""
    rec = open_recording(profile.resolve(raw)) if raw else None
    return ReplayCamera(rec, realtime=True, owns=True)


def probe(profile: Any) -> DeviceStatus:
    """``haptable doctor``: the replay file opens (does not keep it open)."""
    raw = profile.get("recording.replay_file") or ""
    if not raw:
        return DeviceStatus("camera", "replay", "missing", "no [recording] replay_file", NO_FILE)
    try:
        with open_recording(profile.resolve(raw)) as rec:
            return DeviceStatus("camera", "replay", "ok", f"{rec.path}: {rec.n_frames} frames")
    except UserError as exc:
        return DeviceStatus("camera", "replay", "error", str(exc), NO_FILE)
