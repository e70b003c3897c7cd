"""The touch-calibration wizard on the console's camera, outside the screens.

The classifier offers a calibration session (its optional ``touch_calibration(profile)``,
see ``console.core.hookspecs``): targets in table millimetres, fed the contacts of each frame.
The wizard hooks the camera service's frames, shows the targets on the projector (when
one runs), lets a camera twin touch the shown target, and reports to the session's
observers with topic ``calibration``: ``Started`` (the targets), ``Progress`` (each
target recorded, lifted or skipped), ``Snapshot`` (the fit's report), ``Stopped``
(finished or cancelled) and ``Failed`` (not available, or the fit failed).

``message`` is the operator's line about where the wizard stands (plain text).
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

from console.config.profile_files import profile_file
from console.core.contracts import TouchableCamera, TouchCalibrating
from console.core.errors import UserError
from console.session.events import Failed, Progress, Snapshot, Started, Stopped

TOPIC = "calibration"
#: what a finished calibration's result asks for, until it is saved
SAVE_KEY = "S: save"
#: ``projector_note`` while the wizard runs with no projector to show its targets
NO_PROJECTOR = (
    "projector not started: the targets show on the Camera view only (a scene on "
    "Scenes, F6, starts it)"
)


class TouchCalibration:
    """One wizard per console session; ``start`` begins a new calibration."""

    def __init__(self, session: Any, projector: Callable[[], Any] | None = None) -> None:
        self.session = session
        #: the running projector service, or None (the wizard then runs without targets)
        self.projector: Callable[[], Any] = projector or (lambda: None)
        self.active: Any = None  # the classifier's calibration session while it runs
        self.result: Any = None  # the finished fit (``report()``, ``save(path)``)
        self.message = ""
        self.report_text = ""  # the finished fit's numbers (``message`` adds its key)
        self.failed = False  # ``message`` reports a failure
        #: what the projector does for the running wizard ("" when none runs): set when
        #: the targets are sent, when they showed, when sending failed
        self.projector_note = ""
        self._lock = threading.RLock()
        self._to_projector: queue.Queue = queue.Queue()
        self._sender: threading.Thread | None = None

    @property
    def camera(self) -> Any:
        return self.session.camera

    # ------------------------------------------------------------------ start
    def start(self) -> bool:
        """Begin a calibration with the classifier's session; False (and a ``Failed``
        event naming the reason) when the camera or the classifier offers none."""
        cal = self._new()
        if cal is None:
            return False
        targets = [[float(v) for v in t] for t in cal.targets_mm]
        with self._lock:
            self.active, self.result, self.failed = cal, None, False
            self.message = f"touch target 1 of {len(targets)}"
        svc = self.camera
        if self._hook not in svc.frame_hooks:
            svc.frame_hooks.append(self._hook)
        self._project("start", targets)
        self._aim_twin()
        self.session.emit(Started(TOPIC, detail=self.message))
        self._progress()
        return True

    def _new(self) -> Any:
        svc, prof = self.camera, self.session.profile
        clf = svc.classifier
        if clf is None:
            why = "the vision is not running yet; wait for its numbers, then press k"
            if svc.error:
                why = f"no camera ({svc.error})"
            return self._unavailable(f"touch calibration: {why}")
        if not isinstance(clf, TouchCalibrating):
            name = prof.get("gestures.classifier") or "?"
            return self._unavailable(
                f"touch calibration: the classifier {name!r} offers none; choose one that "
                "does in [gestures] classifier (e.g. svm)"
            )
        try:
            return clf.touch_calibration(prof)
        except UserError as exc:
            return self._unavailable(str(exc))

    def _unavailable(self, msg: str) -> None:
        with self._lock:
            self.message, self.failed = msg, False  # a plain sentence, not an error
        self.session.emit(Failed(TOPIC, message=msg, severity="warning"))
        return None

    # ------------------------------------------------------------------ while it runs
    def target_mm(self) -> tuple[float, float] | None:
        """The target to touch now (table mm), or None."""
        cal = self.active
        nt = cal.next_target() if cal is not None else None
        return None if nt is None else nt[1]

    def target_px(self) -> tuple[float, float] | None:
        """Where the target appears in the camera image, when the camera knows its
        mapping (a twin does), else None."""
        pos = self.target_mm()
        if pos is None or self.camera.classifier is None:
            return None
        return _mm_to_px(self.camera.camera, pos)

    def _hook(self, frame: Any, work: dict) -> None:
        """Fed every processed frame (the camera's processing thread)."""
        with self._lock:
            cal = self.active
            if cal is None:
                return
            ev = cal.feed(work.get("contacts", ()) or ())
            if ev not in ("recorded", "lifted", "done"):
                return
            done, total = cal.progress()
            if ev == "recorded":
                self.message = f"recorded {done}/{total}: lift the finger"
                self._project("touch")
                self._set_twin_target(None)
            elif ev == "lifted":
                self.message = f"touch target {cal.index + 1} of {total}"
                self._aim_twin()
        if ev == "done":
            self._finish()
        else:
            self._progress()

    def skip(self) -> None:
        """Skip the current target (the finger cannot reach it, the projector hides it)."""
        with self._lock:
            cal = self.active
            if cal is None:
                return
            cal.skip()
            self._project("touch")
            done = cal.state == "done"
            if not done:
                self.message = f"touch target {cal.index + 1} of {cal.progress()[1]}"
                self._aim_twin()
        if done:
            self._finish()
        else:
            self._progress()

    def cancel(self) -> bool:
        """Stop the running calibration (nothing is kept); False when none runs."""
        with self._lock:
            if self.active is None:
                return False
            self.active = None
            self.message, self.failed = "calibration cancelled", False
        self._unhook()
        self._project("stop")
        self.session.emit(Stopped(TOPIC, reason="cancelled"))
        return True

    def _finish(self) -> None:
        with self._lock:
            cal, self.active = self.active, None
        if cal is None:
            return
        self._unhook()
        try:
            result = cal.finish()
        except UserError as exc:
            with self._lock:
                self.message, self.failed = str(exc), True
            self.session.emit(Failed(TOPIC, message=str(exc)))
            self.session.emit(Stopped(TOPIC, reason=str(exc)))
            return
        r = result.report()
        with self._lock:
            self.result = result
            self.report_text = report_words(r)
            self.message = f"{self.report_text} {SAVE_KEY}"
        self._project("stop")
        self.session.emit(Snapshot(TOPIC, data=dict(r)))
        self.session.emit(Stopped(TOPIC, reason="done"))

    def save(self, path: str | Path | None = None) -> Path:
        """Write the finished calibration (default: the profile's ``[vision]
        calibration`` file, which the classifier reads); ``UserError`` when none is."""
        if self.result is None:
            raise UserError("no calibration to save: run it first (k)")
        prof = self.session.profile
        dest = (
            Path(path)
            if path
            else profile_file(prof, "vision.calibration", "touch_calibration.json")
        )
        self.result.save(dest)
        with self._lock:  # the key it asked for is done: the line says so, not "S: save"
            self.message = f"{self.report_text} saved to {dest}"
        self.session.emit(Stopped(TOPIC, reason=f"saved: {dest}"))  # the log's line
        return dest

    # ------------------------------------------------------------------ helpers
    def _progress(self) -> None:
        cal = self.active
        if cal is None:
            return
        done, total = cal.progress()
        self.session.emit(Progress(TOPIC, fraction=done / max(total, 1), text=self.message))

    def _unhook(self) -> None:
        svc = self.camera
        if self._hook in svc.frame_hooks:
            svc.frame_hooks.remove(self._hook)
        self._set_twin_target(None)

    def _aim_twin(self) -> None:
        """On the camera twin, the simulated operator touches the shown target."""
        if self.active is not None:
            self._set_twin_target(self.target_mm())

    def _set_twin_target(self, pos_mm: Any) -> None:
        cam = self.camera.camera
        if isinstance(cam, TouchableCamera):
            cam.set_target(pos_mm)

    def _project(self, what: str, targets: list | None = None) -> None:
        """Tell the projector, in order, from a thread of its own (never stall the frame
        loop on the projector's socket)."""
        svc = self.projector()
        if what != "touch":  # what is true from now on (the sender says how it went)
            self.projector_note = "" if what == "stop" else NO_PROJECTOR
        if svc is None:  # no projector running: the console alone drives the wizard
            return
        with self._lock:
            if what == "start":
                self.projector_note = "projector: sending the targets ..."
            self._to_projector.put((svc, what, targets))
            if self._sender is None:
                self._sender = threading.Thread(
                    target=self._send, name="calibration-projector", daemon=True
                )
                self._sender.start()

    def _send(self) -> None:
        while True:
            with self._lock:
                if self._to_projector.empty():
                    self._sender = None
                    return
                svc, what, targets = self._to_projector.get()
            try:
                if what == "start":
                    svc.start_scene(
                        "touch_calibration", [{"type": "targets", "targets_mm": targets}]
                    )
                    if self.active is not None:
                        self.projector_note = "projector: shows the targets"
                elif what == "touch":
                    svc.update({"type": "touch"})
                else:
                    svc.stop_scene()
            except Exception as exc:  # noqa: BLE001 - the projector is optional here
                if self.active is not None:
                    self.projector_note = (
                        f"projector: {exc}: the targets show on the Camera view only"
                    )
                self.session.emit(Failed("projector", message=str(exc), severity="warning"))


def _mm_to_px(cam: Any, pos_mm: Any) -> tuple[float, float] | None:
    """Where a table point appears in the camera (a touchable camera, the twin, knows)."""
    if not isinstance(cam, TouchableCamera):
        return None
    px = cam.mm_to_px((float(pos_mm[0]), float(pos_mm[1])))
    return None if px is None else (float(px[0]), float(px[1]))


def report_words(r: dict) -> str:
    """A calibration's result (``report()``) in words that do not read as a
    contradiction (``0.00 mm rms ... (leave-one-out 3.55 mm)``): the leave-one-out error
    first, as what to expect of a new touch (each target predicted by the fit without
    it: the number to trust), then the fit's residual on the targets it was fitted to
    (near 0 when the correction bends to pass through them)."""
    return (
        f"{r['pairs']} targets: expect {r['loo_rms_mm']:.2f} mm rms on a new touch "
        "(leave-one-out: each target predicted without it; trust this); fit residual "
        f"{r['rms_mm']:.2f} mm rms, {r['max_mm']:.2f} mm max on the targets themselves; "
        f"outliers {r['outliers'] or 'none'}."
    )
