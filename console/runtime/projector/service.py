"""What the console uses for projected scenes: ``ProjectorService``, the supervised
projector process plus the active scene and the preparation of what it needs.

::

    svc = ProjectorService.from_profile(profile, plugins)   # plugins: console.config.plugins.Plugins
    svc.start()                        # spawn (or adopt) the projector, connect
    svc.start_scene("knob")            # build the scene, prepare its needs, show it
    svc.update({"type": "rotate", "delta_deg": 45})   # events go to the active scene
    svc.stop_scene()                   # black
    svc.status()                       # connected, heartbeat age, fps, restarts, pid ...
    svc.snapshot("shown.png")          # what the projector shows now, as PNG
    svc.close()                        # stop the projector (stop_projector=False: leave it
                                       # running, black, for the next console to adopt)

The projector process is started as the projector registered by a plugin says
(``haptable_register_projectors``; ``[projector] driver`` picks one when several are).
``providers`` maps a need kind (``tables``, ``flow_regions``, ``knob``, ``contacts``)
to a function preparing it; ``start_scene`` calls only those its scene declares and
lists the rest in ``status()["unprepared_needs"]`` (why, where a provider said:
``status()["unprepared_why"]``; ``prepare_again()`` retries them). ``effect_providers``
gives the providers the registered effects back (``tables`` from the ``flow`` effect).
Call from any thread (scene events are serialised); nothing here blocks on the projector
except the ``wait_*`` calls.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import numpy as np

from console.core.contracts import TableEffect, points_event
from console.core.errors import UserError
from console.runtime.projector.client import ProjectorLink
from console.runtime.projector.protocol import HEARTBEAT_S, PEER_TIMEOUT_S, socket_path_for
from console.runtime.projector.supervisor import ProjectorLaunch, ProjectorSupervisor


def prepare_needs(
    needs: dict,
    providers: dict[str, Callable[[Any], Any]],
    reasons: dict[str, str] | None = None,
) -> tuple[dict, list[str]]:
    """Prepare only what a scene declares: call ``providers[kind](value)`` for each
    declared need. Returns (prepared, kinds not prepared: no provider, or the provider
    could not). A provider that cannot prepare raises ``UserError``; with ``reasons``
    given its message goes to ``reasons[kind]``, else it propagates."""
    prepared, missing = {}, []
    for kind, value in (needs or {}).items():
        if not value:
            continue
        if kind in providers:
            try:
                prepared[kind] = providers[kind](value)
            except UserError as exc:
                if reasons is None:
                    raise
                missing.append(kind)
                reasons[kind] = str(exc)
        else:
            missing.append(kind)
    return prepared, missing


def effect_providers(
    profile: Any, plugins: Any, current_map: Callable[[], Any]
) -> dict[str, Callable[[Any], Any]]:
    """Need providers backed by the registered effects (no plugin imported).

    ``tables`` (a list of grid points, or of (a, b) pairs, or ``"map"``: all of them):
    the lookup tables (a ``console.core.contracts.TableEffect``) of ``current_map()`` (the console's
    vibration map: a ``VibrationMap`` or a map file; it raises ``UserError`` when there
    is none), checked to cover the declared points. Returns ``{"tables": Tables,
    "points": [...]}`` (and ``"points_mm"`` for ``"map"``: the scene is told them as a
    ``points`` event, so it draws the map's own ids where they are)."""
    effects: dict[str, Any] = {}

    def flow() -> Any:  # the effect offering lookup tables, built once for this service
        if "tables" not in effects:
            effects["tables"] = plugins.provider(
                "effect", TableEffect, profile, plugin_hint="vibrotactile", fresh=True
            )
        return effects["tables"]

    def tables(points: Any) -> dict:
        eff = flow()
        vmap = current_map()
        t = eff.tables(vmap=vmap)
        have = {int(n) for n in t.vmap.points}
        if points == "map":  # every point of the map, as the map numbers them
            return {
                "tables": t,
                "points": [int(n) for n in t.vmap.points],
                "points_mm": np.asarray(t.vmap.points_mm, float).tolist(),
            }
        flat = sorted(
            {int(q) for p in points for q in (p if isinstance(p, (list, tuple)) else (p,))}
        )
        lack = [n for n in flat if n not in have]
        if lack:
            raise UserError(
                f"tables: the vibration map has no point {lack[0]} (of {len(lack)} missing); "
                "measure or import the whole grid"
            )
        return {"tables": t, "points": flat}

    return {"tables": tables}


def _tell_points(scene: Any, prepared: dict) -> None:
    """A scene that asked for the whole map's tables learns the map's point ids and mm."""
    got = prepared.get("tables")
    if isinstance(got, dict) and "points_mm" in got:
        scene.update(points_event(got["points"], got["points_mm"]))


def projector_launch(
    profile: Any,
    plugins: Any,
    socket_path: Path,
    *,
    headless: bool = False,
    extra: Iterable[str] = (),
) -> ProjectorLaunch:
    """How to start the projector serving ``socket_path``: from the registered projector
    ``[projector] driver`` names (default: the only one, else the first by name)."""
    regs = plugins.of("projector")
    if not regs:
        raise UserError(
            "no projector is registered: enable the projector plugin (not in "
            "HAPTABLE_BLOCK_PLUGINS) or install a plugin that registers one"
        )
    name = profile.get("projector.driver", "") if profile is not None else ""
    if name and name not in regs:
        raise UserError(
            f"[projector] driver = {name!r}: no such projector; available: "
            f"{', '.join(sorted(regs))}"
        )
    reg = regs[name or sorted(regs)[0]]
    launch = reg.factory(profile, socket_path=socket_path, headless=headless, extra=list(extra))
    if not isinstance(launch, ProjectorLaunch) or not launch.argv:
        raise UserError(
            f"projector {reg.name!r} (plugin {reg.plugin}): gave no command to start it"
        )
    return launch


class ProjectorService:
    """What the console uses: the supervised projector plus the active scene."""

    def __init__(
        self,
        *,
        socket_path: Path | str,
        command: list[str] | None,
        scenes: dict[str, Callable[[Any], Any]],
        profile: Any = None,
        providers: dict[str, Callable[[Any], Any]] | None = None,
        heartbeat_s: float = HEARTBEAT_S,
        peer_timeout_s: float = PEER_TIMEOUT_S,
        backoff_max_s: float = 5.0,
        log_path: Path | str | None = None,
        env: dict[str, str] | None = None,
        require_tick: bool = False,
    ) -> None:
        self.socket_path = Path(socket_path)
        self.scenes = dict(scenes)
        self.profile = profile
        self.providers = dict(providers or {})
        self.link = ProjectorLink(
            self.socket_path,
            heartbeat_s=heartbeat_s,
            peer_timeout_s=peer_timeout_s,
            require_tick=require_tick,
        )
        self.supervisor = (
            ProjectorSupervisor(
                command,
                self.socket_path,
                self.link,
                backoff_max_s=backoff_max_s,
                log_path=log_path,
                env=env,
            )
            if command
            else None
        )
        self.scene: Any = None
        self.scene_name: str | None = None
        self.prepared: dict = {}
        self.unprepared: list[str] = []
        self.unprepared_why: dict[str, str] = {}
        self._lock = threading.RLock()  # the UI and the frame loop may both send events

    @classmethod
    def from_profile(
        cls,
        profile: Any,
        plugins: Any,
        *,
        headless: bool = False,
        providers: dict[str, Callable[[Any], Any]] | None = None,
        log_path: Path | str | None = None,
        extra_args: Iterable[str] = (),
        require_tick: bool = False,
    ) -> ProjectorService:
        """Settings from the profile's [projector] section, scenes from the plugins.

        The projector's output goes to ``projector.log`` beside the socket unless
        ``log_path`` says otherwise."""
        sock = socket_path_for(profile)
        launch = projector_launch(profile, plugins, sock, headless=headless, extra=extra_args)

        def get(key: str, default: Any) -> Any:
            return profile.get(f"projector.{key}", default) if profile is not None else default

        return cls(
            socket_path=sock,
            command=list(launch.argv),
            env=launch.environment(),
            scenes={name: reg.factory for name, reg in plugins.of("scene").items()},
            profile=profile,
            providers=providers,
            heartbeat_s=get("heartbeat_s", HEARTBEAT_S),
            peer_timeout_s=get("peer_timeout_s", PEER_TIMEOUT_S),
            backoff_max_s=get("restart_backoff_max_s", 5.0),
            log_path=log_path or sock.parent / "projector.log",
            require_tick=require_tick,
        )

    def start(self) -> None:
        """Start (or adopt) the projector and connect; showing black until a scene starts."""
        if self.supervisor is not None:
            self.supervisor.start()
        self.link.start()

    def start_scene(self, name: str, events: Iterable[dict] = ()) -> dict:
        """Make ``name`` the active scene: prepare what it needs, apply ``events``, show it."""
        if name not in self.scenes:
            raise UserError(
                f"no scene named {name!r}; available: {', '.join(sorted(self.scenes)) or 'none'}"
            )
        scene = self.scenes[name](self.profile)  # a console.core.contracts.Scene
        why: dict[str, str] = {}
        prepared, missing = prepare_needs(scene.needs or {}, self.providers, why)
        _tell_points(scene, prepared)
        for ev in events:
            scene.update(ev)
        with self._lock:
            self.scene, self.scene_name = scene, name
            self.prepared, self.unprepared, self.unprepared_why = prepared, missing, why
            return self._push()

    def prepare_again(self) -> list[str]:
        """Retry the active scene's unprepared needs (e.g. once a vibration map is
        loaded); returns the kinds still not prepared."""
        with self._lock:
            scene, todo = self.scene, list(self.unprepared)
        if scene is None or not todo:
            return todo
        needs = scene.needs or {}
        why: dict[str, str] = {}
        prepared, missing = prepare_needs({k: needs.get(k) for k in todo}, self.providers, why)
        with self._lock:
            if self.scene is scene:
                _tell_points(scene, prepared)
                self.prepared.update(prepared)
                self.unprepared, self.unprepared_why = missing, why
            return list(self.unprepared)

    def update(self, event: dict) -> dict:
        """Pass an event to the active scene and show its new state."""
        with self._lock:
            if self.scene is None:
                raise UserError("no active scene: start one first (start_scene)")
            self.scene.update(event)
            return self._push()

    def stop_scene(self) -> None:
        """Show black."""
        with self._lock:
            self.scene, self.scene_name, self.prepared, self.unprepared = None, None, {}, []
            self.unprepared_why = {}
            self.link.send_state("black", {"kind": "black"})

    def _push(self) -> dict:
        state = self.scene.state()
        self.link.send_state(self.scene_name, state)
        return state

    def wait_connected(self, timeout_s: float = 10.0) -> bool:
        """Wait until the projector has answered (started or adopted, then connected)."""
        return self.link.wait_connected(timeout_s)

    def tick(self) -> None:
        """Call from the console's main loop (e.g. a Textual interval) when built with
        ``require_tick=True``: if the loop stops, the projector turns black."""
        self.link.tick()

    def wait_drawn(self, timeout_s: float = 5.0) -> bool:
        """Wait until the projector shows the newest state."""
        return self.link.wait_drawn(None, timeout_s)

    def snapshot(self, path: str | Path, timeout_s: float = 10.0) -> bool:
        """Save what the projector shows now as a PNG (for diagnosis and tests)."""
        return self.link.snapshot(path, timeout_s)

    def status(self) -> dict:
        st = {
            "scene": self.scene_name,
            "unprepared_needs": self.unprepared,
            "unprepared_why": dict(self.unprepared_why),
            **self.link.status(),
        }
        if self.supervisor is not None:
            st.update(self.supervisor.status())
        return st

    def close(self, stop_projector: bool = True) -> None:
        """Stop the projector (default) or leave it running for the next console."""
        self.link.closing = True
        if stop_projector and self.supervisor is not None:
            self.supervisor.stop()
        elif self.supervisor is not None:
            self.supervisor.detach()
        self.link.close()
