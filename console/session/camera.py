"""The console's camera: the profile's camera and classifier in a frame loop (the
runtime's ``FrameLoop`` with the ``vision`` and ``classify`` stages), keeping the newest
frame and result for the Camera view and a latency monitor for the Latency screen.

Screens that show it say so with ``watch(viewer, True)`` (the Camera and Latency screens
when shown) and ``watch(viewer, False)`` when hidden: the loop runs while someone watches
and stops when nobody does. A viewer that shows frames only so often says so
(``watch(viewer, True, fps=15)``, the Camera screen): while every viewer asks for a rate
and nothing else takes the frames (no frame hook: a calibration, a study, TUIO), a camera
that can be paced (``PacedCamera``: the twin) delivers frames at that rate, and the
vision runs on those only. A camera that renders in Python runs apart (``RunsApart``: the
twin in its own process, as a camera device, ``[runtime] twin_camera_process``). A demo
started from the console runs in its own process and opens the camera there: the service
closes it meanwhile (``release``/``give_back``). The camera opens first and its frames
show (``to_show``) while the classifier is built (``camera_start``; ``starting`` says
what is prepared); ``snapshot`` gives processed frames only.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

import numpy as np

from console.core.contracts import (
    AdjustableCamera,
    OrderedTunables,
    ReportsProblem,
    SwitchableSink,
    TunablesInProfile,
)
from console.core.errors import UserError
from console.core.schema import host_problem
from console.core.types import TunableRange
from console.core.words import AT_CONSOLE, worded
from console.runtime.latency import LatencyMonitor
from console.runtime.loop import FrameLoop
from console.runtime.stages import (
    base_stages,
    learn_background,
    open_camera,
    open_classifier,
)
from console.session.background_check import InView, in_view
from console.session.camera_start import LOADING_VISION, OPENING_CAMERA, Starting, preview_loop
from console.session.demo_history import RunHistory
from console.session.events import SessionEvent, Started, Stopped


@runtime_checkable
class RunsApart(Protocol):
    """A camera that can stream from its own process (the twin renders its frames in
    Python): ``apart()`` returns that camera (closing it ends the process)."""

    def apart(self) -> Any: ...


@runtime_checkable
class PacedCamera(Protocol):
    """A camera that delivers frames at most ``fps`` a second when asked (``None``: at
    its own rate; ``0``: none, while nobody reads), rendering or transferring no more."""

    def set_rate(self, fps: float | None) -> None: ...


#: seconds between two readings of the loop's p50s kept for the Latency screen
HISTORY_TICK_S = 0.5
#: how long the vision's build waits for the first frame to be taken by a screen
FIRST_FRAME_WAIT_S = 2.0
#: after an exposure or gain change, frames taken this soon are not kept for ``b`` (a
#: camera applies a new exposure a frame or two later)
CONTROL_SETTLE_S = 0.05


class _Hooks(list):
    """``frame_hooks``: a list that tells the service when hooks come and go (a hook
    takes every frame: the camera's full rate)."""

    def __init__(self, changed: Callable[[], None]) -> None:
        super().__init__()
        self._changed = changed

    def append(self, hook) -> None:
        super().append(hook)
        self._changed()

    def remove(self, hook) -> None:
        super().remove(hook)
        self._changed()

    def clear(self) -> None:
        super().clear()
        self._changed()


class _Closing(Exception):
    """``CameraService.close()`` was asked while the camera opened."""


class CameraService:
    """``emit(event)`` reports the loop's start and stop (topic ``camera``)."""

    def __init__(
        self, profile, plugins, emit: Callable[[SessionEvent], None] | None = None
    ) -> None:
        self.profile = profile
        self.plugins = plugins
        self.emit = emit or (lambda event: None)
        self.camera = None
        self.classifier = None
        self.loop = None
        self.error = ""
        #: switchable sink name -> why it could not be opened (``sink_problem``)
        self.sink_errors: dict[str, str] = {}
        #: why the classifier names no gesture though a model is set ("": none)
        self.classifier_problem = ""
        self._lock = threading.Lock()
        self._start_lock = threading.Lock()  # two screens may start it at once
        self.latest: tuple[Any, dict] | None = None
        self.recent: deque[np.ndarray] = deque(maxlen=15)
        #: the vision's (hands, contacts) in each of ``recent`` (None: not processed)
        self.recent_seen: deque[tuple[int, int] | None] = deque(maxlen=15)
        #: the settings as the profile has them (as the vision started, or as last kept
        #: by ``save_tuning``): what ``reset_params`` puts back
        self.profile_params: dict[str, float] = {}
        #: frames taken before this (monotonic s, the camera's clock) are not ``recent``:
        #: the exposure or gain changed, and a background is learned under one setting
        self._recent_from_s = 0.0
        # fn(frame, work) called from the processing thread (each takes every frame)
        self.frame_hooks: list = _Hooks(self._pace)
        self.borrower: str | None = None  # the demo running on this camera, if any
        self._viewers: dict[int, float | None] = {}  # id() of whoever watches -> its fps
        self.rate_fps: float | None = None  # the rate asked of the camera (None: its own)
        self._sinks: dict[str, Any] = {}  # the switchable frame sinks on, by name
        self.starting = Starting()  # what the start prepares now (the Camera screen says)
        self._taken = threading.Event()  # a frame of this start was read (``to_show``)
        self._closed = threading.Event()  # ``close()`` asked: a start under way gives up
        self._preview: tuple[Any, dict] | None = None  # a frame while the vision loads
        #: the last loop's ``status()`` as it stopped, and when (``time.time()``): the
        #: Latency screen shows it while no loop runs
        self.last_run: tuple[float, dict] | None = None
        self._loop_started_s = 0.0  # when the running loop started (``time.time()``)
        #: the loop's p50 per stage every ``HISTORY_TICK_S``, whether or not the Latency
        #: screen shows; kept when the loop stops (its sparklines, said to be old)
        self.history = RunHistory()
        self._history_at = 0.0  # when the last reading was kept (monotonic)

    @property
    def running(self) -> bool:
        return self.loop is not None and self.loop.running

    def watch(self, viewer: object, on: bool, fps: float | None = None) -> None:
        """``viewer`` shows the camera (``on``) or no longer does; ``fps``: it shows at
        most that many frames a second (``None``: it wants every frame). The loop starts
        with the first viewer and stops when the last one leaves. Blocking (opening the
        camera, or joining its loop): call in a worker. A failure to open is kept in
        ``error``."""
        with self._lock:
            if on:
                self._viewers[id(viewer)] = None if fps is None else float(fps)
            else:
                self._viewers.pop(id(viewer), None)
            watched = bool(self._viewers)
        if not watched:
            self.stop("nobody watches")
            self._pace()  # an open camera renders nothing meanwhile
            return
        self._pace()
        if on:
            try:
                with self._start_lock:
                    if not self.watched:  # the last viewer left meanwhile
                        return
                    self._start_locked()
            except UserError as exc:
                self.error = str(exc)

    def leave(self, viewer: object) -> None:
        """``viewer`` no longer shows the camera; returns at once (call from the UI
        thread). The loop stops in a thread of its own, after a start in progress ends,
        unless a viewer came back meanwhile."""
        with self._lock:
            self._viewers.pop(id(viewer), None)
            shows = any(r is not None for r in self._viewers.values())
            watched = bool(self._viewers)
        if not shows:
            self._taken.set()  # a start waiting for a screen to take its first frame
        if not watched:
            threading.Thread(target=self._stop_unwatched, name="camera-leave", daemon=True).start()

    def _stop_unwatched(self) -> None:
        with self._start_lock:
            if self.watched:  # a viewer came back while the start ended
                return
            stopped = self._stop_locked()
        if stopped:
            self.emit(Stopped("camera", reason="nobody watches"))
        self._pace()

    def _stop_locked(self) -> bool:
        """Stop the loop (call with ``_start_lock`` held); whether one ran."""
        self._keep_last_run()
        loop, self.loop = self.loop, None
        if loop is not None:
            loop.stop()
        return loop is not None

    def _keep_last_run(self) -> None:
        """``last_run``: the running loop's numbers, before it stops."""
        if self.loop is not None:
            now, st = time.time(), self.status()
            st["ran_s"] = now - self._loop_started_s  # its counts over its whole run
            self.last_run = (now, st)
            self.history.end()

    def wanted_rate(self) -> float | None:
        """The frames a second the camera must deliver: none (0) while the loop is
        stopped and nobody watches; the fastest viewer's rate when every viewer named one
        and no frame hook takes frames; else ``None`` (all: a loop started without a
        viewer, ``start()``, too)."""
        with self._lock:
            rates = list(self._viewers.values())
        if not rates:
            return None if self.running else 0.0
        if self.frame_hooks or any(r is None for r in rates):
            return None
        return max(rates)

    def _pace(self) -> None:
        """Ask the camera for ``wanted_rate()`` (a ``PacedCamera``; others deliver all)."""
        rate = self.wanted_rate()
        cam = self.camera
        if isinstance(cam, PacedCamera):
            cam.set_rate(rate)
            self.rate_fps = rate

    @property
    def watched(self) -> bool:
        with self._lock:
            return bool(self._viewers)

    def start(self) -> None:
        """Open the camera and classifier and start the loop (blocking: call in a worker)."""
        with self._start_lock:
            self._start_locked()

    def _start_locked(self) -> None:
        if self.running or self.borrower is not None or self._closed.is_set():
            return
        try:
            self._open(open_camera, open_classifier, learn_background)
        except _Closing:  # the console quit while the camera opened: nothing to start
            return
        finally:
            self.starting.set("")
        for key, value in self.params().items():  # the first values seen: the profile's
            self.profile_params.setdefault(key, value)
        stages = base_stages(self.classifier)
        window = int(self.profile.get("runtime.latency_window_frames", 1200) or 1200)
        mon = LatencyMonitor([n for n, _ in stages], size=window)
        self.loop = FrameLoop(self.camera, stages, monitor=mon, queue_size=2, sinks=[self._sink])
        self._open_sinks()
        self.history.begin("camera")
        self.loop.start()
        self._loop_started_s = time.time()
        self._pace()
        self.emit(Started("camera"))

    def _open(self, open_camera, open_classifier, learn_background) -> None:
        """The camera first, its frames shown (``to_show``, ``camera_start``) while the
        classifier is built: the first frame does not wait for the vision's libraries."""
        if self.camera is not None:
            return
        self.starting.set(OPENING_CAMERA)
        with self._lock:  # a closed camera's last frame is not this one's
            self.latest = self._preview = None
            self._taken.clear()
        camera = open_camera(self.profile, self.plugins)
        if isinstance(camera, RunsApart) and self._apart():
            camera = camera.apart()
        preview = None
        try:
            self._give_up_if_closed()
            if self.classifier is None:  # kept across a demo: its tuned thresholds
                self.camera = camera  # its controls and status while the vision loads
                self._pace()
                preview = preview_loop(camera, self._preview_sink)
                # the vision's libraries hold the interpreter while they load: the first
                # frame is taken by the screen (``to_show``) before they start
                with self._lock:  # a viewer that shows frames (it names its rate)
                    shows = any(r is not None for r in self._viewers.values())
                if shows:
                    self._taken.wait(FIRST_FRAME_WAIT_S)
                self._give_up_if_closed()
                self.starting.set(LOADING_VISION)
                self.classifier = open_classifier(self.profile, self.plugins)
                problem = (
                    self.classifier.problem if isinstance(self.classifier, ReportsProblem) else None
                )
                self.classifier_problem = "" if problem is None else worded(problem, AT_CONSOLE)
            self._give_up_if_closed()
            learn_background(camera, self.classifier)
        except BaseException:
            self.camera = None
            camera.close()
            raise
        finally:
            if preview is not None:
                preview.stop()
        self.camera = camera

    def _preview_sink(self, frame, work: dict) -> None:
        """A frame while the vision is prepared: shown, passed to no frame hook."""
        with self._lock:
            self._preview = (frame, work)
            self._keep_recent(frame, None)

    def _apart(self) -> bool:
        """``[runtime] twin_camera_process`` (on when the profile does not say)."""
        try:
            value = self.profile.get("runtime.twin_camera_process")
        except Exception:  # a profile without the section (its plugin not loaded)
            value = None
        return True if value is None else bool(value)

    def release(self, borrower: str) -> None:
        """Stop this service's loop and close the camera for ``borrower`` (a demo process
        opens it: a camera device opens once). Until ``give_back`` the service does not
        start again. Blocking: call in a worker."""
        with self._start_lock:
            if self.borrower is not None:
                raise RuntimeError(f"the camera is already in use by {self.borrower}")
            self._keep_last_run()
            if self.loop is not None:
                self.loop.stop()
                self.loop = None
            if self.camera is not None:
                self.camera.close()
                self.camera = None
            self.latest = self._preview = None
            self.borrower = borrower
        self.emit(Stopped("camera", reason=f"in use by {borrower}"))

    def give_back(self) -> None:
        """The borrower has closed the camera: the service may open it again."""
        with self._start_lock:
            self.borrower = None

    def _sink(self, frame, work: dict) -> None:
        with self._lock:
            self.latest = (frame, work)
            self._keep_recent(frame, work)
        now, loop = time.monotonic(), self.loop
        if loop is not None and now - self._history_at >= HISTORY_TICK_S:
            self._history_at = now
            self.history.add({"latency": loop.monitor.snapshot()})
        for hook in list(self.frame_hooks):
            hook(frame, work)

    def _keep_recent(self, frame, work: dict | None) -> None:
        """Add ``frame`` to ``recent`` (and the hands and contacts of its ``work`` to
        ``recent_seen``) unless it was taken before the controls changed (call with
        ``_lock`` held)."""
        if frame.t_capture_s >= self._recent_from_s:
            self.recent.append(frame.image)
            seen = None if work is None else (work.get("hands"), work.get("contacts"))
            self.recent_seen.append(None if seen is None else tuple(len(x or ()) for x in seen))

    def snapshot(self) -> tuple[Any, dict] | None:
        """The newest processed frame and its ``work`` (None before the vision runs)."""
        with self._lock:
            return self.latest

    def to_show(self) -> tuple[Any, dict] | None:
        """The newest frame to show: processed (``snapshot``), else one the camera
        delivered while the vision is prepared (its ``work`` empty)."""
        with self._lock:
            if self.latest is None and self._preview is not None:
                self._taken.set()
            return self.latest if self.latest is not None else self._preview

    def stop(self, reason: str = "stopped") -> None:
        with self._start_lock:
            stopped = self._stop_locked()
        if stopped:
            self.emit(Stopped("camera", reason=reason))

    def _give_up_if_closed(self) -> None:
        """A start under way ends at its next step once ``close()`` was asked (quitting
        right after the Camera screen opened does not wait for the vision to load)."""
        if self._closed.is_set():
            raise _Closing

    def close(self) -> None:
        """Stop the loop and close the camera and sinks; a start under way gives up at
        its next step. The service does not start again."""
        self._closed.set()
        self._taken.set()  # a start waiting for a screen to take its first frame
        self.stop("closed")
        for name in list(self._sinks):
            self._close_sink(name)
        with self._start_lock:
            if self.camera is not None:
                self.camera.close()
                self.camera = None

    # ------------------------------------------------------------------ tuning
    def median_background(self) -> np.ndarray | None:
        """The per-pixel median of the recent frames (None before any): what ``b``
        would learn (``console.session.background_check`` looks for a hand in it)."""
        with self._lock:
            frames = list(self.recent)
        if not frames or self.classifier is None:
            return None
        return np.median(np.stack(frames), axis=0).astype(np.float32)

    def hand_in_view(self, median: np.ndarray | None = None) -> InView:
        """A hand in the recent frames (``background_check.in_view``): what ``b``
        asks about before it learns them (``median``: theirs, when known)."""
        with self._lock:
            frames, seen = list(self.recent), list(self.recent_seen)
        return in_view(frames, seen, median)

    def capture_background(self, image: np.ndarray | None = None) -> int:
        """Background = ``image`` or the per-pixel median of the recent frames (show the
        empty table); the number of recent frames (0: none yet)."""
        with self._lock:
            n = len(self.recent)
        image = self.median_background() if image is None else image
        if image is None or self.classifier is None:
            return 0
        self.classifier.set_background(image)
        return n

    def _adjustable(self):
        """The camera when its driver takes exposure, gain ... (``AdjustableCamera``)."""
        cam = self.camera
        return cam if isinstance(cam, AdjustableCamera) else None

    def params(self) -> dict[str, float]:
        """The classifier's tunables (``console.core.contracts.Classifier``) and the camera's
        controls (``AdjustableCamera``: exposure, gain), by name."""
        out = self.classifier.tunables() if self.classifier is not None else {}
        cam = self._adjustable()
        return {**out, **cam.control_values()} if cam is not None else out

    def vision_params(self) -> dict[str, float]:
        """The classifier's tunables alone (what a demo's classifier takes)."""
        return self.classifier.tunables() if self.classifier is not None else {}

    def control_values(self) -> dict[str, float]:
        """The camera's controls alone (exposure, gain: what a demo's camera takes; empty
        when its driver takes none)."""
        cam = self._adjustable()
        return cam.control_values() if cam is not None else {}

    def param_ranges(self) -> dict[str, TunableRange]:
        out = self.classifier.tunable_ranges() if self.classifier is not None else {}
        cam = self._adjustable()
        return {**out, **cam.controls()} if cam is not None else out

    def camera_controls(self) -> bool:
        """Whether the camera's driver takes exposure and gain from the console."""
        return self._adjustable() is not None

    def set_param(self, key: str, value: float) -> None:
        """Change a vision threshold or a camera control (kept in its range); the next
        frame uses it. A step that would break the order the classifier's thresholds
        keep (``OrderedTunables``) is refused: a ``UserError`` saying why."""
        rng = self.param_ranges().get(key)
        if rng is None:
            return
        why = self._out_of_order(key, rng.clamp(value))
        if why:
            raise UserError(why)
        self._set(key, value)

    def _out_of_order(self, key: str, value: float) -> str:
        """Why ``key`` = ``value`` breaks the thresholds' order ("" when it does not, or
        when it moves a setting back towards it)."""
        clf, now = self.classifier, self.params()
        if not isinstance(clf, OrderedTunables) or key not in now:
            return ""
        for lo, hi, why in clf.tunable_order():
            if lo not in now or hi not in now:
                continue
            if key == lo and now[hi] > 0 and value >= now[hi] and value > now[lo]:
                return f"{lo} stays {now[lo]:g}: it must stay below {hi} {now[hi]:g} ({why})"
            if key == hi and 0 < value <= now[lo] and value < now[hi]:
                return f"{hi} stays {now[hi]:g}: it must stay above {lo} {now[lo]:g} ({why})"
        return ""

    def changed_params(self) -> dict[str, tuple[float, float]]:
        """The settings changed from the profile's: {name: (now, the profile's)}."""
        now = self.params()
        return {k: (now[k], v) for k, v in self.profile_params.items() if k in now and now[k] != v}

    def reset_params(self) -> list[str]:
        """Every setting back as the profile has it (``profile_params``); the names
        changed."""
        changed = list(self.changed_params())
        for key in changed:
            self._set(key, self.profile_params[key])
        return changed

    def _set(self, key: str, value: float) -> None:
        """``key`` = ``value`` kept in its range: the classifier's or the camera's."""
        rng = self.param_ranges().get(key)
        if rng is None:
            return
        cam = self._adjustable()
        if cam is not None and key in cam.controls():
            self.set_control(key, rng.clamp(value))
        elif self.classifier is not None:
            self.classifier.set_tunable(key, rng.clamp(value))

    def set_control(self, name: str, value: float) -> None:
        """The camera's exposure or gain = ``value``; the recent frames start again (a
        background is the median of frames under one setting)."""
        cam = self._adjustable()
        if cam is None:
            raise UserError("this camera's driver takes no exposure or gain")
        cam.set_control(name, value)
        with self._lock:  # the frames so far were taken under the old setting
            self.recent.clear()
            self.recent_seen.clear()
            self._recent_from_s = time.monotonic() + CONTROL_SETTLE_S

    def tuning_saved(self) -> bool:
        """Whether the profile's overrides file keeps vision settings (``save_tuning``
        replaces them)."""
        # lazy: the overrides file is read only when W asks (as save_tuning writes it)
        from console.config.profile import overrides_keep

        clf, cam = self.classifier, self._adjustable()
        keys = list(clf.tunable_keys().values()) if isinstance(clf, TunablesInProfile) else []
        keys += list(cam.control_keys().values()) if cam is not None else []
        return bool(keys) and overrides_keep(self.profile, keys)

    def save_tuning(self) -> Path:
        """Keep the tuned thresholds for the next start: written to the profile's override
        file in the user's config directory (``console.config.profile.save_overrides``) under the
        keys the classifier names (``TunablesInProfile``); returns the file."""
        # lazy: pluggy loads only when tunables are saved
        from console.config.profile import save_overrides

        clf = self.classifier
        if clf is None:
            raise UserError("no thresholds to save yet: wait for the camera's first frame")
        if not isinstance(clf, TunablesInProfile):
            name = self.profile.get("gestures.classifier") or "?"
            raise UserError(
                f"the classifier {name!r} names no profile keys for its thresholds: they "
                "last until the console closes"
            )
        keys = clf.tunable_keys()
        values = {keys[k]: v for k, v in clf.tunables().items() if k in keys}
        cam = self._adjustable()
        if cam is not None:
            ckeys = cam.control_keys()
            values.update({ckeys[k]: v for k, v in cam.control_values().items() if k in ckeys})
        path = save_overrides(self.profile, values, self.plugins)
        self.profile_params.update(self.params())  # the profile's now
        return path

    # ------------------------------------------------------------------ output switches
    def switches(self) -> dict[str, Any]:
        """The frame sinks the console can switch (``contracts.SwitchableSink``, e.g. the
        TUIO sender), by name."""
        return {
            name: reg.factory
            for name, reg in self.plugins.of("frame_sink").items()
            if isinstance(reg.factory, SwitchableSink)
        }

    def sink_state(self, name: str) -> tuple[bool, str]:
        """(on, "host:port") of switchable sink ``name``, as this loop has it."""
        keys = self.switches()[name].keys
        target = f"{self.profile.get(keys['host'])}:{self.profile.get(keys['port'])}"
        return name in self._sinks, target

    def sink_problem(self, name: str) -> str:
        """Why sink ``name``, on in the profile, could not be opened ("": it was not)."""
        return self.sink_errors.get(name, "")

    def set_sink(self, name: str, on: bool, target: str | None = None) -> Path:
        """Switch sink ``name`` on or off (and point it at ``target`` "host:port"), saved
        to the profile's overrides file (the next start has it); a running loop feeds it
        from the next frame. Returns the file. Bad ``target``: a ``UserError``."""
        # lazy: pluggy loads only when tunables are saved
        from console.config.profile import load_profile, save_overrides, with_settings

        factory = self.switches().get(name)
        if factory is None:
            raise UserError(f"no switchable output {name!r}: its plugin is not loaded")
        keys = factory.keys
        settings: dict[str, Any] = {keys["enabled"]: bool(on)}
        if target is not None:
            settings[keys["host"]], settings[keys["port"]] = parse_target(name, target)
        self._close_sink(name)  # its port free for the trial (a WebSocket server)
        try:  # a target it cannot send to: refused, nothing written, the old one kept
            if on or target is not None:
                trial = factory(with_settings(self.profile, {**settings, keys["enabled"]: True}))
                if trial is not None:
                    trial.close()
            path = save_overrides(self.profile, settings, self.plugins)
            self.profile = load_profile(self.profile.path, self.plugins)
        except UserError:
            if self.running:
                self._open_sinks()
            raise
        if self.running:
            self._open_sinks()
        return path

    def _open_sinks(self) -> None:
        """Open the switchable sinks the profile turns on (those not open yet)."""
        for name, factory in self.switches().items():
            if name not in self._sinks:
                self.sink_errors.pop(name, None)
                try:  # a sender that fails never stops the camera: its line says why
                    sink = factory(self.profile)
                except UserError as exc:
                    self.sink_errors[name] = str(exc)
                    continue
                if sink is not None:
                    self._sinks[name] = sink
                    self.frame_hooks.append(sink)

    def _close_sink(self, name: str) -> None:
        self.sink_errors.pop(name, None)
        sink = self._sinks.pop(name, None)
        if sink is not None:
            self.frame_hooks.remove(sink)
            sink.close()

    def views(self) -> tuple[str, ...]:
        """The classifier's intermediate images a result shows (``VisionResult.view``)."""
        return tuple(self.classifier.views) if self.classifier is not None else ()

    def status(self, percentiles: bool = True) -> dict:
        """The camera's status and the loop's latency snapshot (``percentiles=False``:
        its counters and rate only, ``LatencyMonitor.counts``)."""
        cam = {}
        if self.camera is not None:
            try:
                cam = self.camera.status()
            except Exception as exc:
                cam = {"error": str(exc)}
        mon = None
        if self.loop is not None:
            m = self.loop.monitor
            mon = m.snapshot() if percentiles else m.counts()
        return {"camera": cam, "latency": mon, "error": self.error, "borrower": self.borrower}


def target_problems(host: str, port: str) -> list[str]:
    """What is wrong with a "host:port" target's two halves, in words ([] when nothing):
    a port outside 1-65535, an IPv4 address with a number outside 0-255, a host the
    profile's own check refuses (``host_problem``: a space, no host name). Every check the
    setting meets when saved is made here first, so a refusal names the typed host, never
    the overrides file it was not written to."""
    problems = []
    parts = host.split(".")
    if all(p.isdigit() for p in parts):  # digits and dots: an IPv4 address
        if len(parts) != 4:
            problems.append(f"{host} is not an IPv4 address (four numbers 0-255)")
        problems += [f"{p} is not 0-255 in an IPv4 address" for p in parts if int(p) > 255][:1]
    elif (why := host_problem(host)) is not None:
        problems.append(f"host {host!r} {why}")
    if not port.isdigit():
        problems.append(f"port {port!r} is not a number 1-65535")
    elif not 1 <= int(port) <= 65535:
        problems.append(f"port {port} is not 1-65535")
    return problems


def parse_target(name: str, target: str) -> tuple[str, int]:
    """(host, port) of sink ``name``'s ``target`` "host:port", or a ``UserError`` saying
    what is wrong with it (its shape, its address, its port)."""
    host, sep, port = target.strip().rpartition(":")
    if not sep or not host or not port:
        raise UserError(f"{name} target {target!r}: write host:port, e.g. 127.0.0.1:3333")
    problems = target_problems(host, port)
    if problems:
        raise UserError(f"{name} target {target!r}: {'; '.join(problems)}")
    return host, int(port)
