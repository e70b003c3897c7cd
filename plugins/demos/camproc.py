"""The scripted twin camera in its own process, as a camera device is.

A real camera exposes and transfers frames without costing the console's interpreter
anything; the twin camera renders its frames in Python, and in the console's process that
rendering competes for the GIL with vision, the knob and the audio driver thread.
``ProcessCamera`` runs the profile's twin camera (scripted for a demo) in a child process:
frames land in a ring of shared-memory slots and a pipe announces each one (slot, seq,
capture time on the system-wide monotonic clock, frames the renderer dropped). ``read``
copies the newest announced frame out; it waits on the pipe without holding the GIL.
"""

from __future__ import annotations

import json
import os
import pickle
import select
import struct
import subprocess
import sys
import time
from multiprocessing import resource_tracker, shared_memory
from typing import Any

import numpy as np

from console.plugin_api import Frame, UserError, load_plugins
from console.plugin_api.runtime import open_camera

from .script import script_twin

#: Shared-memory frame slots (the loop copies a frame out before it is reused).
SLOTS = 8
#: One announcement: slot, frame seq, capture time (monotonic s), frames the renderer lost.
MSG = struct.Struct("<iqdq")


def _child() -> None:
    """``python -m plugins.demos.camproc SHM DEMO``, the pickled profile on stdin."""
    shm_name, demo = sys.argv[1], sys.argv[2]
    profile = pickle.loads(sys.stdin.buffer.read(int(sys.stdin.buffer.readline())))
    cam = open_camera(profile, load_plugins())
    shm = shared_memory.SharedMemory(name=shm_name)
    resource_tracker.unregister(shm._name, "shared_memory")  # the parent owns it
    out = sys.stdout.buffer
    try:
        if demo:
            script_twin(cam, demo, profile)
        bg = cam.background()
        slots = np.ndarray((SLOTS + 1, *bg.shape), np.uint8, buffer=shm.buf)
        slots[SLOTS] = bg
        out.write(MSG.pack(-1, bg.shape[0], float(bg.shape[1]), 0))
        out.flush()
        k = 0
        while True:
            if select.select([sys.stdin], [], [], 0)[0]:
                line = sys.stdin.buffer.readline()
                if not line:  # stdin closed: stop
                    break
                _command(cam, line)
            f = cam.read(0.1)
            if f is None:
                continue
            slot = k % SLOTS
            slots[slot] = f.image
            dropped = int(cam.status().get("dropped", 0) or 0)
            out.write(MSG.pack(slot, f.seq, f.t_capture_s, dropped))
            out.flush()
            k += 1
    except (BrokenPipeError, KeyboardInterrupt):
        pass
    finally:
        cam.close()
        slots = None
        shm.close()


def _command(cam: Any, line: bytes) -> None:
    """One command from the parent (a JSON line): ``{"set_target": [x_mm, y_mm] | null}``
    puts the operator's hand on the twin (or gives it back to the script)."""
    cmd = json.loads(line)
    if "set_target" in cmd and callable(getattr(cam, "set_target", None)):
        t = cmd["set_target"]
        cam.set_target(None if t is None else (float(t[0]), float(t[1])))


def _start_resource_tracker() -> None:
    """Start multiprocessing's resource tracker (it cleans the shared memory up if the
    console dies) with the real stderr: it hands ``sys.stderr.fileno()`` to its helper,
    and inside the console Textual's stderr capture answers -1 ("bad value(s) in
    fds_to_keep": the demo failed to start from the console)."""
    if _fileno(sys.stderr) >= 0:
        resource_tracker.ensure_running()
        return
    captured, sys.stderr = sys.stderr, sys.__stderr__
    try:
        resource_tracker.ensure_running()
    finally:
        sys.stderr = captured


def _fileno(stream: Any) -> int:
    try:
        return int(stream.fileno())
    except (OSError, ValueError, AttributeError):
        return -1


class ProcessCamera:
    """Camera protocol over a twin camera rendering in a child process."""

    def __init__(self, profile: Any, demo: str = "", *, start_timeout_s: float = 60.0):
        w = int(profile.get("camera.width_px") or 640)
        h = int(profile.get("camera.height_px") or 480)
        _start_resource_tracker()
        self._shm = shared_memory.SharedMemory(create=True, size=(SLOTS + 1) * w * h)
        blob = pickle.dumps(profile)
        self._proc = subprocess.Popen(
            [sys.executable, "-m", "plugins.demos.camproc", self._shm.name, demo or ""],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
        )
        self._proc.stdin.write(b"%d\n" % len(blob) + blob)
        self._proc.stdin.flush()
        self._fd = self._proc.stdout.fileno()
        self._buf = b""
        self._closed = False
        self._dropped = 0
        self._render_dropped = 0
        self._frames = 0
        self._times: list[float] = []
        first = self._next(start_timeout_s)
        if first is None:
            self.close()
            raise UserError("twin camera process did not start; run `haptable doctor`")
        _, rows, cols, _ = first
        self._slots = np.ndarray((SLOTS + 1, rows, int(cols)), np.uint8, buffer=self._shm.buf)
        self._bg = self._slots[SLOTS].copy()

    def _next(self, timeout_s: float) -> tuple | None:
        """The next announcement, or ``None`` after ``timeout_s`` (or the child ended)."""
        while len(self._buf) < MSG.size:
            if not select.select([self._fd], [], [], timeout_s)[0]:
                return None
            chunk = os.read(self._fd, 64 * MSG.size)
            if not chunk:
                return None
            self._buf += chunk
        msg, self._buf = MSG.unpack(self._buf[: MSG.size]), self._buf[MSG.size :]
        return msg

    def read(self, timeout_s: float = 0.1) -> Frame | None:
        if self._closed:
            return None
        msg = self._next(timeout_s)
        if msg is None:
            return None
        # behind: skip to the newest announced frame (a late reader loses frames, as a
        # camera driver's queue does); the skipped ones count as camera drops
        while len(self._buf) >= MSG.size or select.select([self._fd], [], [], 0)[0]:
            nxt = self._next(0)
            if nxt is None:
                break
            msg = nxt
            self._dropped += 1
        slot, seq, t_capture, self._render_dropped = msg
        img = self._slots[slot].copy()
        self._frames += 1
        self._times = [*self._times[-60:], time.monotonic()]
        return Frame(image=img, seq=seq, t_capture_s=t_capture, source="twin-process")

    def background(self) -> np.ndarray:
        return self._bg.copy()

    def set_target(self, pos_mm: tuple[float, float] | None) -> None:
        """The operator's hand on the twin at ``pos_mm`` (table mm), or back to the script
        (``None``), as the in-process twin camera's ``set_target``."""
        if self._closed:
            return
        t = None if pos_mm is None else [float(pos_mm[0]), float(pos_mm[1])]
        try:
            self._proc.stdin.write(json.dumps({"set_target": t}).encode() + b"\n")
            self._proc.stdin.flush()
        except (BrokenPipeError, OSError):
            pass  # the child ended: status() says so

    def mm_to_px(self, pos_mm: tuple[float, float]) -> tuple[float, float] | None:
        """``None``: the table mapping lives with the twin in the child process; this
        camera's frames are drawn in the demo's own status, never with targets."""
        return None

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        try:
            self._proc.stdin.close()  # the child stops when its stdin closes
            self._proc.wait(3.0)
        except (OSError, subprocess.TimeoutExpired):
            self._proc.kill()
            self._proc.wait(3.0)
        self._proc.stdout.close()
        self._slots = None
        try:
            self._shm.close()
            self._shm.unlink()
        except (FileNotFoundError, BufferError):
            pass

    def status(self) -> dict[str, Any]:
        t = self._times
        fps = (len(t) - 1) / (t[-1] - t[0]) if len(t) > 1 and t[-1] > t[0] else 0.0
        return {
            "driver": "twin",
            "process": True,
            "fps": round(fps, 2),
            "frames": self._frames,
            "dropped": self._dropped + self._render_dropped,
            "alive": self._proc.poll() is None,
        }


if __name__ == "__main__":
    _child()
