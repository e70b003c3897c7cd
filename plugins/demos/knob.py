"""The knob demo (paper 5.3-5.4): a two-finger rotation drives the knob in a condition.

The registered ``knob`` effect gives a live session; its stream plays through the
outputs from ``start()`` to ``stop()`` (ramped in and out by the stream). Per frame:
``scene`` (the ``knob`` scene follows the angle) <- ``effect`` (the hand's contacts feed
the session: tracker -> sectors -> stream) -> ``scheduled`` (the new angle, velocity and
crossings were posted to the stream: its next audio block plays them).
"""

from __future__ import annotations

import time
from collections import deque
from typing import Any

from console.plugin_api import Frame, KnobTrials
from console.plugin_api.runtime import PASSED

from .scene import SceneLink


class KnobDemo:
    name = "knob"

    def __init__(
        self,
        profile: Any,
        plugins: Any,
        outputs: Any,
        *,
        condition: str = "HD+CF",
        sectors: int | None = None,
        projector: Any = None,
    ) -> None:
        effect = plugins.provider(
            "effect", KnobTrials, profile, plugin_hint="electrostatic", fresh=True
        )
        self.session = effect.session(condition, sectors)
        self.condition, self.outputs = condition, outputs

        self.link = SceneLink(plugins, profile, "knob", projector)
        self.scene = self.link.scene
        k = self.session.knob
        self.sectors = int(k.sectors)
        # the scene counts sectors from its trial's start item at angle 0
        self._zero_deg = float(k.center_deg(k.item)) - k.width_deg / 2
        self.report = None
        #: the last crossings (bounded: a demo runs for as long as the operator likes)
        self.crossings: deque[dict] = deque(maxlen=512)
        self.crossings_total = 0
        self.events: list[dict] = []
        self.frames_touching = 0
        #: crossing id -> when it was posted to the stream (monotonic s; bounded)
        self._posted: dict[int, float] = {}

    def start(self, progress=None, *, wait: bool = False) -> None:
        """Open the knob's stream (its detents are synthesised in the kernel: nothing to
        prepare, so ``wait`` and ``progress`` change nothing)."""
        if self.scene is not None:
            self.link.emit({"type": "trial", "sectors": int(self.sectors), "distance_deg": 270.0})
        self.report = self.outputs.stream(self.session.stream, name=f"knob {self.condition}")

    def stop(self, timeout_s: float = 2.0) -> None:
        """Ramp the stream down and wait (bounded) for it to end."""
        self.session.stream.request_stop()
        if self.report is not None:
            self.report.done.wait(timeout_s)

    def effect_stage(self, frame: Frame, work: dict) -> None:
        hand = work.get("hand")
        contacts = hand.contacts if hand is not None and hand.contacts else work.get("contacts", ())
        pts = [c for c in contacts if c.pos_mm is not None] or list(contacts)
        t = frame.t_capture_s
        crossed = self.session.feed(t, pts)
        if crossed:
            now = time.monotonic()
            for cid in list(self.session.crossing_ids)[-len(crossed) :]:
                self._posted[int(cid)] = now
            while len(self._posted) > 512:
                self._posted.pop(next(iter(self._posted)))
        tr = self.session.tracker
        work["knob"] = {
            "angle_deg": float(tr.angle_deg),
            "velocity_deg_s": float(tr.velocity_deg_s),
            "touching": bool(tr.touching),
            "item": int(self.session.knob.item),
            "crossings": len(crossed),
        }
        if len(pts) >= 2:
            self.frames_touching += 1
        self.crossings_total += len(crossed)
        for c in crossed:
            self.crossings.append(
                {"t_s": c.t_s, "seq": frame.seq, "item": c.to_item, "direction": c.direction}
            )

    def crossing_to_output_s(self) -> list[float]:
        """Per crossing the outputs reported: from its post to the stream to the block
        holding its detent's first sample handed to the audio driver (seconds)."""
        rep = self.report
        if rep is None:
            return []
        return [d[2] - self._posted[d[0]] for d in list(rep.detents) if d[0] in self._posted]

    def crossing_in_kernel_s(self) -> list[float]:
        """Per crossing: from its post arriving at the outputs process to the block holding
        its pulse's first sample handed to the driver (the socket hop left out)."""
        rep = self.report
        if rep is None:
            return []
        return [d[2] - d[3] for d in list(rep.detents) if len(d) > 3 and d[3] == d[3]]

    def scheduled_stage(self, frame: Frame, work: dict) -> object:
        """Stamped only when this frame's crossings posted detents to the stream (its next
        block, <= one audio block away, plays them): end to end counts those frames."""
        if not work.get("knob", {}).get("crossings"):
            return PASSED  # nothing scheduled: no output stamp, the scene still runs
        work["scheduled_s"] = time.monotonic()
        return None

    def scene_stage(self, frame: Frame, work: dict) -> None:
        a = work.get("knob", {}).get("angle_deg")
        if self.scene is not None and a is not None:
            ev = {"type": "knob", "angle_deg": float(a) - self._zero_deg}
            self.link.emit(ev, min_interval_s=1 / 30)

    def stage_fns(self) -> list:
        return [
            ("effect", self.effect_stage),
            ("scheduled", self.scheduled_stage),
            ("scene", self.scene_stage),
        ]
