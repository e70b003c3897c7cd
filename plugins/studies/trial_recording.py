"""A study's recording: one HDF5 file per trial in the participant's folder, written as
crash-safely as the trial log (``haptable study run ... --record`` or ``[recording]
study_trials = true``).

``DIR/<participant>/recording/trial_0003.h5`` (``format`` = ``haptable-study-trial``,
``format_version`` 1) holds the trial as the plan gave it (``trial``: its stimulus
parameters), its ``done`` record (the response, its time, replays, correct), every plan
handed to the outputs with the kernel's report clocks (``outputs``: JSON lines of
``console.plugin_api.plan_line``, through ``WatchedOutputs``), the kernel's own events in
the trial's window of gate clocks (``gate_events``: relay switches, e-stops, resets,
faults, refusals; ``console.plugin_api.GateLog``; attributes ``gate_clock_start`` and
``gate_clock_end``) and, when the trial saw the
camera (a projected study on the Studies screen, ``[recording] study_trials``: the
recorder is a frame hook of the console's camera loop), its ``frames`` (N, H, W) uint8
with ``t_capture_s``, written into the trial's ``.part`` file by a writer thread as they
come (a bounded queue: a full one drops the frame and counts it, ``frames_dropped``).
Root attributes: the experiment, participant, trial index, participant seed, the SHA-256
of ``plan.json`` and of the vibration map (``recording/map.npz``, written once,
atomically), the profile and the versions.

Why one file per trial (not one per participant with a group per trial): HDF5 cannot add
a group to a file crash-safely (a kill -9 while its metadata is written can leave the
whole file unreadable, and SWMR mode adds no group). A trial is written to
``.trial_0003.h5.part``, fsynced and renamed into place *before* its ``done`` line is
appended: a completed trial's file is whole or absent-with-the-trial-undone, a killed
trial leaves only a ``.part`` the resume overwrites, and a trial repeated on resume
replaces its file (never a second copy)."""

from __future__ import annotations

import hashlib
import json
import logging
import os
import platform
import queue
import threading
import time
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import (
    GATE_EVENT_DTYPE,
    GATE_EVENTS,
    GateLog,
    UserError,
    WatchedOutputs,
    plan_line,
    save_map,
)

from .store import RunFiles

log = logging.getLogger("haptable.studies")

FORMAT = "haptable-study-trial"
FORMAT_VERSION = 1
FOLDER = "recording"
MAP_FILE = "map.npz"


def trial_name(index: int) -> str:
    return f"trial_{int(index):04d}.h5"


def file_sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def versions() -> dict[str, str]:
    import h5py  # lazy: only when recording

    return {
        "numpy": np.__version__,
        "h5py": h5py.__version__,
        "hdf5": h5py.version.hdf5_version,
        "python": platform.python_version(),
    }


def _fsync_file(path: Path) -> None:
    with open(path, "rb+") as f:
        os.fsync(f.fileno())


def _fsync_dir(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


class TrialRecorder:
    """Records each trial of one participant's run into ``<root>/recording/``.

    ``watch(outputs)``: the outputs the player plays on (every plan noted);
    ``begin(index)`` when the trial's stimulus starts, ``frame(frame, work)`` for each
    camera frame of a projected trial, ``finish(done)`` writes the file (before the
    ``done`` line), ``discard()`` forgets an interrupted trial."""

    def __init__(
        self,
        root: Path,
        plan: dict[str, Any],
        *,
        profile: Any,
        vmap: Any = None,
        seed: int = 0,
        queue_frames: int = 240,
        plan_file: str = "plan.json",
        attrs: dict[str, Any] | None = None,
    ) -> None:
        self.folder = Path(root) / FOLDER
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise UserError(
                f"{self.folder}: cannot make the recording folder ({exc.strerror or exc}); "
                "give a writable --out"
            ) from None
        self.plan = plan
        self.profile = profile
        self.seed = int(seed)
        self.plan_sha256 = file_sha256(Path(root) / plan_file)
        self.attrs = dict(attrs or {})  # more root attributes (an adaptive run's protocol)
        self._outputs: Any = None  # whose kernel's gate events each trial keeps
        self._gate_log: GateLog | None = None
        self.map_sha256 = self._store_map(vmap) if vmap is not None else ""
        self.versions = json.dumps(versions())
        self._noted: list[tuple[str, dict, Any]] = []
        self.index: int | None = None
        self.written = 0
        self.frames_dropped = 0
        self._queue: queue.Queue = queue.Queue(maxsize=int(queue_frames))
        self._thread: threading.Thread | None = None
        self._h5: Any = None
        self._h5_index: int | None = None
        self._frames_for: int | None = None  # the trial whose frames the writer writes

    def _store_map(self, vmap: Any) -> str:
        """``map.npz`` written once (atomically); a resume must use the same map."""
        target = self.folder / MAP_FILE
        tmp = self.folder / ".map.npz.part"
        save_map(tmp, vmap)
        _fsync_file(tmp)
        new = file_sha256(tmp)
        if target.exists():
            old = file_sha256(target)
            tmp.unlink()
            if old != new:
                raise UserError(
                    f"{target}: the earlier trials were recorded with another vibration map; "
                    "resume with the same --map (or record into a new --out)"
                )
            return old
        os.replace(tmp, target)
        _fsync_dir(self.folder)
        return new

    def watch(self, outputs: Any) -> WatchedOutputs:
        self._outputs = outputs
        return WatchedOutputs(outputs, self._note)

    def noted_play(self, play: Any, outputs: Any = None) -> Any:
        """``play(plan)`` (the console session's, which gives no report) with each plan
        noted as handed to the outputs (no kernel clocks: the session keeps them); the
        gate events of ``outputs`` (the session's) are kept per trial."""
        self._outputs = outputs

        def recorded_play(plan: Any) -> Any:
            self._note("plan", {"plan": plan, "t_asked_s": time.monotonic()}, None)
            return play(plan)

        return recorded_play

    def _note(self, kind: str, rec: dict, report: Any) -> None:
        if self.index is not None:
            self._noted.append((kind, rec, report))

    def begin(self, index: int) -> None:
        self._end_frames(keep=False)
        self.index = self._frames_for = int(index)
        self._noted = []
        self._gate_log = GateLog(self._outputs) if self._outputs is not None else None

    def frame(self, frame: Any, work: dict[str, Any] | None = None) -> None:
        """A camera frame seen during the trial (a camera loop's frame hook: projected
        studies): copied into a bounded queue, written into the trial's ``.part`` file
        by the writer thread (a full queue drops the frame and counts it)."""
        index = self.index
        if index is None:
            return
        item = (index, np.array(frame.image, dtype=np.uint8, copy=True), float(frame.t_capture_s))
        if self._thread is None:
            self._thread = threading.Thread(
                target=self._write_frames, name="haptable-trial-frames", daemon=True
            )
            self._thread.start()
        try:
            self._queue.put_nowait(item)
        except queue.Full:
            self.frames_dropped += 1

    def _write_frames(self) -> None:
        while True:
            item = self._queue.get()
            if isinstance(item, threading.Event):
                item.set()  # the trial ended: every frame queued before is written
                continue
            try:
                self._write_frame(*item)
            except Exception:  # a trial never stops for its recording; the file says so
                log.exception("study recording %s: a frame was not written", self.folder)
                self.frames_dropped += 1

    def _write_frame(self, index: int, image: np.ndarray, t_s: float) -> None:
        import h5py  # lazy: only when recording

        if index != self._h5_index:
            if self._frames_for != index:
                return  # a frame of a trial discarded or already written
            self._close_part(delete=True)
            self._h5, self._h5_index = h5py.File(self._part(index), "w"), index
        f = self._h5
        if "frames" not in f:
            h, w = image.shape[:2]
            f.create_dataset(
                "frames",
                (0, h, w),
                np.uint8,
                maxshape=(None, h, w),
                chunks=(1, h, w),
                compression="gzip",
                compression_opts=1,
            )
            f.create_dataset("t_capture_s", (0,), np.float64, maxshape=(None,), chunks=(1024,))
        frames, times = f["frames"], f["t_capture_s"]
        if image.shape != frames.shape[1:]:
            self.frames_dropped += 1
            return
        n = frames.shape[0]
        frames.resize(n + 1, axis=0)
        frames[n] = image
        times.resize((n + 1,))
        times[n] = t_s

    def _part(self, index: int) -> Path:
        return self.folder / f".{trial_name(index)}.part"

    def _close_part(self, *, delete: bool) -> None:
        if self._h5 is not None:
            path = Path(self._h5.filename)
            self._h5.close()
            self._h5, self._h5_index = None, None
            if delete:
                path.unlink(missing_ok=True)

    def _end_frames(self, *, keep: bool) -> None:
        """No more frames for the trial; the writer writes those queued (``keep``) or
        skips them, then the trial's ``.part`` is closed (deleted unless ``keep``)."""
        self.index = None
        if not keep:
            self._frames_for = None
        if self._thread is not None:
            done = threading.Event()
            self._queue.put(done)
            done.wait()
        self._frames_for = None
        if not keep:
            self._close_part(delete=True)

    def discard(self) -> None:
        self._end_frames(keep=False)
        self._noted = []

    def note(self, record: dict[str, Any]) -> None:
        """A trial log line's part: ``start`` begins the trial's recording, ``done``
        writes its file (before the line is written), ``interrupted`` forgets it."""
        if "trial" not in record:
            return
        event = record.get("event")
        if event == "start":
            self.begin(record["trial"])
        elif event == "done":
            self.finish(record)
        elif event == "interrupted":
            self.discard()

    def finish(self, done: dict[str, Any]) -> Path:
        """Write the trial's file (``.part``, fsync, rename, fsync the folder)."""
        import h5py  # lazy: only when recording

        index = int(done["trial"])
        self._end_frames(keep=True)
        trial = self.trial_record(index, done)
        events, clocks = self._trial_events()
        lines = [plan_line(*x) for x in self._noted]
        target = self.folder / trial_name(index)
        part = self._part(index)
        if self._h5 is None or self._h5_index != index:
            self._close_part(delete=True)
            self._h5, self._h5_index = h5py.File(part, "w"), index
        f = self._h5
        a = f.attrs
        a["format"], a["format_version"] = FORMAT, FORMAT_VERSION
        a["created_utc"] = datetime.now(UTC).isoformat(timespec="seconds")
        a["experiment"] = str(self.plan["experiment"])
        a["participant"] = str(done.get("participant", ""))
        a["trial_index"] = index
        a["participant_seed"] = str(self.seed)
        a["plan_sha256"], a["map_sha256"] = self.plan_sha256, self.map_sha256
        a["versions"] = self.versions
        a["profile_name"] = str(getattr(self.profile, "name", ""))
        a["profile_json"] = json.dumps(getattr(self.profile, "data", {}), default=str)
        a["frames_dropped"] = int(self.frames_dropped)
        a["gate_clock_start"], a["gate_clock_end"] = clocks
        for k, v in self.attrs.items():
            a[k] = v
        f.create_dataset(GATE_EVENTS, data=events, dtype=GATE_EVENT_DTYPE)
        f.create_dataset("trial", data=json.dumps(trial, sort_keys=True))
        f.create_dataset("done", data=json.dumps(done, sort_keys=True))
        f.create_dataset("outputs", data="".join(json.dumps(x) + "\n" for x in lines))
        self._close_part(delete=False)
        _fsync_file(part)
        os.replace(part, target)
        _fsync_dir(self.folder)
        self.written += 1
        self._noted, self.frames_dropped = [], 0
        return target

    def trial_record(self, index: int, done: dict[str, Any]) -> dict[str, Any]:
        """The trial as the plan gave it (what its replay renders again)."""
        return self.plan["trials"][index]

    def _trial_events(self) -> tuple[np.ndarray, tuple[int, int]]:
        """The kernel's gate events of the trial and its window of gate clocks (-1: no
        kernel to ask)."""
        log_, self._gate_log = self._gate_log, None
        if log_ is None or not log_.live:
            return np.zeros(0, GATE_EVENT_DTYPE), (-1, -1)
        rows = log_.pull()
        end = int(rows["clock"].max()) if len(rows) else log_.since
        return rows, (log_.since, max(end, log_.clock_now()))


@dataclass
class RecordedRunFiles(RunFiles):
    """A participant's files whose trial events also drive a ``TrialRecorder``: ``start``
    begins a trial, ``done`` writes its recording first and then the line, ``interrupted``
    forgets it (the runner is unchanged: it only appends events)."""

    recorder: TrialRecorder | None = None

    def append(self, record: dict[str, Any]) -> None:
        if self.recorder is not None:
            self.recorder.note(record)
        super().append(record)


def recorded_files(files: RunFiles, recorder: TrialRecorder) -> RecordedRunFiles:
    return RecordedRunFiles(files.root, files.plan, recorder=recorder)


def wants_recording(args: Any, profile: Any) -> bool:
    """``--record`` or ``[recording] study_trials = true``."""
    return bool(getattr(args, "record", False) or profile.get("recording.study_trials"))


#: the Studies screen's "record trials" switch: its id, and its key in a run's ``spec``
RECORD = "record"


def spec_wants_recording(spec: dict[str, Any], profile: Any) -> bool:
    """Whether a Studies screen run records its trials: its switch (``spec["record"]``),
    else the profile's ``[recording] study_trials``."""
    if RECORD in spec:
        return bool(spec[RECORD])
    return bool(profile.get("recording.study_trials"))


def first_difference(
    played: list[dict[str, Any]], name: str, digest: str
) -> tuple[str | None, int]:
    """(the first recorded plan that is not ``name`` with hash ``digest``, said in one
    line, and its index) or (None, how many matched): a replay's verdict on one trial."""
    for k, x in enumerate(played):
        if (x.get("name"), x.get("hash")) != (name, digest):
            return (
                f"plan {k + 1}: recorded {x.get('name')!r} ({str(x.get('hash'))[:12]}) vs "
                f"re-rendered {name!r} ({digest[:12]})"
            ), k
    return None, len(played)
