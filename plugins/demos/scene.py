"""A demo's projected scene: the demo's own copy (its logic: arrow buttons, the selected
direction) and, when the console runs a projector, the same events forwarded to it.

``projector`` is anything with ``update(event) -> dict`` (the console's
``console.runtime.projector.service.ProjectorService`` after ``start_scene``). A projector
failure never stops the haptics: it is logged and counted.
"""

from __future__ import annotations

import logging
import time
from typing import Any

log = logging.getLogger("haptable.demos.scene")


class SceneLink:
    def __init__(self, plugins: Any, profile: Any, name: str, projector: Any = None) -> None:
        reg = plugins.of("scene").get(name)
        self.name = name
        self.scene = reg.factory(profile) if reg is not None else None
        self.projector = projector
        self.forwarded = 0
        self.failures = 0
        self._last_sent = 0.0

    def state(self) -> dict:
        return self.scene.state() if self.scene is not None else {}

    def emit(self, event: dict, *, min_interval_s: float = 0.0) -> None:
        """Apply ``event`` to the scene; forward it to the projector (at most every
        ``min_interval_s`` for high-rate events like the knob angle)."""
        if self.scene is not None:
            self.scene.update(event)
        if self.projector is None:
            return
        now = time.monotonic()
        if min_interval_s and now - self._last_sent < min_interval_s:
            return
        self._last_sent = now
        try:
            self.projector.update(event)
            self.forwarded += 1
        except Exception as exc:
            self.failures += 1
            if self.failures == 1:
                log.warning("projector update failed (haptics go on): %s", exc)
