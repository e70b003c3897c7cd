"""The protocol's projected scene: answers from the arrow buttons the camera sees
touched (exp2, Fig. 12b), and the knob and its menu during knob trials (Fig. 16a).

The protocol names the scene (``[study] scene``, ``flow_hand`` for experiment 2: the
hand-placement guide on the trial's region and four arrow buttons beside it). During a
run on the console session, ``ProjectedAnswers`` shows it on the projector, moves the
guide to each trial's region (``{"type": "region"}``), marks the stimulus playing
(``{"type": "playing"}``), and passes each new fingertip contact the camera loop sees
(``contacts`` with ``pos_mm``) to the scene as a ``touch``; when the scene's state then has
a ``selected`` arrow, that direction is the answer. A finger must lift before it answers
again (a resting finger answers once). For the knob (``scene = "knob"``) each trial sets
the scene's sectors and distance (``{"type": "trial"}``) and the live knob session's state
is shown as the finger turns it (``show``, ``LiveKnob``).
"""

from __future__ import annotations

import threading
from typing import Any

from console.plugin_api import UserError

from .runner import Answer

#: contacts closer than this to one of the last frame's are the same finger (still down)
SAME_FINGER_MM = 15.0


class ProjectedAnswers:
    """The scene ``scene`` on the session's projector and its touched arrows as answers
    put to ``responder`` (a ``QueueResponder``)."""

    def __init__(self, session: Any, responder: Any, scene: str, by: str = "a study run") -> None:
        self.session = session
        self.responder = responder
        self.scene = scene
        self.by = by  # who holds the projector, as the Scenes screen says it
        self.armed = False
        self._down: list[tuple[float, float]] = []
        self._lock = threading.Lock()
        self._open = False

    def open(self) -> None:
        """Show the scene and watch the camera (blocking: from a worker)."""
        if not self.session.scenes.start(self.scene, by=self.by):
            raise UserError(
                f"scene {self.scene}: the projector did not show it (the Scenes screen says "
                "why); untick 'projector' to answer with the keys"
            )
        self.session.camera.frame_hooks.append(self._frame)
        self.session.camera.watch(self, True)
        if self.session.camera.error:
            self.close()
            raise UserError(f"camera: {self.session.camera.error}; untick 'projector'")
        self._open = True

    def close(self) -> None:
        self.armed = False
        hooks = self.session.camera.frame_hooks
        if self._frame in hooks:
            hooks.remove(self._frame)
        self.session.camera.watch(self, False)
        if self._open:
            self.session.scenes.stop()
            self._open = False

    def _update(self, event: dict[str, Any]) -> dict[str, Any]:
        svc = self.session.projector
        if svc is None:
            raise UserError("the projector stopped; start the study again")
        return svc.update(event)

    def show(self, event: dict[str, Any]) -> Any:
        """Pass an event to the scene (the knob's state while a knob trial runs)."""
        return self._update(event)

    def notice(self, kind: str, info: dict[str, Any]) -> None:
        """Follow the run (the runner's notices): region, playing, waiting for an answer;
        a knob trial's sectors and distance."""
        if kind == "start" and info["trial"]["stimulus"].get("task") == "knob":
            s, i = info["trial"]["stimulus"], info["trial"]["index"]
            self._update(
                {
                    "type": "trial",
                    "sectors": s["sectors"],
                    "distance_deg": s["distance_deg"],
                    "seed": i,
                }
            )
            return
        if kind == "start":
            self.armed = False
            region = info["trial"].get("region")
            if region:
                try:
                    self._update({"type": "region", "name": region})
                except UserError as exc:
                    raise UserError(
                        f"{exc}: the protocol's regions must be [projector] hand_regions"
                    ) from None
            self._update({"type": "playing", "on": True})
        elif kind == "replay":
            self.armed = False
            self._update({"type": "playing", "on": True})
        elif kind == "waiting":
            self._update({"type": "playing", "on": False})
            self.armed = True
        elif kind in ("done", "aborted", "finished"):
            self.armed = False

    def _frame(self, frame: Any, work: dict[str, Any]) -> None:
        pts = [
            (float(c.pos_mm[0]), float(c.pos_mm[1]))
            for c in work.get("contacts", ())
            if c.pos_mm is not None
        ]
        with self._lock:
            new = [
                p
                for p in pts
                if all(
                    (p[0] - q[0]) ** 2 + (p[1] - q[1]) ** 2 > SAME_FINGER_MM**2 for q in self._down
                )
            ]
            self._down = pts
        if not self.armed:
            return
        for p in new:
            try:
                state = self._update({"type": "touch", "pos_mm": [p[0], p[1]]})
            except UserError:
                return
            sel = state.get("selected")
            if sel:
                self.armed = False
                self.responder.put(Answer(response=str(sel)))
                return
