"""The demo lifecycle: a registered demo run in its own process on the console's table,
camera and projector.

``DemoControl.start(name)`` hands the camera over (it opens once), starts the
``DemoProcess`` on the console's table (a client of the same outputs kernel), waits for
it to run (``progress``/``cancelled`` follow its preparation) and forwards its scene
events to the projector; ``stop()`` stops it, shows black if it showed its scene and
takes the camera back. It reports events with topic ``demo``: ``Started`` (``detail``:
starting, running, stopping), ``Progress`` while it prepares, ``Snapshot`` (``poll()``),
``Stopped`` (``reason``: stopped, cancelled, e-stopped, an error ...) and ``Failed``. Blocking calls run on the caller's thread: screens call them from workers.

From its start to its end a demo holds the profile's table for other processes
(``console.runtime.table_hold``): a shell's study run, demo or long play is refused
naming it, as the console's plays are refused while one of theirs runs.
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from console.core.errors import UserError
from console.kernel.private_dir import runtime_dir
from console.runtime.demo_process import DemoCancelled, DemoProcess
from console.runtime.table_hold import table_held
from console.session.demo_history import RunHistory
from console.session.events import Progress, Snapshot, Started, Stopped

_ISSUED: set[Path] = set()  # the paths given to runs of this console


def twin_log_path(name: str) -> Path:
    """Where a demo process writes what the twin's outputs received (``.json`` bursts and
    relay switches, ``.npz`` samples: ``console.runtime.twin_log``): the private runtime
    directory, one file per run named by its start time (none is overwritten)."""
    stamp = time.strftime("%Y%m%d-%H%M%S")
    for n in range(1000):  # two starts in one second: the second gets -2 ...
        p = runtime_dir() / f"demo-{os.getpid()}-{name}-{stamp}{f'-{n + 1}' if n else ''}.json"
        if p not in _ISSUED and not p.exists() and not p.with_suffix(".npz").exists():
            _ISSUED.add(p)  # (its run writes it when it ends)
            return p
    raise UserError(f"{runtime_dir()}: 1000 demo logs of {name} this second; remove some")


class ProjectorForward:
    """The demo's scene events, forwarded to the console's projector service once the
    demo's scene is shown there (events before that are applied when it starts)."""

    def __init__(self, service: Any) -> None:
        self.service = service
        self.ready = False
        self.pending: list[dict] = []
        self._lock = threading.Lock()

    def update(self, event: dict) -> dict:
        with self._lock:
            if not self.ready:
                self.pending = [*self.pending[-199:], event]
                return {}
        return self.service.update(event)

    def start(self, scene: str) -> None:
        with self._lock:
            first, self.pending = self.pending, []
        self.service.start_scene(scene, first)
        with self._lock:
            for ev in self.pending:
                self.service.update(ev)
            self.pending, self.ready = [], True


class DemoControl:
    """The one demo ``session`` runs at a time: ``name`` (running or being prepared),
    ``state`` (idle, starting, running, stopping, or how the last run ended) and ``run``
    (the ``DemoProcess`` while it lives)."""

    #: extra ``factory(...)`` arguments per demo name (e.g. ``{"flow": {"prepare": False}}``)
    params: dict[str, dict]

    def __init__(self, session: Any) -> None:
        self.session = session
        self.params = {}
        self.run: Any = None
        self.name: str | None = None
        self.state = "idle"
        self.last_snapshot: dict | None = None
        self.last_final: dict | None = None  # the last run's "stopped" message
        self.history = RunHistory()  # its latency per poll, and when it ended
        self.estop_after = ""  # an e-stop that came while the last run stopped (its reason)
        self._forward: ProjectorForward | None = None
        self._lock = threading.Lock()
        self._stop_lock = threading.Lock()
        self._stopping: Any = None  # the run a stop is under way for
        self._table = contextlib.ExitStack()  # the table held for other processes

    # ------------------------------------------------------------------ start
    def check_start(self, name: str) -> None:
        """Refuse a start now (one line): an unknown demo, one already running, outputs
        not open or e-stopped."""
        s = self.session
        if name not in s.plugins.of("demo"):
            raise UserError(f"no demo named {name!r}")
        if self.name is not None:
            raise UserError(f"demo {self.name} is running: s stops it")
        out = s.outputs
        if out is None:
            raise UserError(f"demo {name}: outputs not open ({s.outputs_error or 'starting'})")
        if out.estopped:
            raise UserError(f"demo {name}: the e-stop is active; ctrl+r resets it")
        held = s.held_why()
        if held:  # a study run holds the table (this console's, or a shell's)
            raise UserError(f"demo {name}: {held}")

    def start(
        self,
        name: str,
        progress: Callable[[float, str], None] | None = None,
        cancelled: Callable[[], bool] | None = None,
    ) -> Any:
        """Start demo ``name`` and wait until it runs (blocking); returns its process.
        A refusal or failure raises (``UserError``, ``DemoCancelled``) after outputs and
        camera were taken back, and is reported as ``Stopped``."""
        s = self.session
        with self._lock:
            self.check_start(name)
            who = f"the {name} demo (the console's, pid {os.getpid()})"
            # a shell's command that took the table since the check: TableBusy names it
            self._table.enter_context(table_held(s.profile, who, "s on Scenes (F6) stops it"))
            self.name, self.state = name, "starting"
            self.last_snapshot = self.last_final = None  # this run's, not the last one's
            self.history.begin(name)
            self.estop_after = ""
        s.emit(Started("demo", name, detail="starting"))

        def step(frac: float, text: str) -> None:
            s.emit(Progress("demo", name, fraction=frac, text=text))
            if progress is not None:
                progress(frac, text)

        cancelled = cancelled or (lambda: False)
        params = dict(self.params.get(name, {}))
        run = None
        try:
            step(0.0, "handing over the camera")
            camera = s.camera
            vision, controls = camera.vision_params(), camera.control_values()
            if vision:
                params.setdefault("vision", vision)  # the Camera screen's tuned thresholds
            if controls:
                params.setdefault("camera_controls", controls)  # its exposure and gain
            out = s.outputs
            try:
                camera.release(f"demo {name}")
                if cancelled():
                    raise DemoCancelled(name)
                projector = s.scenes.service
                fwd = ProjectorForward(projector) if projector is not None else None
                run = DemoProcess(
                    s.table_profile,  # the outputs' settings: the table is shared
                    name,
                    params=params,
                    on_scene=fwd.update if fwd is not None else None,
                    twin_log=twin_log_path(name),
                    plugins=s.plugins,
                    table_dir=out.table.dir,
                    fast=out.fast,
                )
                self.run, self._forward = run, fwd
                run.wait_started(step, cancelled)
            except BaseException:
                if run is not None:
                    run.stop("cancelled")
                    # numbers only from a run that came up (a start cut short has none)
                    came_up = run.scene_name is not None
                    self.last_snapshot = run.snapshot() if came_up else None
                    self.last_final = run.final
                self.run = None
                self._take_back(run)
                raise
        except BaseException as exc:
            cancel = cancelled() or isinstance(exc, DemoCancelled)
            self._ended(name, "cancelled" if cancel else "failed")  # the caller says why
            raise
        if fwd is not None:
            try:
                fwd.start(run.scene_name)
            except (UserError, OSError) as exc:
                s.fail("projector", f"projector: {exc}", severity="warning")
        if cancelled():  # cancelled while it came up: it does not run on
            self.stop("cancelled")
            raise DemoCancelled(name)
        self.state = "running"
        s.emit(Started("demo", name, detail="running"))
        return run

    # ------------------------------------------------------------------ stop
    def stop(self, reason: str = "stopped", now: bool = False) -> str:
        """Stop the running demo (blocking): the process lets the playing plan end
        (``now``: ramps it down at once), leaves the table and exits; black on the
        projector if it showed its scene; the camera taken back. Returns how it ended
        (``Stopped`` says so too)."""
        with self._lock:
            run, name = self.run, self.name
            if run is None or name is None or self._stopping is run:
                return self.state  # nothing runs, or its stop is under way
            self._stopping, self.state = run, "stopping"
        self.session.emit(Started("demo", name, detail="stopping"))
        try:
            self._stop_run(run, now)
        except Exception as exc:  # noqa: BLE001 - one line, the console stays up
            reason = f"stop failed: {exc}"
        reason = self._how_it_ended(run, reason)
        self._ended(name, reason)
        return reason

    def _how_it_ended(self, run: Any, reason: str) -> str:
        """The stop's ``reason``, unless the run ended otherwise first (an error, its
        watchdog ...); an e-stop that came while it stopped is ``estop_after``."""
        ended = run.exit_reason
        if not ended or ended in ("stopped", reason):
            return reason
        if ended == "e-stopped" and reason != "e-stopped" and not run.error:
            self.estop_after = run.estop_reason or "e-stop"  # the stop was asked first
            return reason
        return ended

    def estop(self, reason: str) -> None:
        """The e-stop: the demo process is told at once (the table's kernel silenced its
        outputs already; ``stop`` then ends it)."""
        run = self.run
        if run is not None:
            run.estop(reason)

    def _stop_run(self, run: Any, now: bool = False) -> None:
        with self._stop_lock:
            try:
                if now:
                    run.stop(now=True)
                else:
                    run.stop()
                self.last_snapshot = run.snapshot()
                self.last_final = run.final
            finally:
                fwd, self._forward = self._forward, None
                if fwd is not None and fwd.ready:
                    with contextlib.suppress(Exception):
                        if fwd.service.status().get("scene") == run.scene_name:
                            fwd.service.stop_scene()
                self._take_back(run)

    def _take_back(self, run: Any) -> None:
        """The demo process has ended: the console's camera again."""
        self.session.camera.give_back()

    def _ended(self, name: str, reason: str) -> None:
        self.history.end()
        with self._lock:
            self.run, self.name, self.state = None, None, reason
            self._table.close()  # other processes may play again
        self.session.emit(Stopped("demo", name, reason=reason))

    # ------------------------------------------------------------------ state
    @property
    def running(self) -> Any:
        """The running demo process (None while none runs or it is still preparing)."""
        run = self.run
        if run is None or self.state not in ("running", "stopping") or run.stopped:
            return None
        return run

    def poll(self) -> dict | None:
        """The running demo's newest snapshot, reported as ``Snapshot`` (None: none
        runs). Never blocks: a demo that ended by itself is stopped on a thread
        (``Stopped`` says why)."""
        run, name = self.run, self.name
        if run is None or name is None or self.state == "starting":
            return None  # (a starting demo has no numbers yet: its Progress says how far)
        try:
            snap = run.snapshot()
        except Exception as exc:  # noqa: BLE001 - shown, never raised
            snap = {"demo": name, "last_error": f"snapshot failed: {exc}"}
        self.last_snapshot = snap
        self.history.add(snap)
        self.session.emit(Snapshot("demo", name, data=snap))
        if run.stopped and self.state == "running":  # it ended by itself: tidy up
            self.state = "stopping"
            threading.Thread(
                target=self.stop,
                args=(run.exit_reason or "ended",),
                name="haptable-demo-ended",
                daemon=True,
            ).start()
        return snap

    def scene_feed(self) -> dict | None:
        """What the running demo sends to the projector: ``demo`` (its name), ``scene``
        (the scene it drives), ``sent`` (its scene events reach the console's
        projector: the projector ran when it started and its scene shows there) and
        ``state`` (``running`` or ``stopping``: it sends until it ends); None
        while no demo runs. A screen's projector line derives from this whether the
        scene's live input comes."""
        run, fwd, name = self.running, self._forward, self.name
        if run is None or name is None:
            return None
        sent = fwd is not None and fwd.ready
        return {"demo": name, "scene": run.scene_name, "sent": sent, "state": self.state}

    def projecting(self) -> str | None:
        """The demo whose scene the projector shows or will show (it started with the
        projector running: its events go there until it ends), else None."""
        name, fwd = self.name, self._forward
        return name if name is not None and fwd is not None else None

    def set_target(self, pos_mm: tuple[float, float] | None) -> bool:
        """The operator's finger on the twin the running demo watches (None lifts it);
        False when the demo's camera cannot be touched."""
        cam = self.touchable()
        if cam is None:
            return False
        cam.set_target(pos_mm)
        return True

    def touchable(self) -> Any:
        """The running demo's camera when the operator can touch the twin with it."""
        run = self.run
        if run is None or self.state != "running":
            return None
        return run.camera

    def close(self) -> None:
        """Quitting: stop the demo (blocking) before the session closes the outputs; what
        it plays ramps down at once (not played to its end: the operator waits)."""
        if self.run is not None:
            self.stop("stopped", now=True)
