"""The twin camera in its own process, as a camera device is (``TwinCamera.apart()``).

A real camera exposes and transfers frames without costing the console's interpreter
anything; the twin camera renders its frames in Python, and in the console's process that
rendering competes for the GIL with the vision, the UI, the knob and the audio driver
thread. ``ProcessCamera`` runs a ``TwinCamera`` (its rig, script and state pickled: a
demo's scripted hand, the console's demo loop) in a child process: frames land in a ring
of shared-memory slots and a pipe announces each one (slot, seq, capture time on the
system-wide monotonic clock, frames the renderer dropped). ``read`` copies the newest
announced frame out; it waits on the pipe without holding the GIL.

The parent keeps a copy of the twin for what needs no stream: the table mapping
(``mapping``, ``mm_to_px``), offline renders (``render_sample``, ``render_background``).
What changes the stream (``set_script``, ``set_target(s)``, ``set_rate``, ``place``) is
sent to the child, which applies it from its next frame. The child ends when its stdin
closes: ``close()``, or the parent's end however it comes (no orphan is left).
"""

from __future__ import annotations

import contextlib
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

from console.plugin_api import Frame, GestureScript, UserError

#: Shared-memory frame slots (the reader copies a frame out before it is reused).
SLOTS = 8
#: Announced frames a late reader still gets, oldest first (fewer than SLOTS: a frame's
#: slot is not reused before it is read); beyond them the oldest are skipped.
READ_BACKLOG = 3
#: One announcement: slot, frame seq, capture time (monotonic s), frames the renderer lost.
MSG = struct.Struct("<iqdq")
#: The renderer's nice value when it paces itself in real time: above the console, the
#: projector and the tests (nice 0) but not real-time, so a busy machine cannot be starved
#: by it; the frame loop and the outputs kernel stay above it (FIFO).
RENDER_NICE = -5
#: OpenCV's worker threads in the renderer: one. A frame's warps and blurs are too small
#: to gain from a second core, and waking (and spinning) the pool every frame cost a
#: quarter of the renderer's CPU on a 2-core machine the demo, kernel and console share.
RENDER_CV_THREADS = 1
#: One command's length (a pickled ``(method name, args)`` follows).
CMD = struct.Struct("<I")
#: The commands the child applies to its twin (its methods of those names).
COMMANDS = ("set_script", "set_target", "set_targets", "set_rate", "place", "set_control")


def _commands(buf: bytearray) -> list[bytes]:
    """The complete commands at the head of ``buf`` (taken out of it)."""
    out = []
    while len(buf) >= CMD.size:
        n = CMD.unpack_from(buf)[0]
        if len(buf) < CMD.size + n:
            break
        out.append(bytes(buf[CMD.size : CMD.size + n]))
        del buf[: CMD.size + n]
    return out


def _child() -> None:
    """``python -m plugins.twin.camera.process SHM``, the pickled twin on stdin."""
    shm_name = sys.argv[1]
    out = sys.stdout.buffer
    # commands are read from the descriptor itself: a buffered reader could keep a second
    # command that came with the first where ``select`` cannot see it (the calibration's
    # "lift" and "touch the next target" arrive together: the finger would never move)
    fd = sys.stdin.fileno()
    buf = bytearray()
    pending: list[bytes] = []
    while not pending:
        chunk = os.read(fd, 1 << 20)
        if not chunk:
            return
        buf += chunk
        pending = _commands(buf)
    cam = pickle.loads(pending.pop(0))
    import cv2  # lazy: the renderer's (the twin loaded it); its pool, in this process only

    cv2.setNumThreads(RENDER_CV_THREADS)
    if cam.realtime:  # it stands for a camera, whose frames do not wait for the CPU
        with contextlib.suppress(OSError):  # (where raising the priority is allowed)
            os.setpriority(os.PRIO_PROCESS, 0, RENDER_NICE)
    shm = shared_memory.SharedMemory(name=shm_name)
    resource_tracker.unregister(shm._name, "shared_memory")  # the parent owns it
    slots = None
    try:
        bg = cam.background()
        slots = np.ndarray((SLOTS + 1, *bg.shape), np.uint8, buffer=shm.buf)
        slots[SLOTS] = bg
        out.write(MSG.pack(-1, bg.shape[0], float(bg.shape[1]), 0))
        out.flush()
        k = 0
        for blob in pending:  # commands that came with the twin
            _command(cam, blob)
        while True:
            # paused (``set_rate(0)``: nobody reads): wait for the next command, render nothing
            if select.select([fd], [], [], None if cam.paused else 0)[0]:
                chunk = os.read(fd, 1 << 20)
                if not chunk:  # stdin closed: the parent closed us, or ended
                    break
                buf += chunk
            for blob in _commands(buf):  # every command that came, before the next frame
                _command(cam, blob)
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


def _command(cam: Any, blob: bytes) -> None:
    """One command from the parent: ``(method, args)``, a method of ``COMMANDS``."""
    name, args = pickle.loads(blob)
    if name in COMMANDS:
        getattr(cam, name)(*args)


def _start_resource_tracker() -> None:
    """Start multiprocessing's resource tracker (it cleans the shared memory up if the
    parent dies) with the real stderr: it hands ``sys.stderr.fileno()`` to its helper,
    and inside the console Textual's stderr capture answers -1 ("bad value(s) in
    fds_to_keep": the camera failed to start from the console)."""
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
    """Camera protocol over a ``TwinCamera`` rendering in a child process (the twin's
    ``apart()``); ``twin`` is the parent's copy (mapping, offline renders)."""

    def __init__(self, twin: Any, *, start_timeout_s: float = 60.0) -> None:
        self.twin = twin
        w, h = twin.rig.mapping.image_px
        _start_resource_tracker()
        self._shm = shared_memory.SharedMemory(create=True, size=(SLOTS + 1) * int(w) * int(h))
        blob = pickle.dumps(twin)
        self._proc = subprocess.Popen(
            [sys.executable, "-m", __name__, self._shm.name],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
        )
        self._proc.stdin.write(CMD.pack(len(blob)) + blob)
        self._proc.stdin.flush()
        self._fd = self._proc.stdout.fileno()
        self._buf = b""
        self._closed = False
        self._dropped = 0
        self._unread = 0  # announced before the first read or during a pause: not drops
        self._render_dropped = 0
        self._frames = 0
        self._rate: float | None = twin.rate_fps
        # frames announced before the first read are nobody's drops: a camera delivers
        # nothing before its stream is read (a demo prepares for seconds meanwhile)
        self._stale = True
        self._times: list[float] = []
        try:
            first = self._next(start_timeout_s)
        except BaseException:  # interrupted while it starts (a demo's start cancelled)
            self._proc.kill()  # it has shown nothing: no orphan left loading
            self.close()
            raise
        if first is None:
            self.close()
            raise UserError("twin camera process did not start; run `haptable doctor`")
        _, rows, cols, _ = first
        self._slots = np.ndarray((SLOTS + 1, rows, int(cols)), np.uint8, buffer=self._shm.buf)
        self._bg = self._slots[SLOTS].copy()

    @property
    def pid(self) -> int:
        """The camera process's id."""
        return self._proc.pid

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
        if self._stale:  # announced before the first read or a pause: unread, not drops
            self._stale = False
            while self._next(0) is not None:
                self._unread += 1
        msg = self._next(timeout_s)
        if msg is None:
            return None
        # behind: the frames announced meanwhile wait in order, as in a camera driver's
        # buffer queue; past READ_BACKLOG the oldest are skipped (camera drops)
        while select.select([self._fd], [], [], 0)[0]:
            chunk = os.read(self._fd, 64 * MSG.size)
            if not chunk:
                break
            self._buf += chunk
        while len(self._buf) // MSG.size >= READ_BACKLOG:
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
        """The empty table the child rendered when it started."""
        return self._bg.copy()

    # ------------------------------------------------------------------ to the child
    def _send(self, name: str, *args: Any) -> None:
        if self._closed:
            return
        blob = pickle.dumps((name, args))
        try:
            self._proc.stdin.write(CMD.pack(len(blob)) + blob)
            self._proc.stdin.flush()
        except (BrokenPipeError, OSError, ValueError):
            pass  # the child ended: status() says so

    def set_target(self, pos_mm: tuple[float, float] | None, *args: Any) -> None:
        """The operator's hand on the twin at ``pos_mm`` (table mm), or off the table
        (``None``), as ``TwinCamera.set_target``."""
        t = None if pos_mm is None else (float(pos_mm[0]), float(pos_mm[1]))
        self._send("set_target", t, *args)

    def set_targets(self, points_mm: list, *args: Any) -> None:
        self._send("set_targets", [tuple(map(float, p)) for p in points_mm], *args)

    def set_script(self, script: Any) -> None:
        """Show ``script`` (a ``GestureScript`` or one of the twin's scripts) from the
        child's next frame on."""
        if isinstance(script, GestureScript):
            script = self.twin.sequence(script)
        self._send("set_script", script)

    def place(
        self,
        gesture: str,
        center_mm: tuple[float, float],
        angle_deg: float = 90.0,
        subject: str = "s1",
        side: str = "right",
    ) -> None:
        """Hold a static gesture at ``center_mm`` (``TwinCamera.place``)."""
        self._send("place", gesture, tuple(map(float, center_mm)), angle_deg, subject, side)

    def set_rate(self, fps: float | None) -> None:
        """Frames at most ``fps`` a second (``None``: the camera's own rate; ``0``: none,
        the child waits without rendering); the script's time runs on at the camera's
        fps (``TwinCamera.set_rate``)."""
        was = self._rate
        self._rate = None if fps is None else float(fps)
        if was == 0.0 and self._rate != 0.0:
            self._stale = True  # the reader's next read skips what came before the pause
        self._send("set_rate", self._rate)

    # ------------------------------------------------------------------ AdjustableCamera
    def controls(self) -> dict[str, Any]:
        """The twin's exposure and gain (``TwinCamera.controls``)."""
        return self.twin.controls()

    def control_values(self) -> dict[str, float]:
        return self.twin.control_values()

    def control_keys(self) -> dict[str, str]:
        return self.twin.control_keys()

    def set_control(self, name: str, value: float) -> None:
        """Exposure or gain from the child's next frame on (the parent's copy says it)."""
        self.twin.set_control(name, value)
        self._send("set_control", name, getattr(self.twin, name))

    # ------------------------------------------------------------------ in the parent
    @property
    def mapping(self) -> Any:
        return self.twin.mapping

    def mm_to_px(self, pos_mm: tuple[float, float]) -> tuple[float, float] | None:
        """Where the table point ``pos_mm`` shows in the image (the parent's mapping)."""
        return self.twin.mm_to_px(pos_mm)

    def render_sample(self, *args: Any, **kw: Any) -> tuple[np.ndarray, dict[str, Any]]:
        """One performance rendered offline, in this process (``TwinCamera.render_sample``)."""
        return self.twin.render_sample(*args, **kw)

    def render_background(self, t_s: float, rng: np.random.Generator) -> np.ndarray:
        return self.twin.render_background(t_s, rng)

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
            "pid": self._proc.pid,
            "fps": round(fps, 2),
            "nominal_fps": self.twin.fps,
            "rate_fps": self._rate,
            "frames": self._frames,
            "dropped": self._dropped + self._render_dropped,
            # which side was late: the reader (the frame loop) or the renderer (the twin
            # standing in for the camera's own hardware)
            "dropped_reading": self._dropped,
            "dropped_rendering": self._render_dropped,
            "unread": self._unread,  # before the first read, or while paused
            "alive": self._proc.poll() is None,
            "closed": self._closed,
            **self.twin.control_values(),
        }


if __name__ == "__main__":
    _child()
