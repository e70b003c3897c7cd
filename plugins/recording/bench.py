"""``haptable bench recording``: the recorder at the camera's 60 fps on the twin's frames.

Frames the camera twin rendered beforehand (the table with its sensor noise, which is
what limits lossless compression) are fed to a ``Recorder`` at 60 fps from one thread, as the frame
loop feeds it, for ``--minutes`` (default 1; quick: 10 s) with the profile's codec; and
for 10 s with each codec. Reported: frames fed, written and dropped, bytes per frame and
write rate, the sink call's time on the feeding thread (p50/p99: what the frame loop
pays), the writer's backlog at the end, and the machine."""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import Frame, machine_info, summarize_s
from console.plugin_api.runtime import open_camera

from .settings import CODECS
from .writer import Recorder

FPS = 60.0


def twin_frames(ctx: Any, n: int) -> list[np.ndarray]:
    """``n`` frames from the profile's camera (the twin: rendered as fast as it can)."""
    cam = open_camera(ctx.profile, ctx.pm)
    try:
        if hasattr(cam, "realtime"):
            cam.realtime = False
        out = []
        while len(out) < n:
            f = cam.read(0.5)
            if f is not None:
                out.append(np.array(f.image, copy=True))
        return out
    finally:
        cam.close()


def feed(images: list[np.ndarray], seconds: float, codec: str, profile: Any) -> dict:
    """Feed ``images`` (looped) at 60 fps for ``seconds`` into a recorder; its numbers."""
    with tempfile.TemporaryDirectory(prefix="haptable-bench-rec-") as d:
        path = Path(d) / "bench.h5"
        rec = Recorder(path, profile, codec=codec, queue_frames=240, flush_s=0.5)
        call_s: list[float] = []
        n = int(seconds * FPS)
        cpu0 = time.process_time()
        t0 = time.monotonic()
        for k in range(n):
            due = t0 + k / FPS
            wait = due - time.monotonic()
            if wait > 0:
                time.sleep(wait)
            frame = Frame(images[k % len(images)], k, due, source="bench")
            c0 = time.perf_counter()
            rec(frame, {})
            call_s.append(time.perf_counter() - c0)
        fed_s = time.monotonic() - t0
        backlog = rec.queue.qsize()
        rec.close()
        wall_s = time.monotonic() - t0
        cpu_s = time.process_time() - cpu0
        size = os.path.getsize(path)
        raw = images[0].nbytes
    return {
        "codec": codec,
        "seconds": round(fed_s, 2),
        "frames_fed": n,
        "frames_written": rec.written,
        "frames_dropped": rec.dropped,
        "writer_error": rec.error,
        "backlog_at_end_frames": backlog,
        "close_wait_s": round(wall_s - fed_s, 3),
        "bytes_per_frame": round(size / max(rec.written, 1)),
        "raw_bytes_per_frame": raw,
        "compression_ratio": round(raw * max(rec.written, 1) / size, 3) if size else None,
        "write_rate_mb_s": round(size / 1e6 / wall_s, 2),
        "process_cpu_s_per_s": round(cpu_s / wall_s, 3),
        "writer_cpu_ms_per_frame": round(1e3 * rec.writer_cpu_s / max(rec.written, 1), 2),
        "load_avg_end": [round(x, 2) for x in os.getloadavg()],
        "sink_call_ms": summarize_s(call_s),
    }


def run(ctx: Any, quick: bool, minutes: float | None = None) -> dict:
    seconds = 60.0 * minutes if minutes is not None else (10.0 if quick else 60.0)
    images = twin_frames(ctx, 30 if quick else 120)
    codec = ctx.profile.get("recording.codec") or "gzip1"
    res: dict = {
        "machine": machine_info(),
        "fps": FPS,
        "frame_shape": list(images[0].shape),
        "means": "twin frames fed at 60 fps from one thread into the recorder (as the "
        "frame loop does); dropped: the writer's queue was full",
        "load_avg_start": [round(x, 2) for x in os.getloadavg()],
        "run": feed(images, seconds, codec, ctx.profile),
    }
    res["codecs_10s"] = [feed(images, 3.0 if quick else 10.0, c, ctx.profile) for c in CODECS]
    return res
