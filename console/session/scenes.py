"""Projected scenes: the console's projector service and the scene it shows.

``SceneControl`` starts the projector process on first use (``ensure``), shows a scene
there (``start``), shows black (``stop``) and stops the process (``close_projector``).
It reports ``Started``/``Stopped``/``Failed`` events with topic ``projector``. Blocking
calls run on the caller's thread: screens call them from workers.
"""

from __future__ import annotations

import contextlib
import os
import threading
from typing import Any

from console.core.errors import UserError
from console.session.events import Started, Stopped

#: how long a scene start waits for the projector process to connect
CONNECT_WAIT_S = 10.0


class SceneControl:
    """The projector service of ``session`` (None until first used) and its scenes."""

    def __init__(self, session: Any) -> None:
        self.session = session
        self.service: Any = None  # the running ProjectorService
        self._lock = threading.Lock()

    def ensure(self) -> Any:
        """The projector service, started on first use (blocking)."""
        with self._lock:
            if self.service is None:
                from console.runtime.projector.service import ProjectorService, effect_providers

                s = self.session
                headless = not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY")
                svc = ProjectorService.from_profile(
                    s.profile,
                    s.plugins,
                    headless=headless,
                    providers=effect_providers(s.profile, s.plugins, self.current_map),
                )
                svc.start()
                self.service = svc
            return self.service

    def current_map(self) -> Any:
        """The console's vibration map for a scene's ``tables``: the vibration session's,
        else this profile's measured map, else a ``UserError``."""
        return self.session.vibration.current_map()

    def start(self, name: str) -> bool:
        """Show scene ``name`` on the projector (starting it). Blocking; a failure is
        reported as a ``Failed`` event."""
        try:
            svc = self.ensure()
            svc.link.wait_connected(CONNECT_WAIT_S)
            svc.start_scene(name)
        except (UserError, OSError) as exc:
            self.session.fail("projector", f"scene {name}: {exc}", name=name, severity="warning")
            return False
        self.session.emit(Started("projector", name, detail=f"scene {name} started"))
        return True

    def stop(self) -> None:
        """Show black (the projector keeps running)."""
        svc = self.service
        if svc is not None:
            svc.stop_scene()
            self.session.emit(Stopped("projector", reason="black"))

    def status(self) -> dict | None:
        """``ProjectorService.status()`` (None: not started)."""
        svc = self.service
        if svc is None:
            return None
        try:
            return svc.status()
        except Exception as exc:  # noqa: BLE001 - shown, never raised into the UI
            return {"last_error": str(exc)}

    def close_projector(self) -> None:
        """Stop the projector process (blocking)."""
        with self._lock:
            svc, self.service = self.service, None
        if svc is not None:
            with contextlib.suppress(Exception):
                svc.close()
            self.session.emit(Stopped("projector", reason="closed"))
