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
        #: (scene, who asked for it) of the last ``start(name, by=...)``: what a screen
        #: says holds the projector while that scene shows; ``starting``: the same
        #: while the projector starts for it
        self.holder: tuple[str, str] | None = None
        self.starting: tuple[str, str] | None = None

    def ensure(self) -> Any:
        """The projector service, started on first use (blocking)."""
        with self._lock:
            if self.service is None:
                # lazy: the projector's service (numpy, its process) loads when a scene starts
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

    def start(self, name: str, by: str = "the Scenes screen") -> bool:
        """Show scene ``name`` on the projector (starting it) for ``by`` (who holds the
        projector then, as the screens say it). Blocking; a failure is reported as a
        ``Failed`` event; refused while a demo shows its own scene there (its scene is
        never replaced unasked: the demo stops first)."""
        demo = self.session.demos.projecting()
        if demo is not None:
            fix = "s stops it first" if by == "the Scenes screen" else "Scenes (F6): s stops it"
            why = f"the {demo} demo shows its scene on the projector; {fix}"
            self.session.fail(
                "projector", f"scene {name} not started: {why}", name=name, severity="warning"
            )
            return False
        self.starting = (name, by)
        try:
            svc = self.ensure()
            svc.link.wait_connected(CONNECT_WAIT_S)
            svc.start_scene(name)
        except (UserError, OSError) as exc:
            self.session.fail("projector", f"scene {name}: {exc}", name=name, severity="warning")
            return False
        finally:
            self.starting = None
        self.holder = (name, by)
        self.session.emit(Started("projector", name, detail=f"scene {name} started"))
        return True

    def stop(self) -> None:
        """Show black (the projector keeps running)."""
        svc = self.service
        self.holder = None
        if svc is not None:
            svc.stop_scene()
            self.session.emit(Stopped("projector", reason="black"))

    def status(self) -> dict | None:
        """``ProjectorService.status()`` with ``holder`` (who asked for the scene shown);
        ``{"starting": True, "scene": ..., "holder": ...}`` while the projector starts;
        None: not started."""
        svc, starting = self.service, self.starting
        if svc is None:
            if starting is None:
                return None
            return {"starting": True, "scene": starting[0], "holder": starting[1]}
        try:
            st = dict(svc.status())
        except Exception as exc:  # noqa: BLE001 - shown, never raised into the UI
            st = {"last_error": str(exc)}
        feed = self.session.demos.scene_feed()  # a demo's scene shown: the demo holds it
        if starting is not None:
            st["holder"] = starting[1]
        elif feed is not None and feed.get("sent") and st.get("scene") == feed["scene"]:
            st["holder"] = f"the {feed['demo']} demo"
        elif self.holder is not None and st.get("scene") == self.holder[0]:
            st["holder"] = self.holder[1]  # another scene (a demo's): not theirs
        return st

    def close_projector(self) -> None:
        """Stop the projector process (blocking)."""
        with self._lock:
            svc, self.service = self.service, None
        self.holder = None
        if svc is not None:
            with contextlib.suppress(Exception):
                svc.close()
            self.session.emit(Stopped("projector", reason="closed"))
