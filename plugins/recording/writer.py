"""The recorder: a frame sink that writes a run into one HDF5 file (``format.md`` of the
package docstring) without slowing the frame loop.

The sink (``Recorder.__call__``, on the frame loop's thread) copies the frame and its
decisions into a bounded queue and returns; a full queue drops the frame and counts it
(``dropped``: in ``/stats`` and the run's status). The writer thread compresses and writes
in HDF5's SWMR mode (single writer, multiple readers: the file is consistent on disk at
every flush) and flushes every ``flush_s``: a run killed with ``kill -9`` leaves a file
that opens with every frame flushed before. ``watch_outputs`` notes every plan and relay
request the run hands its outputs, with the kernel's clocks its report got (``watch``)."""

from __future__ import annotations

import json
import logging
import os
import platform
import queue
import threading
import time
import zlib
from collections import deque
from concurrent.futures import ThreadPoolExecutor
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import GATE_EVENT_DTYPE, GATE_EVENTS, GateLog, UserError

from .decisions import dumps, frame_decisions, plan_record
from .watch import WatchedOutputs, plan_line

log = logging.getLogger("haptable.recording")

FORMAT = "haptable-recording"
FORMAT_VERSION = 1
_STOP = object()


def versions() -> dict[str, str]:
    """The versions that made the run's decisions (bit-for-bit replay needs the same)."""
    import cv2  # lazy: the vision loaded it already
    import h5py  # lazy: only when recording

    try:
        haptable = metadata.version("haptable")
    except metadata.PackageNotFoundError:
        haptable = "unknown"
    return {
        "haptable": haptable,
        "numpy": np.__version__,
        "opencv": cv2.__version__,
        "h5py": h5py.__version__,
        "hdf5": h5py.version.hdf5_version,
        "python": platform.python_version(),
    }


def check_target(path: Path) -> Path:
    """``path`` as a recording target, or one ``UserError`` line with the fix."""
    path = Path(path).expanduser().resolve()
    if path.is_dir():
        raise UserError(f"recording {path}: is a folder; give a file name such as run.h5")
    if not path.parent.is_dir():
        raise UserError(
            f"recording {path}: folder {path.parent} does not exist; create it or give "
            "another path (--record or [recording] path)"
        )
    where = path if path.exists() else path.parent
    if not os.access(where, os.W_OK):
        raise UserError(
            f"recording {path}: cannot write there (no permission); give a writable path "
            "(--record or [recording] path)"
        )
    return path


class Recorder:
    """A frame sink writing frames and decisions to ``path`` (see the module)."""

    def __init__(
        self,
        path: Path,
        profile: Any,
        *,
        codec: str = "gzip1",
        queue_frames: int = 240,
        flush_s: float = 0.5,
    ) -> None:
        self.path = check_target(path)
        self.profile = profile
        self.codec = codec
        self.flush_s = float(flush_s)
        self.queue: queue.Queue = queue.Queue(maxsize=int(queue_frames))
        self.dropped = 0
        self.written = 0
        self.error = ""
        self.writer_cpu_s = 0.0  # the writer thread's CPU time, once closed
        self.attrs: dict[str, Any] = {}
        self.background: np.ndarray | None = None
        self.scene: Any = None
        self._last_scene: Any = None
        self._lock = threading.Lock()
        self._outputs_seen: list[tuple[str, dict, Any]] = []
        self._dropped_seq: list[int] = []  # frames the full queue dropped, not yet written
        self._gate_log: GateLog | None = None  # the kernel's own events (``watch_outputs``)
        self._closed = False
        self._thread = threading.Thread(target=self._run, name="haptable-recorder", daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ frame loop side
    def begin(self, *, demo: str = "", classifier: Any = None, scene: Any = None) -> None:
        """What the run starts from, before its first frame: the demo's name, the
        classifier's tunables and learned background, the scene (its state per frame)."""
        self.attrs["demo"] = demo
        if classifier is not None:
            self.attrs["tunables"] = json.dumps(
                {k: float(v) for k, v in classifier.tunables().items()}
            )
            bg = getattr(getattr(classifier, "background", None), "image", None)
            self.background = None if bg is None else np.array(bg, copy=True)
        self.scene = scene

    def __call__(self, frame: Any, work: dict) -> None:
        if self._closed:
            return
        dec = frame_decisions(work, plan_object=True)
        dec["stamps_s"] = dict(frame.stamps_s)
        if self.scene is not None:
            dec["scene"] = self.scene.state()
        item = (np.array(frame.image, copy=True), int(frame.seq), float(frame.t_capture_s), dec)
        try:
            self.queue.put_nowait(item)
        except queue.Full:
            self.dropped += 1
            with self._lock:
                self._dropped_seq.append(item[1])

    def watch_outputs(self, outputs: Any) -> WatchedOutputs:
        """``outputs`` noting every plan and relay request the run makes (``watch``);
        the kernel's own gate events from now on are pulled into ``gate_events``."""
        self._gate_log = GateLog(outputs)
        return WatchedOutputs(outputs, self._note_output)

    def _note_output(self, kind: str, rec: dict, report: Any) -> None:
        with self._lock:
            self._outputs_seen.append((kind, rec, report))

    def _output_lines(self, final: bool) -> bytes:
        """The noted outputs whose report is done (all of them when ``final``) as JSON
        lines, in the order they were asked for."""
        with self._lock:
            ready, waiting = [], []
            for x in self._outputs_seen:
                done = final or x[2] is None or x[2].done.is_set()
                (ready if done else waiting).append(x)
            self._outputs_seen = waiting
        return b"".join(dumps(plan_line(*x)) + b"\n" for x in ready)

    def status(self) -> dict:
        return {
            "path": str(self.path),
            "written": self.written,
            "dropped": self.dropped,
            "waiting": self.queue.qsize(),
            "error": self.error,
        }

    def close(self) -> None:
        """Write what waits, then close the file (safe twice)."""
        if self._closed:
            return
        self._closed = True
        self.queue.put(_STOP)
        self._thread.join()
        if self.dropped:
            why = f"the writer failed: {self.error}" if self.error else "the writer fell behind"
            log.warning("recording %s: %d frames dropped (%s)", self.path, self.dropped, why)

    # ------------------------------------------------------------------ writer thread
    def _run(self) -> None:
        f = None
        # gzip1: frames are deflated on two threads (zlib lets go of the GIL), written in order
        pool = ThreadPoolExecutor(2, "haptable-recorder-zlib") if self.codec == "gzip1" else None
        pending: deque = deque()
        try:
            last_flush = time.monotonic()
            while True:
                item = self.queue.get()
                if item is _STOP:
                    break
                if f is None:
                    f, ds = self._open(item[0].shape)
                packed = pool.submit(_deflate, item[0]) if pool is not None else None
                pending.append((item, packed))
                while pending and (
                    len(pending) > 2 or pending[0][1] is None or pending[0][1].done()
                ):
                    self._write(ds, *pending.popleft())
                now = time.monotonic()
                if now - last_flush >= self.flush_s:
                    self._flush(f, ds)
                    last_flush = now
            while pending:
                self._write(ds, *pending.popleft())
        except Exception as exc:  # the run goes on; the status and the log say so
            self.error = f"{type(exc).__name__}: {exc}"
            log.exception("recording %s failed", self.path)
            while True:  # keep the sink from blocking: count what cannot be written
                item = self.queue.get()
                if item is _STOP:
                    break
                self.dropped += 1
        finally:
            if pool is not None:
                pool.shutdown(wait=True, cancel_futures=True)
            if f is not None:
                try:
                    self._flush(f, ds, final=True)
                    f.close()
                except Exception:
                    log.exception("recording %s: close failed", self.path)
            self.writer_cpu_s = time.thread_time()

    def _flush(self, f: Any, ds: dict, final: bool = False) -> None:
        """Plans done, the kernel's new gate events, the frames dropped so far, the
        counts; then everything to disk."""
        _append(ds["plans"], self._output_lines(final=final))
        if self._gate_log is not None:
            rows = self._gate_log.pull()
            if len(rows):
                n = ds["gate_events"].shape[0]
                ds["gate_events"].resize((n + len(rows),))
                ds["gate_events"][n:] = rows
        with self._lock:
            lost, self._dropped_seq = self._dropped_seq, []
        if lost:
            n = ds["dropped_seq"].shape[0]
            ds["dropped_seq"].resize((n + len(lost),))
            ds["dropped_seq"][n:] = lost
        ds["stats"][:] = (self.written, self.dropped)
        f.flush()

    def _open(self, shape: tuple[int, ...]):
        import h5py  # lazy: only when recording

        f = h5py.File(self.path, "w", libver="latest")
        f.attrs["format"] = FORMAT
        f.attrs["format_version"] = FORMAT_VERSION
        f.attrs["created_utc"] = datetime.now(UTC).isoformat(timespec="seconds")
        f.attrs["versions"] = json.dumps(versions())
        f.attrs["profile_name"] = str(getattr(self.profile, "name", ""))
        f.attrs["profile_json"] = json.dumps(getattr(self.profile, "data", {}), default=str)
        try:
            f.attrs["profile_toml"] = Path(self.profile.path).read_text(encoding="utf-8")
        except (OSError, AttributeError, TypeError):
            f.attrs["profile_toml"] = ""
        f.attrs["codec"] = self.codec
        for k, v in self.attrs.items():
            f.attrs[k] = v
        h, w = shape
        comp = (
            {"compression": "lzf"}
            if self.codec == "lzf"
            else {"compression": "gzip", "compression_opts": 1}
        )
        ds = {
            "frames": f.create_dataset(
                "frames", (0, h, w), np.uint8, maxshape=(None, h, w), chunks=(1, h, w), **comp
            ),
            "seq": f.create_dataset("seq", (0,), np.int64, maxshape=(None,), chunks=(1024,)),
            "t_capture_s": f.create_dataset(
                "t_capture_s", (0,), np.float64, maxshape=(None,), chunks=(1024,)
            ),
            "decisions": f.create_dataset(
                "decisions", (0,), np.uint8, maxshape=(None,), chunks=(1 << 16,)
            ),
            "index": f.create_dataset(
                "decisions_index", (0, 2), np.int64, maxshape=(None, 2), chunks=(1024, 2)
            ),
            "plans": f.create_dataset("plans", (0,), np.uint8, maxshape=(None,), chunks=(4096,)),
            "stats": f.create_dataset("stats", data=np.zeros(2, np.int64)),
            "gate_events": f.create_dataset(
                GATE_EVENTS, (0,), GATE_EVENT_DTYPE, maxshape=(None,), chunks=(256,)
            ),
            "dropped_seq": f.create_dataset(
                "dropped_seq", (0,), np.int64, maxshape=(None,), chunks=(1024,)
            ),
        }
        bg = self.background
        f.create_dataset("background", data=bg if bg is not None else np.zeros((0, 0), np.float32))
        f.swmr_mode = True  # from here on the file is consistent on disk at each flush
        return f, ds

    def _write(self, ds: dict, item: tuple, packed: Any = None) -> None:
        image, seq, t_s, dec = item
        n = self.written
        ds["frames"].resize(n + 1, axis=0)
        if packed is not None:  # deflated outside HDF5: HDF5's deflate filter reads it
            ds["frames"].id.write_direct_chunk((n, 0, 0), packed.result())
        else:
            ds["frames"][n] = image
        for key, value in (("seq", seq), ("t_capture_s", t_s)):
            ds[key].resize((n + 1,))
            ds[key][n] = value
        if dec.get("plan") is not None:  # hashed here, off the frame loop
            dec["plan"] = plan_record(dec["plan"])
        if "scene" in dec:  # kept when it changed (``Recording.scene(k)`` looks back)
            if dec["scene"] == self._last_scene:
                del dec["scene"]
            else:
                self._last_scene = dec["scene"]
        start = ds["decisions"].shape[0]
        blob = dumps(dec)
        _append(ds["decisions"], blob)
        ds["index"].resize(n + 1, axis=0)
        ds["index"][n] = (start, len(blob))  # last: a frame counts once this is written
        self.written = n + 1


def _deflate(image: np.ndarray) -> bytes:
    """A frame as HDF5's deflate filter stores a chunk (zlib, level 1)."""
    return zlib.compress(image.tobytes(), 1)


def _append(dset: Any, blob: bytes) -> None:
    if not blob:
        return
    start = dset.shape[0]
    dset.resize((start + len(blob),))
    dset[start:] = np.frombuffer(blob, np.uint8)
